#include "procedures/staged_run.hpp"

#include "base/errors.hpp"
#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "io/particle_file.hpp"
#include "io/vtk.hpp"
#include "procedures/checkpointed_cycling.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <omp.h>

namespace centridem {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

World build_world(const Scenario& sc) {
  World world(sc.simulation.world);
  world.particles_mut().reserve(sc.particles.records.size());
  for (const ParticleRecord& r : sc.particles.records)
    world.add_particle(r.position, r.radius, sc.particles.density_kg_m3, sc.particles.group);
  world.set_ball_ball_defaults(sc.ball_ball);
  for (const WallSpec& w : sc.walls) world.add_wall(w.make(), w.contact);
  world.set_body_field(sc.gravity.field());
  return world;
}

namespace {

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

std::string duration(double s) {
  if (!std::isfinite(s)) return "?";
  if (s < 60) return fmt::format("{:.0f} s", std::max(s, 0.0));
  if (s < 3600)
    return fmt::format("{} min {:02d} s", static_cast<int>(s / 60), static_cast<int>(s) % 60);
  return fmt::format("{} h {:02d} min", static_cast<int>(s / 3600), static_cast<int>(s / 60) % 60);
}

std::string describe(const ContactProperties& c) {
  std::string s(to_string(c.model));
  if (c.stiffness_method == StiffnessMethod::deformability)
    s += fmt::format(" E*={:g} Pa kratio={:g}", c.effective_modulus_Pa, c.stiffness_ratio);
  else
    s += fmt::format(" kn={:g} N/m ks={:g} N/m", c.normal_stiffness_N_per_m,
                     c.shear_stiffness_N_per_m);
  s += fmt::format(" fric={:g}", c.friction);
  if (c.model != ContactModel::linear) s += fmt::format(" rr_fric={:g}", c.rolling_friction);
  if (c.model == ContactModel::arrlinear)
    s += fmt::format(" F0={:g} N D0={:g} m", c.attraction_force_N, c.attraction_range_m);
  if (c.dashpot_normal_ratio > 0 || c.dashpot_shear_ratio > 0)
    s += fmt::format(" dp_nratio={:g} dp_sratio={:g} dp_mode={}", c.dashpot_normal_ratio,
                     c.dashpot_shear_ratio, c.dashpot_mode);
  return s;
}

std::string describe(const GravitySpec& g) {
  const Vec3 a = g.field().gravity_m_s2;
  std::string s = fmt::format("[{:.6g}, {:.6g}, {:.6g}] m/s^2", a.x, a.y, a.z);
  if (g.form == GravitySpec::Form::scaled)
    s += fmt::format(" ({:g} g / {:g})", g.g_level, g.size_reduction_factor);
  return s;
}

std::string describe_end(const StageSpec& s) {
  switch (s.end) {
  case StageEnd::steps:
    return fmt::format("{} steps", s.steps);
  case StageEnd::time:
    return fmt::format("{:g} s", s.time_s);
  case StageEnd::equilibrium:
    return fmt::format("until ratio < {:g} (max {} steps)", s.equilibrium_ratio,
                       s.equilibrium_max_steps);
  }
  return "?";
}

std::string path_in(const std::string& dir, const std::string& name) {
  return (fs::path(dir) / name).string();
}

// measurements.csv: one row per measurement, across stages. A resumed run
// cuts the file back to the length its checkpoint recorded (the rows written
// after it are written again) and appends.
class MeasurementTable {
public:
  MeasurementTable(const std::string& path, std::vector<std::string> walls)
      : walls_(std::move(walls)) {
    f_ = std::fopen(path.c_str(), "w");
    if (!f_) throw std::runtime_error("cannot write " + path);
    std::string h = "step,time_s,stage,ratio,kinetic_energy_J,coordination_number,contacts,"
                    "ball_wall_contacts,particles,timestep_s,max_overlap_ratio";
    for (const std::string& w : walls_)
      h += fmt::format(",{0}_force_x_N,{0}_force_y_N,{0}_force_z_N", w);
    put(h + "\n");
  }
  // The table as a checkpoint left it: `bytes` long, its last row at `last_step`.
  MeasurementTable(const std::string& path, std::vector<std::string> walls, std::uintmax_t bytes,
                   long last_step)
      : walls_(std::move(walls)), last_step_(last_step) {
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec || size < bytes)
      throw InputError("--resume", path,
                       fmt::format("measurements.csv holds {} bytes, fewer than the {} its "
                                   "checkpoint recorded: the run folder was changed",
                                   ec ? 0 : size, bytes));
    fs::resize_file(path, bytes, ec);
    if (ec) throw std::runtime_error("cannot shorten " + path + ": " + ec.message());
    f_ = std::fopen(path.c_str(), "a");
    if (!f_) throw std::runtime_error("cannot write " + path);
    bytes_ = bytes;
  }
  ~MeasurementTable() {
    if (f_) std::fclose(f_);
  }
  MeasurementTable(const MeasurementTable&) = delete;
  MeasurementTable& operator=(const MeasurementTable&) = delete;

  void row(const World& world, const Measurements& m, const std::string& stage) {
    if (m.step == last_step_) return;
    last_step_ = m.step;
    std::string r = fmt::format("{},{:.9e},{},{:.6e},{:.6e},{:.6f},{},{},{},{:.6e},{:.6e}", m.step,
                                m.time_s, stage, m.mean_unbalanced_force_ratio, m.kinetic_energy_J,
                                m.coordination_number, m.ball_ball_contacts, m.ball_wall_contacts,
                                m.particles, m.timestep_s, m.max_overlap_ratio);
    for (const std::string& name : walls_) {
      const auto& ws = world.walls();
      auto it = std::find_if(ws.begin(), ws.end(), [&](const Wall& w) { return w.name == name; });
      if (it == ws.end())
        r += ",,,"; // removed
      else
        r += fmt::format(",{:.6e},{:.6e},{:.6e}", it->force.x, it->force.y, it->force.z);
    }
    put(r + "\n");
  }
  std::uintmax_t bytes() const { return bytes_; }
  long last_step() const { return last_step_; }

private:
  void put(const std::string& text) {
    std::fwrite(text.data(), 1, text.size(), f_);
    std::fflush(f_);
    bytes_ += text.size();
  }
  std::vector<std::string> walls_;
  std::FILE* f_ = nullptr;
  std::uintmax_t bytes_ = 0;
  long last_step_ = -1;
};

// ParaView frames and their three series files (particles, contact force
// chains, walls). One frame per step: a frame
// written at the same step as the last one (a stage that starts by removing
// particles) replaces it.
class FrameWriter {
public:
  explicit FrameWriter(std::string dir)
      : dir_(std::move(dir)), particles_(path_in(dir_, "particles.pvd")),
        contacts_(path_in(dir_, "contacts.pvd")), walls_(path_in(dir_, "walls.pvd")) {}

  void write(const World& world) {
    if (!made_) make_directories(path_in(dir_, "frames")), made_ = true;
    const bool same = world.step_count() == last_step_;
    const std::size_t k = same ? next_ - 1 : next_;
    const std::string pf = fmt::format("frames/particles_{:06d}.vtu", k);
    const std::string cf = fmt::format("frames/contacts_{:06d}.vtp", k);
    const std::string wf = fmt::format("frames/walls_{:06d}.vtp", k);
    write_particles_vtu(world, path_in(dir_, pf));
    write_contacts_vtp(world, path_in(dir_, cf));
    if (!world.walls().empty()) write_walls_vtp(world, path_in(dir_, wf));
    if (!same) {
      particles_.add(world.time(), pf);
      contacts_.add(world.time(), cf);
      if (!world.walls().empty()) walls_.add(world.time(), wf);
      ++next_;
      last_step_ = world.step_count();
    }
  }
  std::size_t count() const { return next_; }

  // For the checkpoint: the series so far.
  nlohmann::json save() const {
    return {{"next", next_},
            {"last_step", last_step_},
            {"made", made_},
            {"particles", particles_.entries()},
            {"contacts", contacts_.entries()},
            {"walls", walls_.entries()}};
  }
  // The series as the checkpoint left them; frames a stopped process wrote
  // after it are removed (this run writes them again).
  void restore(const nlohmann::json& j) {
    next_ = j.at("next").get<std::size_t>();
    last_step_ = j.at("last_step").get<long>();
    made_ = j.at("made").get<bool>();
    using Entries = std::vector<std::pair<double, std::string>>;
    auto p = j.at("particles").get<Entries>();
    auto c = j.at("contacts").get<Entries>();
    auto w = j.contains("walls") ? j.at("walls").get<Entries>() : Entries{}; // older checkpoints
    std::error_code ec;
    if (p.empty())
      fs::remove(particles_.path(), ec);
    else
      particles_.assign(std::move(p));
    if (c.empty())
      fs::remove(contacts_.path(), ec);
    else
      contacts_.assign(std::move(c));
    if (w.empty())
      fs::remove(walls_.path(), ec);
    else
      walls_.assign(std::move(w));
    for (const auto& e : fs::directory_iterator(fs::path(dir_) / "frames", ec)) {
      const std::string n = e.path().filename().string();
      std::size_t k = 0;
      if (std::sscanf(n.c_str(), "particles_%zu.vtu", &k) == 1 ||
          std::sscanf(n.c_str(), "contacts_%zu.vtp", &k) == 1 ||
          std::sscanf(n.c_str(), "walls_%zu.vtp", &k) == 1)
        if (k >= next_) fs::remove(e.path(), ec);
    }
  }

private:
  std::string dir_;
  PvdSeries particles_, contacts_, walls_;
  bool made_ = false;
  std::size_t next_ = 0;
  long last_step_ = -1;
};

std::vector<WallReading> read_walls(const World& world) {
  std::vector<WallReading> out;
  for (const Wall& w : world.walls()) out.push_back({w.name, w.force, w.contact_count});
  return out;
}

nlohmann::ordered_json to_json(const Vec3& v) {
  return {v.x, v.y, v.z};
}

nlohmann::ordered_json to_json(const StageReport& r, const StageSpec& spec, std::size_t index) {
  nlohmann::ordered_json j;
  j["index"] = index;
  j["name"] = r.name;
  j["end"] = std::string(to_string(r.end));
  switch (spec.end) {
  case StageEnd::steps:
    j["target"] = {{"steps", spec.steps}};
    break;
  case StageEnd::time:
    j["target"] = {{"time_s", spec.time_s}};
    break;
  case StageEnd::equilibrium:
    j["target"] = {{"ratio", spec.equilibrium_ratio},
                   {"max_steps", spec.equilibrium_max_steps},
                   {"check_interval", spec.equilibrium_check_interval}};
    j["reached_equilibrium"] = r.reached_equilibrium;
    break;
  }
  j["first_step"] = r.first_step;
  j["steps"] = r.steps;
  j["start_time_s"] = r.start_time_s;
  j["time_s"] = r.time_s;
  j["end_time_s"] = r.start_time_s + r.time_s;
  j["particles_removed"] = r.particles_removed;
  j["contacts_modified"] = r.contacts_modified;
  const Measurements& m = r.end_state;
  nlohmann::ordered_json mj;
  mj["particles"] = m.particles;
  mj["coordination_number"] = m.coordination_number;
  mj["mean_unbalanced_force_ratio"] = m.mean_unbalanced_force_ratio;
  mj["kinetic_energy_J"] = m.kinetic_energy_J;
  mj["ball_ball_contacts"] = m.ball_ball_contacts;
  mj["ball_wall_contacts"] = m.ball_wall_contacts;
  mj["max_overlap_ratio"] = m.max_overlap_ratio;
  mj["timestep_s"] = m.timestep_s;
  nlohmann::ordered_json wj = nlohmann::ordered_json::object();
  for (const WallReading& w : r.walls)
    wj[w.name] = {{"force_N", to_json(w.force_N)}, {"contacts", w.contacts}};
  mj["walls"] = wj;
  j["measurements"] = mj;
  j["wall_time_s"] = r.wall_time_s;
  j["particle_steps_per_s"] = r.particle_steps_per_s;
  j["particles_file"] = r.particles_file;
  j["frames"] = r.frames;
  return j;
}

class Summary {
public:
  Summary(std::string path, const Scenario& sc, int threads) : path_(std::move(path)), sc_(sc) {
    head_["scenario"] = sc.source_path;
    head_["description"] = sc.description;
    head_["threads"] = threads;
    head_["particles_at_start"] = sc.particles.records.size();
  }
  void write(const RunReport& r, const std::string& status, const std::string& error) const {
    nlohmann::ordered_json j = head_;
    j["output_dir"] = r.output_dir;
    j["status"] = status;
    if (!error.empty()) j["error"] = error;
    j["wall_time_s"] = r.wall_time_s;
    nlohmann::ordered_json stages = nlohmann::ordered_json::array();
    for (std::size_t k = 0; k < r.stages.size(); ++k)
      stages.push_back(to_json(r.stages[k], sc_.stages[k], k));
    j["stages"] = stages;
    replace_text_file(path_, j.dump(2) + "\n");
  }

private:
  std::string path_;
  const Scenario& sc_;
  nlohmann::ordered_json head_;
};

void echo(RunLog& log, const Scenario& sc, const World& world, int threads) {
  log.info(fmt::format("centridem run {}{}", sc.source_path,
                       sc.description.empty() ? "" : " - " + sc.description));
  const auto& r = world.particles().radius;
  const auto [rmin, rmax] = std::minmax_element(r.begin(), r.end());
  log.info(fmt::format("  particles  {} from {} (density {:g} kg/m^3, radii {:.4g}-{:.4g} m)",
                       world.particles().size(), sc.particles.file, sc.particles.density_kg_m3,
                       r.empty() ? 0.0 : *rmin, r.empty() ? 0.0 : *rmax));
  log.info("  ball-ball  " + describe(sc.ball_ball));
  for (const WallSpec& w : sc.walls)
    log.info(fmt::format("  wall       {} ({}): {}", w.name,
                         w.shape == WallShape::plane ? "plane" : "rectangle", describe(w.contact)));
  log.info("  gravity    " + describe(sc.gravity));
  const WorldSettings& s = sc.simulation.world;
  log.info(fmt::format("  timestep   {}; local damping {:g}; threads {}",
                       s.timestep_s > 0
                           ? fmt::format("{:g} s (fixed)", s.timestep_s)
                           : fmt::format("auto (safety factor {:g})", s.timestep_safety_factor),
                       s.local_damping, threads));
  for (std::size_t k = 0; k < sc.stages.size(); ++k) {
    const StageSpec& st = sc.stages[k];
    std::string out = fmt::format("  stage {}    {}: {}", k, st.name, describe_end(st));
    if (st.frames_every > 0) out += fmt::format(", frames every {} steps", st.frames_every);
    log.info(out);
  }
  log.info(fmt::format("  output     {} (resolved scenario: scenario.resolved.toml)",
                       sc.simulation.output_dir));
}

void warn_wall_overlaps(RunLog& log, const World& world) {
  const ParticleStore& p = world.particles();
  for (const Wall& w : world.walls()) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (wall_proximity(w, p.position[i]).distance < p.radius[i]) ++n;
    if (n > 0)
      log.warn(fmt::format("{} particles overlap wall \"{}\" at the start (or lie behind it)", n,
                           w.name));
  }
}

// Removes what an earlier run into the same folder left and this one would
// not overwrite (frames beyond this run's last, stage files of other names):
// only files with the names a run writes.
void remove_previous_outputs(const std::string& dir) {
  std::error_code ec;
  auto starts = [](const std::string& s, const char* p) { return s.rfind(p, 0) == 0; };
  auto ends = [](const std::string& s, const std::string& e) {
    return s.size() >= e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0;
  };
  for (const char* f : {"particles.pvd", "contacts.pvd", "walls.pvd", "final_state.csv"})
    fs::remove(fs::path(dir) / f, ec);
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string n = e.path().filename().string();
    if (starts(n, "stage_") && ends(n, "_particles.txt")) fs::remove(e.path(), ec);
  }
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "frames", ec)) {
    const std::string n = e.path().filename().string();
    if ((starts(n, "particles_") && ends(n, ".vtu")) ||
        ((starts(n, "contacts_") || starts(n, "walls_")) && ends(n, ".vtp")))
      fs::remove(e.path(), ec);
  }
}

} // namespace

StageChanges apply_stage_changes(World& world, const StageSpec& st, const std::string& path) {
  StageChanges out;
  for (const std::string& name : st.remove_walls) world.remove_wall(name);
  if (st.remove_particles) {
    const ParticleStore& p = world.particles();
    const Box box = st.remove_particles->box;
    const bool outside = st.remove_particles->outside;
    out.particles_removed = world.remove_particles(
        [&](std::size_t i) { return box.contains(p.position[i]) != outside; });
  }
  for (const WallChange& c : st.walls) {
    const std::size_t k = world.wall_index(c.name);
    if (c.velocity) world.set_wall_velocity(k, *c.velocity);
    if (c.contact) world.set_wall_defaults(k, *c.contact);
  }
  if (st.gravity) world.set_body_field(st.gravity->field());
  if (st.ball_ball) world.set_ball_ball_defaults(*st.ball_ball);
  if (st.modify_contacts) {
    const ParticleStore& p = world.particles();
    const std::optional<Box> region = st.modify_contacts->region;
    const ContactPatch& set = st.modify_contacts->set;
    const std::string key = path + ".modify_contacts.set";
    out.contacts_modified = world.modify_ball_ball_contacts(
        [&](std::size_t i, std::size_t j) {
          return !region || (region->contains(p.position[i]) && region->contains(p.position[j]));
        },
        [&](ContactProperties& c) {
          c = apply(set, c);
          validate(c, key);
        });
  }
  if (st.local_damping) world.set_local_damping(*st.local_damping);
  if (st.reset_displacements) world.reset_displacements();
  return out;
}

namespace {

// What a stage changed, for the log.
void log_changes(RunLog& log, const World& world, const StageSpec& st, const StageChanges& c) {
  for (const std::string& name : st.remove_walls) log.info("  removed wall " + name);
  if (st.remove_particles) {
    const Box& b = st.remove_particles->box;
    log.info(fmt::format("  removed {} particles {} the box [{:g}, {:g}, {:g}]-[{:g}, {:g}, {:g}] "
                         "m; {} left",
                         c.particles_removed, st.remove_particles->outside ? "outside" : "inside",
                         b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z, world.particles().size()));
  }
  for (const WallChange& w : st.walls) {
    if (w.velocity)
      log.info(fmt::format("  wall {} velocity [{:g}, {:g}, {:g}] m/s", w.name, w.velocity->x,
                           w.velocity->y, w.velocity->z));
    if (w.contact)
      log.info(fmt::format("  new contacts with wall {}: {}", w.name, describe(*w.contact)));
  }
  if (st.gravity) log.info("  gravity " + describe(*st.gravity));
  if (st.ball_ball) log.info("  new ball-ball contacts: " + describe(*st.ball_ball));
  if (st.modify_contacts)
    log.info(fmt::format("  modified {} existing ball-ball contacts", c.contacts_modified));
  if (st.local_damping) log.info(fmt::format("  local damping {:g}", *st.local_damping));
  if (st.reset_displacements) log.info("  displacements reset to zero");
}

} // namespace

namespace {

constexpr const char* kCheckpointName = "checkpoint.bin";

// A double that JSON may hold as null (NaN, infinities).
double number_or_nan(const nlohmann::json& j) {
  return j.is_null() ? std::numeric_limits<double>::quiet_NaN() : j.get<double>();
}

nlohmann::json measurements_json(const Measurements& m) {
  return {{"step", m.step},
          {"time_s", m.time_s},
          {"timestep_s", m.timestep_s},
          {"particles", m.particles},
          {"ball_ball_contacts", m.ball_ball_contacts},
          {"ball_wall_contacts", m.ball_wall_contacts},
          {"coordination_number", m.coordination_number},
          {"mean_unbalanced_force_ratio", m.mean_unbalanced_force_ratio},
          {"kinetic_energy_J", m.kinetic_energy_J},
          {"max_overlap_ratio", m.max_overlap_ratio}};
}

Measurements measurements_from(const nlohmann::json& j) {
  Measurements m;
  m.step = j.at("step").get<long>();
  m.time_s = number_or_nan(j.at("time_s"));
  m.timestep_s = number_or_nan(j.at("timestep_s"));
  m.particles = j.at("particles").get<std::size_t>();
  m.ball_ball_contacts = j.at("ball_ball_contacts").get<std::size_t>();
  m.ball_wall_contacts = j.at("ball_wall_contacts").get<std::size_t>();
  m.coordination_number = number_or_nan(j.at("coordination_number"));
  m.mean_unbalanced_force_ratio = number_or_nan(j.at("mean_unbalanced_force_ratio"));
  m.kinetic_energy_J = number_or_nan(j.at("kinetic_energy_J"));
  m.max_overlap_ratio = number_or_nan(j.at("max_overlap_ratio"));
  return m;
}

nlohmann::json stage_report_json(const StageReport& r) {
  nlohmann::json walls = nlohmann::json::array();
  for (const WallReading& w : r.walls)
    walls.push_back({w.name, w.force_N.x, w.force_N.y, w.force_N.z, w.contacts});
  return {{"name", r.name},
          {"end", static_cast<int>(r.end)},
          {"first_step", r.first_step},
          {"steps", r.steps},
          {"start_time_s", r.start_time_s},
          {"time_s", r.time_s},
          {"reached_equilibrium", r.reached_equilibrium},
          {"particles_removed", r.particles_removed},
          {"contacts_modified", r.contacts_modified},
          {"end_state", measurements_json(r.end_state)},
          {"walls", walls},
          {"wall_time_s", r.wall_time_s},
          {"particle_steps_per_s", r.particle_steps_per_s},
          {"particles_file", r.particles_file},
          {"frames", r.frames}};
}

StageReport stage_report_from(const nlohmann::json& j) {
  StageReport r;
  r.name = j.at("name").get<std::string>();
  r.end = static_cast<StageEnd>(j.at("end").get<int>());
  r.first_step = j.at("first_step").get<long>();
  r.steps = j.at("steps").get<long>();
  r.start_time_s = j.at("start_time_s").get<double>();
  r.time_s = j.at("time_s").get<double>();
  r.reached_equilibrium = j.at("reached_equilibrium").get<bool>();
  r.particles_removed = j.at("particles_removed").get<std::size_t>();
  r.contacts_modified = j.at("contacts_modified").get<std::size_t>();
  r.end_state = measurements_from(j.at("end_state"));
  for (const auto& w : j.at("walls"))
    r.walls.push_back({w.at(0).get<std::string>(),
                       Vec3{number_or_nan(w.at(1)), number_or_nan(w.at(2)), number_or_nan(w.at(3))},
                       w.at(4).get<std::uint32_t>()});
  r.wall_time_s = number_or_nan(j.at("wall_time_s"));
  r.particle_steps_per_s = number_or_nan(j.at("particle_steps_per_s"));
  r.particles_file = j.at("particles_file").get<std::string>();
  r.frames = j.at("frames").get<std::size_t>();
  return r;
}

// Where a run is: kept in the checkpoint's procedure blob with the stages
// done, the frame series and the length of measurements.csv.
struct RunProgress {
  std::size_t stage = 0;    // the stage under way, or next to start
  bool in_stage = false;    // its changes are applied and it cycles
  long done = 0;            // steps into the stage
  long chunk = 0;           // its chunk length (from its particle count at the start)
  double n_particles = 0;   // particles at its start
  double cycle_seconds = 0; // wall seconds spent cycling in it
  std::size_t frames_before = 0;
  StageReport rep; // its report so far
};

// Removes the temporary files (written aside, then renamed) that a process
// killed while writing one left in the run folder.
void remove_temporaries(const std::string& dir) {
  std::error_code ec;
  for (const char* f : {"checkpoint.bin.tmp", "particles.pvd.tmp", "contacts.pvd.tmp",
                        "walls.pvd.tmp", "summary.json.tmp", "final_state.csv.tmp"})
    fs::remove(fs::path(dir) / f, ec);
}

Clock::time_point seconds_ago(double s) {
  return Clock::now() -
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// final_state.csv: the particles at the end, in their current order, every
// double exactly (17 significant digits).
void write_final_state(const World& world, const std::string& path) {
  const ParticleStore& P = world.particles();
  std::string st = "id,x_m,y_m,z_m,radius_m,vx_m_s,vy_m_s,vz_m_s,wx_rad_s,wy_rad_s,wz_rad_s,ux_m,"
                   "uy_m,uz_m\n";
  st.reserve(P.size() * 300);
  for (std::size_t i = 0; i < P.size(); ++i)
    st += fmt::format("{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},"
                      "{:.17g},{:.17g},{:.17g},{:.17g}\n",
                      P.id[i], P.position[i].x, P.position[i].y, P.position[i].z, P.radius[i],
                      P.velocity[i].x, P.velocity[i].y, P.velocity[i].z, P.spin[i].x, P.spin[i].y,
                      P.spin[i].z, P.displacement[i].x, P.displacement[i].y, P.displacement[i].z);
  replace_text_file(path, st);
}

RunReport run_staged(Scenario sc, const RunOptions& opt, bool resume) {
  auto run_start = Clock::now();
  if (opt.threads) {
    if (*opt.threads < 0)
      throw InputError("--threads", fmt::format("{}", *opt.threads),
                       "must be >= 0 (0 = the OpenMP default)");
    sc.simulation.world.threads = *opt.threads;
  }
  if (!opt.output_dir.empty()) sc.simulation.output_dir = opt.output_dir;
  const std::string dir = sc.simulation.output_dir;
  const std::string ckpt = path_in(dir, kCheckpointName);
  const int threads =
      sc.simulation.world.threads > 0 ? sc.simulation.world.threads : omp_get_max_threads();

  World world(sc.simulation.world);
  nlohmann::json saved; // the resumed checkpoint's progress record
  RunProgress pr;
  if (resume) {
    const LoadedCheckpoint lc = read_checkpoint(world, ckpt);
    try {
      saved = nlohmann::json::parse(lc.procedure_state);
      if (saved.at("format") != "centridem-run")
        throw InputError("--resume", ckpt, "not a checkpoint of `centridem run`");
      sc.source_path = saved.at("source_path").get<std::string>();
      pr.stage = saved.at("stage").get<std::size_t>();
      pr.in_stage = saved.at("in_stage").get<bool>();
      pr.done = saved.at("done").get<long>();
      pr.chunk = saved.at("chunk").get<long>();
      pr.n_particles = saved.at("n_particles").get<double>();
      pr.cycle_seconds = saved.at("cycle_seconds").get<double>();
      pr.frames_before = saved.at("frames_before").get<std::size_t>();
      pr.rep = stage_report_from(saved.at("rep"));
      run_start = seconds_ago(saved.at("run_seconds").get<double>());
    } catch (const nlohmann::json::exception& e) {
      throw InputError("--resume", ckpt,
                       fmt::format("the run's progress record is unreadable ({})", e.what()));
    }
    if (pr.stage > sc.stages.size())
      throw InputError("--resume", ckpt,
                       "the checkpoint does not belong to scenario.resolved.toml");
  } else {
    world = build_world(sc);
    // A fixed timestep above the critical one fails now, before any output.
    if (const double dt = sc.simulation.world.timestep_s; dt > 0 && world.particles().size() > 0) {
      const double crit = world.critical_timestep();
      if (dt > crit)
        throw InputError("simulation.timestep_s", fmt::format("{:.4g}", dt),
                         fmt::format("above the critical timestep {:.4g} s estimated from the "
                                     "particles' masses and contact stiffnesses; use at most "
                                     "{:.4g} s (safety factor {:g}) or \"auto\"",
                                     crit, sc.simulation.world.timestep_safety_factor * crit,
                                     sc.simulation.world.timestep_safety_factor));
    }
    if (fs::exists(ckpt))
      throw InputError(opt.output_dir.empty() ? "simulation.output_dir" : "--out", dir,
                       fmt::format("holds an unfinished run ({}): continue it with `centridem "
                                   "run --resume {}`, or choose another folder (or delete the "
                                   "checkpoint to start afresh)",
                                   ckpt, dir));
  }

  RunLog log(opt.out, opt.err);
  if (!resume) {
    make_directories(dir);
    remove_previous_outputs(dir);
    remove_temporaries(dir);
  }
  log.open(path_in(dir, "log.txt"), resume);
  if (resume) {
    remove_temporaries(dir);
    log.info(fmt::format("centridem run --resume {}: from {} at step {} (t = {:.6g} s), stage {}{}",
                         dir, ckpt, world.step_count(), world.time(), pr.stage,
                         pr.stage < sc.stages.size()
                             ? fmt::format(" {} ({} steps into it)", sc.stages[pr.stage].name,
                                           pr.in_stage ? pr.done : 0)
                             : std::string()));
  } else {
    write_text_file(path_in(dir, "scenario.resolved.toml"), resolved_toml(sc));
    echo(log, sc, world, threads);
    warn_wall_overlaps(log, world);
  }

  std::vector<std::string> wall_names;
  for (const WallSpec& w : sc.walls) wall_names.push_back(w.name);
  std::unique_ptr<MeasurementTable> table_ptr;
  FrameWriter frames(dir);
  RunReport report;
  report.output_dir = dir;
  if (resume) {
    try {
      table_ptr =
          std::make_unique<MeasurementTable>(path_in(dir, "measurements.csv"), wall_names,
                                             saved.at("table").at("bytes").get<std::uintmax_t>(),
                                             saved.at("table").at("last_step").get<long>());
      frames.restore(saved.at("frames"));
      for (const auto& r : saved.at("stages")) report.stages.push_back(stage_report_from(r));
    } catch (const nlohmann::json::exception& e) {
      throw InputError("--resume", ckpt,
                       fmt::format("the run's progress record is unreadable ({})", e.what()));
    }
  } else {
    table_ptr = std::make_unique<MeasurementTable>(path_in(dir, "measurements.csv"), wall_names);
  }
  MeasurementTable& table = *table_ptr;
  Summary summary(path_in(dir, "summary.json"), sc, threads);
  const double progress_every = sc.simulation.progress_interval_s;

  // The checkpoints: at the start, when due (minutes or steps) and on a stop
  // request, always between chunks.
  auto stage_start = Clock::now();
  const auto progress_record = [&] {
    nlohmann::json stages = nlohmann::json::array();
    for (const StageReport& r : report.stages) stages.push_back(stage_report_json(r));
    StageReport rep = pr.rep;
    rep.wall_time_s = pr.in_stage ? seconds_since(stage_start) : 0.0;
    const nlohmann::json j = {
        {"format", "centridem-run"},
        {"version", 1},
        {"source_path", sc.source_path},
        {"stage", pr.stage},
        {"in_stage", pr.in_stage},
        {"done", pr.done},
        {"chunk", pr.chunk},
        {"n_particles", pr.n_particles},
        {"cycle_seconds", pr.cycle_seconds},
        {"frames_before", pr.frames_before},
        {"rep", stage_report_json(rep)},
        {"run_seconds", seconds_since(run_start)},
        {"stages", stages},
        {"frames", frames.save()},
        {"table", {{"bytes", table.bytes()}, {"last_step", table.last_step()}}}};
    return j.dump();
  };
  CheckpointedCycling cyc(
      world, ckpt, {sc.simulation.checkpoint_interval_min, sc.simulation.checkpoint_interval_steps},
      progress_record);
  if (!resume) cyc.write_now();

  std::size_t k = pr.stage;
  try {
    for (; pr.stage < sc.stages.size(); ++pr.stage, pr.in_stage = false) {
      k = pr.stage;
      const StageSpec& st = sc.stages[k];
      const std::string path = fmt::format("stages[{}]", k);
      StageReport& rep = pr.rep;
      if (pr.in_stage) {
        // Resumed within the stage: its changes and first frame are done.
        stage_start = seconds_ago(rep.wall_time_s);
      } else {
        stage_start = Clock::now();
        rep = StageReport{};
        rep.name = st.name;
        rep.end = st.end;
        log.info(fmt::format("stage {} {}: {}", k, st.name, describe_end(st)));
        const StageChanges changes = apply_stage_changes(world, st, path);
        rep.particles_removed = changes.particles_removed;
        rep.contacts_modified = changes.contacts_modified;
        log_changes(log, world, st, changes);
        rep.first_step = world.step_count();
        rep.start_time_s = world.time();
        pr.frames_before = frames.count();
        if (st.frames_every > 0) frames.write(world);
        pr.n_particles = static_cast<double>(world.particles().size());
        // Chunks of about a million particle-steps. The chunk length must not
        // depend on the wall clock: World::cycle re-estimates the automatic
        // timestep at each call, so the chunking is part of the trajectory.
        pr.chunk = std::clamp(static_cast<long>(1e6 / std::max(pr.n_particles, 1.0)), 50L, 1000L);
        pr.done = 0;
        pr.cycle_seconds = 0;
        pr.in_stage = true;
      }

      // Cycle in chunks; write checkpoints, measure, write frames, check
      // equilibrium and print progress only between chunks.
      const double n_particles = pr.n_particles;
      const double t0 = rep.start_time_s;
      const double t_end = t0 + st.time_s;
      long& done = pr.done;
      const long chunk = pr.chunk;
      double ratio = std::numeric_limits<double>::quiet_NaN();
      long trend_step = -1;
      double trend_ratio = 0;
      auto last_progress = Clock::now();
      auto next_multiple = [&](long every) {
        return every > 0 ? (done / every + 1) * every : std::numeric_limits<long>::max();
      };
      for (;;) {
        long want = 0;
        if (st.end == StageEnd::steps) {
          want = st.steps - done;
        } else if (st.end == StageEnd::time) {
          const double left = t_end - world.time();
          if (left <= 1e-12 * st.time_s) break;
          const double dt = world.timestep();
          want = dt > 0 ? std::max(static_cast<long>(std::ceil(left / dt)), 1L) : 1;
          // The automatic timestep may grow within a chunk: close in by
          // halves so that the stage ends within a step of its time.
          if (world.settings().timestep_s <= 0) want = want > 4 ? (want + 1) / 2 : 1;
        } else {
          if (rep.reached_equilibrium) break;
          want = std::min(st.equilibrium_max_steps, next_multiple(st.equilibrium_check_interval)) -
                 done;
        }
        if (want <= 0) break;
        // A checkpoint only where cycling comes next: the forces of the last
        // step are not in it (they are recomputed by the next step), so a
        // measurement or frame must not follow a resume before a step does.
        cyc.at_check();
        const long n = std::min({want, chunk, next_multiple(st.frames_every) - done,
                                 next_multiple(st.measure_every) - done});
        const auto c0 = Clock::now();
        cyc.advance(n);
        pr.cycle_seconds += seconds_since(c0);
        done += n;
        if (st.end == StageEnd::equilibrium &&
            (done % st.equilibrium_check_interval == 0 || done >= st.equilibrium_max_steps)) {
          ratio = world.mean_unbalanced_force_ratio();
          if (ratio < st.equilibrium_ratio) rep.reached_equilibrium = true;
        }
        if (st.frames_every > 0 && done % st.frames_every == 0) frames.write(world);
        if (st.measure_every > 0 && done % st.measure_every == 0)
          table.row(world, world.measure(), st.name);

        if (seconds_since(last_progress) >= progress_every) {
          last_progress = Clock::now();
          const double rate = static_cast<double>(done) / std::max(pr.cycle_seconds, 1e-9);
          std::string where;
          double eta = std::numeric_limits<double>::quiet_NaN();
          if (st.end == StageEnd::steps) {
            where = fmt::format("step {}/{} ({:.0f}%)", done, st.steps,
                                100.0 * static_cast<double>(done) / static_cast<double>(st.steps));
            eta = static_cast<double>(st.steps - done) / rate;
          } else if (st.end == StageEnd::time) {
            const double frac = (world.time() - t0) / st.time_s;
            where = fmt::format("step {} ({:.0f}% of {:g} s)", done, 100.0 * frac, st.time_s);
            eta = frac > 0 ? seconds_since(stage_start) * (1 - frac) / frac : eta;
          } else {
            if (std::isnan(ratio)) ratio = world.mean_unbalanced_force_ratio();
            where = fmt::format("step {} (ratio {:.3e}, target {:.1e})", done, ratio,
                                st.equilibrium_ratio);
            // Extrapolate the ratio's log-linear decay since the last line.
            if (trend_step >= 0 && ratio < trend_ratio && ratio > 0) {
              const double slope =
                  std::log(ratio / trend_ratio) / static_cast<double>(done - trend_step);
              const double steps_left = std::log(st.equilibrium_ratio / ratio) / slope;
              eta =
                  std::min(steps_left, static_cast<double>(st.equilibrium_max_steps - done)) / rate;
            }
            trend_step = done;
            trend_ratio = ratio;
          }
          log.progress(fmt::format("  [{}] {}  t = {:.6g} s  {:.3g} particle-steps/s  ETA {}",
                                   st.name, where, world.time(), rate * n_particles,
                                   duration(eta)));
        }
      }

      // The stage's end: measurements, particles, a frame, a line.
      const Measurements m = world.measure();
      table.row(world, m, st.name);
      if (st.frames_every > 0) frames.write(world);
      rep.steps = done;
      rep.time_s = world.time() - rep.start_time_s;
      rep.end_state = m;
      rep.walls = read_walls(world);
      rep.particles_file = fmt::format("stage_{:02d}_{}_particles.txt", k, st.name);
      write_particle_file(world, path_in(dir, rep.particles_file));
      rep.frames = frames.count() - pr.frames_before;
      rep.wall_time_s = seconds_since(stage_start);
      rep.particle_steps_per_s =
          pr.cycle_seconds > 0 ? n_particles * static_cast<double>(done) / pr.cycle_seconds : 0.0;
      std::string how;
      if (st.end == StageEnd::equilibrium)
        how = rep.reached_equilibrium
                  ? fmt::format(" (equilibrium: ratio {:.3e} < {:g})",
                                m.mean_unbalanced_force_ratio, st.equilibrium_ratio)
                  : fmt::format(" (NOT in equilibrium after max_steps: ratio {:.3e} >= {:g})",
                                m.mean_unbalanced_force_ratio, st.equilibrium_ratio);
      log.info(fmt::format("stage {} {} done: {} steps{}, t = {:.6g} s (+{:.4g} s); "
                           "particles {}, contacts {} ball-ball + {} ball-wall, coordination "
                           "{:.3f}, ratio {:.3e}, kinetic energy {:.4g} J, max overlap {:.3g} r; "
                           "{} wall time, {:.3g} particle-steps/s",
                           k, st.name, done, how, world.time(), rep.time_s, m.particles,
                           m.ball_ball_contacts, m.ball_wall_contacts, m.coordination_number,
                           m.mean_unbalanced_force_ratio, m.kinetic_energy_J, m.max_overlap_ratio,
                           duration(rep.wall_time_s), rep.particle_steps_per_s));
      if (!rep.walls.empty()) {
        std::string w = "  wall forces [N]:";
        for (const WallReading& r : rep.walls)
          w += fmt::format(" {} [{:.4g}, {:.4g}, {:.4g}] ({} contacts);", r.name, r.force_N.x,
                           r.force_N.y, r.force_N.z, r.contacts);
        w.pop_back();
        log.info(w);
      }
      if (st.end == StageEnd::equilibrium && !rep.reached_equilibrium)
        log.warn(fmt::format("stage {} {} stopped at max_steps = {} before reaching ratio {:g}", k,
                             st.name, st.equilibrium_max_steps, st.equilibrium_ratio));
      report.stages.push_back(rep);
      report.wall_time_s = seconds_since(run_start);
      summary.write(report, k + 1 == sc.stages.size() ? "completed" : "running", "");
    }
  } catch (const InstabilityError& e) {
    report.wall_time_s = seconds_since(run_start);
    log.note(fmt::format("unstable in stage {}: {}", k, e.what()));
    summary.write(report, "unstable", e.what());
    throw;
  } catch (const InputError& e) {
    report.wall_time_s = seconds_since(run_start);
    log.note(fmt::format("input error in stage {}: {}", k, e.what()));
    summary.write(report, "input error", e.what());
    throw;
  } catch (const Interrupted& e) {
    report.wall_time_s = seconds_since(run_start);
    const std::string what =
        fmt::format("{}; continue with `centridem run --resume {}`", e.what(), dir);
    log.note(fmt::format("interrupted in stage {}: {}", k, what));
    summary.write(report, "interrupted", what);
    throw Interrupted(e.signal(), what);
  }
  write_final_state(world, path_in(dir, "final_state.csv"));
  report.wall_time_s = seconds_since(run_start);
  summary.write(report, "completed", "");
  std::error_code ec;
  fs::remove(ckpt, ec); // finished: the run folder is the record
  remove_temporaries(dir);
  log.info(fmt::format("done in {}: {}", duration(report.wall_time_s), dir));
  return report;
}

} // namespace

RunReport run_scenario(Scenario sc, const RunOptions& opt) {
  return run_staged(std::move(sc), opt, false);
}

RunReport resume_run(const std::string& dir, const RunOptions& opt) {
  if (!opt.output_dir.empty())
    throw InputError("--out", opt.output_dir,
                     "not with --resume: the run continues in its own folder");
  if (opt.threads)
    throw InputError("--threads", fmt::format("{}", *opt.threads),
                     "not with --resume: the run continues with the thread count it was started "
                     "with (kept in its checkpoint), so that it ends as if never stopped");
  const fs::path d(dir);
  if (!fs::is_regular_file(d / "scenario.resolved.toml"))
    throw InputError("--resume", dir,
                     "not a run folder of `centridem run` (scenario.resolved.toml missing)");
  if (!fs::exists(d / kCheckpointName)) {
    std::string status;
    try {
      std::ifstream in(d / "summary.json");
      status = nlohmann::json::parse(in).at("status").get<std::string>();
    } catch (const std::exception&) {
    }
    if (status == "completed") {
      if (opt.err)
        fmt::print(opt.err, "centridem run: {} completed earlier; nothing to resume\n", dir);
      RunReport r;
      r.output_dir = dir;
      return r;
    }
    throw InputError("--resume", dir,
                     fmt::format("holds no {}: the run stopped before writing one; start it "
                                 "again with `centridem run SCENARIO --out {}`",
                                 kCheckpointName, dir));
  }
  Scenario sc = load_scenario((d / "scenario.resolved.toml").string());
  RunOptions o = opt;
  o.output_dir = dir;
  return run_staged(std::move(sc), o, true);
}

} // namespace centridem
