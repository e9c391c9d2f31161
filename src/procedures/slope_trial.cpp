#include "procedures/slope_trial.hpp"

#include "base/errors.hpp"
#include "engine/world.hpp"
#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "io/picture.hpp"
#include "io/vtk.hpp"
#include "physics/body_field.hpp"
#include "procedures/checkpointed_cycling.hpp"
#include "procedures/moisture.hpp"
#include "procedures/slope_stability.hpp"
#include "procedures/specimen.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <unistd.h>

namespace centridem {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The trial's progress, kept in the checkpoint's procedure blob.
struct Progress {
  int phase = 0;         // 0: foundation; 1: levels
  std::size_t level = 0; // index into plan.g_levels
  long level_first_step = 0;
  double level_t0 = 0;            // world time at the level's start [s]
  double cut_t0 = 0;              // world time at the cut: the trial's time axis starts here [s]
  long foundation_first_step = 0; // world step at the start of the foundation's cycling
  FoundationResult foundation;
  std::size_t excavated = 0, slope_particles = 0;
  std::vector<json> done_levels; // {g, monitor, first_step, steps, time_s, time_limit}
  std::vector<std::pair<double, std::string>> vtk_frames;
  std::vector<std::string> pictures;
  int frames = 0;
  long next_frame_step = 0;
  int slides = 0;
};

json level_json(double g, const FailureMonitor& m, long first_step, long steps, double time_s,
                bool time_limit) {
  return {{"g_level", g},   {"monitor", m.save()}, {"first_step", first_step},
          {"steps", steps}, {"time_s", time_s},    {"time_limit", time_limit}};
}

LevelResult level_from(const json& j, const SlopeGeometry& g, const FailureCriteria& c) {
  FailureMonitor m(g, c);
  m.restore(j.at("monitor"));
  LevelResult r;
  r.g_level = j.at("g_level");
  r.report = m.report();
  r.history = m.history();
  r.first_step = j.at("first_step");
  r.steps = j.at("steps");
  r.time_s = j.at("time_s");
  r.time_limit = j.at("time_limit");
  return r;
}

std::string save_progress(const Progress& p, const FailureMonitor* monitor) {
  json frames = json::array();
  for (const auto& [t, f] : p.vtk_frames) frames.push_back({t, f});
  json j = {{"format", "centridem-slope-trial"},
            {"version", 1},
            {"phase", p.phase},
            {"level", p.level},
            {"level_first_step", p.level_first_step},
            {"level_t0", p.level_t0},
            {"cut_t0", p.cut_t0},
            {"foundation_first_step", p.foundation_first_step},
            {"foundation", to_json(p.foundation)},
            {"excavated", p.excavated},
            {"slope_particles", p.slope_particles},
            {"done_levels", p.done_levels},
            {"vtk_frames", frames},
            {"pictures", p.pictures},
            {"frames", p.frames},
            {"next_frame_step", p.next_frame_step},
            {"slides", p.slides},
            {"monitor", monitor ? monitor->save() : json(nullptr)}};
  return j.dump();
}

Progress load_progress(const std::string& blob, json& monitor_state, const std::string& path) {
  Progress p;
  try {
    const json j = json::parse(blob);
    if (j.at("format") != "centridem-slope-trial")
      throw InputError(path + ": not a slope-trial checkpoint");
    p.phase = j.at("phase");
    p.level = j.at("level");
    p.level_first_step = j.at("level_first_step");
    p.level_t0 = j.at("level_t0");
    // Checkpoints before cut_t0 existed: the first level starts at the cut.
    p.cut_t0 = j.contains("cut_t0") ? j.at("cut_t0").get<double>() : p.level_t0;
    p.foundation_first_step = j.at("foundation_first_step");
    p.foundation = foundation_from_json(j.at("foundation"));
    p.excavated = j.at("excavated");
    p.slope_particles = j.at("slope_particles");
    for (const auto& l : j.at("done_levels")) p.done_levels.push_back(l);
    for (const auto& f : j.at("vtk_frames")) p.vtk_frames.emplace_back(f.at(0), f.at(1));
    p.pictures = j.at("pictures").get<std::vector<std::string>>();
    p.frames = j.at("frames");
    p.next_frame_step = j.at("next_frame_step");
    p.slides = j.at("slides");
    monitor_state = j.at("monitor");
  } catch (const json::exception& e) {
    throw InputError(
        fmt::format("{}: the trial's progress record is unreadable ({})", path, e.what()));
  }
  return p;
}

} // namespace

const LevelResult* SlopeTrialResult::first_failure() const {
  for (const LevelResult& l : levels)
    if (l.report.state == SlopeState::failed) return &l;
  return nullptr;
}

BodyField slope_field(const SlopeScenario& sc, const SlopeGeometry& g, double g_level) {
  const double s = g.scale();
  if (sc.field.kind == FieldKind::uniform) return BodyField::scaled_gravity(g_level, s);
  const double r_ref = sc.field.reference_radius(sc.slope.total_height_m);
  // The chamber's middle (the end of the model, x = length) under the axis.
  const Vec3 base{g.length(), 0.5 * g.breadth(), 0.0};
  const Vec3 axis = sc.field.axis == 'x' ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  return BodyField::centrifuge(g_level, s, r_ref, sc.field.base_radius_m, base, axis,
                               sc.field.coriolis);
}

void frame_slope_picture(const SlopeGeometry& geometry, SideViewInput& in) {
  in.outline.x.clear();
  in.outline.z.clear();
  for (const SectionPoint& q : geometry.outline()) {
    in.outline.x.push_back(q.x);
    in.outline.z.push_back(q.z);
  }
  in.window = SideViewWindow{-0.02 * geometry.length(), 1.02 * geometry.length(),
                             -0.03 * geometry.height(), 1.08 * geometry.height()};
}

SlopeTrialResult run_slope_trial(const SlopeScenario& sc, const SlopeTrialPlan& plan,
                                 const SlopeTrialOptions& o) {
  if (plan.g_levels.empty()) throw InputError("g-levels", "(none)", "at least one g-level");
  const auto t_start = Clock::now();
  auto say = [&](const std::string& line) {
    if (o.log) o.log(line);
  };
  const fs::path dir(o.dir);
  make_directories(o.dir);
  make_directories((dir / "pictures").string());
  if (sc.output.vtk) make_directories((dir / "frames").string());
  const std::string ckpt = (dir / "checkpoint.bin").string();
  const SlopeGeometry geometry(sc.slope);
  const TrialSpec& ts = sc.trial;
  const int threads = o.threads >= 0 ? o.threads : ts.threads;

  WorldSettings ws;
  ws.local_damping = ts.local_damping;
  ws.threads = threads;
  World world(ws);
  Progress pr;
  std::optional<FailureMonitor> monitor;
  SlopeTrialResult result;

  if (fs::exists(ckpt)) {
    // ------------------------------------------------------------- resume
    const LoadedCheckpoint lc = read_checkpoint(world, ckpt);
    json mstate;
    pr = load_progress(lc.procedure_state, mstate, ckpt);
    if (pr.phase == 1 && !mstate.is_null()) {
      monitor.emplace(geometry, sc.failure);
      monitor->restore(mstate);
    }
    result.resumed = true;
    say(fmt::format("resumed from {} at step {} (t = {:.5f} s), {}", ckpt, world.step_count(),
                    world.time(),
                    pr.phase == 0 ? std::string("foundation stage")
                                  : fmt::format("level {} g", plan.g_levels[pr.level])));
  } else {
    // ---------------------------------------------------------- foundation
    const double L = geometry.length(), B = geometry.breadth();
    auto specimen_log = [&](std::string_view l) { say(std::string(l)); };
    if (sc.preparation.enabled) {
      // The prepared foundation, made once per recipe and cached.
      const std::string cache =
          o.cache_dir.empty() ? (dir / "foundation_cache").string() : o.cache_dir;
      const PreparedFoundationFile pf =
          ensure_prepared_foundation(sc, cache, specimen_log, threads);
      const std::string& file = pf.path;
      read_checkpoint(world, file);
      pr.foundation = pf.result;
      pr.foundation.from_cache = !pf.made_now;
      world.set_local_damping(ts.local_damping);
      say(fmt::format("prepared foundation {} ({}): {} particles, porosity by thirds {:.4f} / "
                      "{:.4f} / {:.4f}",
                      file, pr.foundation.from_cache ? "from the cache" : "new",
                      pr.foundation.particles, pr.foundation.layer_porosity[0],
                      pr.foundation.layer_porosity[1], pr.foundation.layer_porosity[2]));
    } else {
      build_foundation(world, sc, geometry, o.cache_dir, 1.0, pr.foundation, specimen_log, threads);
    }
    world.set_body_field(slope_field(sc, geometry, plan.g_levels[0]));
    pr.foundation_first_step = world.step_count();
    say(fmt::format("foundation: {} particles ({}); equilibrium at {:g} g (|g| = {:.4g} m/s^2 "
                    "at the floor)",
                    pr.foundation.particles,
                    pr.foundation.prepared           ? "prepared"
                    : pr.foundation.brick_from_cache ? "brick from cache"
                                                     : "new brick",
                    plan.g_levels[0],
                    norm(world.body_field().acceleration({0.5 * L, 0.5 * B, 0}, {}))));
  }

  // ---------------------------------------------------- cycling helpers
  const long chunk = ts.check_interval_steps;
  auto last_progress = Clock::now();
  long progress_steps = world.step_count();
  CheckpointedCycling cyc(world, ckpt, {ts.checkpoint_interval_min, ts.checkpoint_interval_steps},
                          [&] { return save_progress(pr, monitor ? &*monitor : nullptr); });
  auto advance = [&](long n) { cyc.advance(n); };
  auto after_chunk = [&] { cyc.at_check(); };
  auto rate = [&] {
    const double wall = seconds_since(last_progress);
    const double r = wall > 0 ? static_cast<double>(world.step_count() - progress_steps) *
                                    static_cast<double>(world.particles().size()) / wall
                              : 0.0;
    last_progress = Clock::now();
    progress_steps = world.step_count();
    return r;
  };

  // ---------------------------------------------------------- phase 0
  if (pr.phase == 0) {
    const double L = geometry.length(), B = geometry.breadth();
    const double d50 = median_diameter(world.particles());
    const Vec3 floor_centre{0.5 * L, 0.5 * B, 0.0};
    for (;;) {
      const long done = world.step_count() - pr.foundation_first_step;
      if (done >= ts.foundation_max_steps) break;
      // Checks at multiples of `chunk` steps, also after a resume mid-chunk.
      advance(std::min(chunk - done % chunk, ts.foundation_max_steps - done));
      const double ratio = world.mean_unbalanced_force_ratio();
      const double kinetic = kinetic_energy_ratio(world, floor_centre, d50);
      if (seconds_since(last_progress) >= o.progress_interval_s)
        say(fmt::format("foundation: step {}, ratio {:.3g} (target {:.3g}), kinetic {:.3g} "
                        "(target {:.3g}), {:.3g} particle-steps/s",
                        world.step_count() - pr.foundation_first_step, ratio, ts.equilibrium_ratio,
                        kinetic, ts.rest_kinetic_ratio, rate()));
      // At rest: balanced forces and little motion.
      if (ratio < ts.equilibrium_ratio && kinetic < ts.rest_kinetic_ratio) {
        pr.foundation.converged = true;
        break;
      }
      after_chunk();
    }
    FoundationResult& f = pr.foundation;
    f.steps = world.step_count() - pr.foundation_first_step;
    f.ratio = world.mean_unbalanced_force_ratio();
    f.kinetic_ratio = kinetic_energy_ratio(world, floor_centre, d50);
    f.coordination_number = world.measure().coordination_number;
    f.particles = world.particles().size();
    std::tie(f.surface_min_m, f.surface_mean_m) = foundation_surface(world.particles(), L, d50);
    f.porosity_after = 1 - solid_volume_m3(world.particles()) / (L * B * f.surface_mean_m);
    say(fmt::format("foundation {} in {} steps (ratio {:.3g}, kinetic {:.3g}); surface {:.3f} mm "
                    "(lowest {:.3f} mm) against the crest at {:.3f} mm; porosity {:.4f} -> {:.4f}; "
                    "coordination {:.2f}",
                    f.converged ? "at rest" : "NOT at rest (step limit)", f.steps, f.ratio,
                    f.kinetic_ratio, 1e3 * f.surface_mean_m, 1e3 * f.surface_min_m,
                    1e3 * geometry.height(), f.porosity_before, f.porosity_after,
                    f.coordination_number));
    if (f.surface_min_m < geometry.height() - d50)
      say(fmt::format("warning: the settled foundation's surface ({:.3f} mm at its lowest) is "
                      "below the crest ({:.3f} mm): the cut leaves the crest lower than "
                      "designed",
                      1e3 * f.surface_min_m, 1e3 * geometry.height()));

    // The cut.
    pr.excavated = geometry.excavate(world);
    const ContactProperties at_cut = sc.soil_at_cut();
    if (sc.moisture.enabled) {
      grade_attraction_by_height(world, at_cut, sc.moisture, geometry.height());
    } else if (!sc.trial.at_cut.empty()) {
      world.modify_ball_ball_contacts([](std::size_t, std::size_t) { return true; },
                                      [&](ContactProperties& c) { c = at_cut; });
    }
    world.set_ball_ball_defaults(sc.soil_after_cut());
    if (sc.moisture.enabled && sc.moisture.new_contacts)
      grade_new_contacts_by_height(world, sc.soil_after_cut(), sc.moisture, geometry.height());
    world.reset_displacements();
    pr.slope_particles = world.particles().size();
    say(fmt::format("cut: {} particles excavated, {} remain in the slope", pr.excavated,
                    pr.slope_particles));
    if (sc.moisture.enabled) {
      const std::vector<double> band = band_attraction_factors(sc.moisture);
      say(fmt::format(
          "moisture: F0 x {:.3f} in the lowest of {} bands to x {:.3f} in the highest{}",
          band.front(), band.size(), band.back(),
          sc.moisture.new_contacts ? "; contacts made later by where they are made" : ""));
    }
    pr.phase = 1;
    pr.level = 0;
    pr.level_first_step = world.step_count();
    pr.level_t0 = world.time();
    pr.cut_t0 = world.time();
    pr.next_frame_step = world.step_count();
    monitor.emplace(geometry, sc.failure);
    cyc.write_now();
  }

  // ---------------------------------------------------------- frames
  // One time axis for the log, the pictures, the ParaView series and
  // frames.csv: seconds since the cut (a stepped campaign's later levels go on
  // counting; their own start is in the log and the picture's title).
  auto trial_time = [&] { return world.time() - pr.cut_t0; };
  PvdSeries pvd((dir / "slope.pvd").string());
  PvdSeries pvd_contacts((dir / "slope_contacts.pvd").string());
  PvdSeries pvd_walls((dir / "slope_walls.pvd").string());
  for (const auto& [t, f] : pr.vtk_frames) {
    pvd.add(t, f);
    const std::string k = f.substr(f.size() - 8, 4); // "frames/particles_NNNN.vtu"
    pvd_contacts.add(t, fmt::format("frames/contacts_{}.vtp", k));
    pvd_walls.add(t, fmt::format("frames/walls_{}.vtp", k));
  }
  std::string frames_csv = "frame,time_after_cut_s,step,g_level,picture,title\n";
  if (fs::exists(dir / "frames.csv")) { // a resumed trial: its frames so far
    frames_csv.clear();
    std::ifstream in(dir / "frames.csv");
    std::string line;
    for (int k = 0; std::getline(in, line) && k <= pr.frames; ++k) frames_csv += line + "\n";
  }
  // The limit-equilibrium circle at the level's g (drawn on every picture).
  std::optional<std::pair<double, LeSearchResult>> le_circle;
  auto limit_equilibrium_line = [&](double g_level) -> std::optional<SideViewPolyline> {
    if (!sc.limit_equilibrium.enabled) return std::nullopt;
    if (!le_circle || le_circle->first != g_level) {
      const double rho = limit_equilibrium_bulk_density(sc, &pr.foundation);
      le_circle.emplace(g_level, slope_critical_circle(sc, geometry, rho, g_level));
    }
    const LeSearchResult& c = le_circle->second;
    if (c.slip_surface.empty()) return std::nullopt;
    SideViewPolyline line;
    for (const auto& [x, z] : c.slip_surface) {
      line.x.push_back(x);
      line.z.push_back(z);
    }
    line.colour = {0.1, 0.3, 0.9};
    line.label =
        fmt::format("limit equilibrium (Bishop): FS {:.2f} at {:g} g", c.factor_of_safety, g_level);
    return line;
  };
  auto write_frame = [&](double g_level) {
    const ParticleStore& P = world.particles();
    SideViewInput in;
    in.x.resize(P.size());
    in.y.resize(P.size());
    in.z.resize(P.size());
    in.radius = P.radius;
    in.value.resize(P.size());
    for (std::size_t i = 0; i < P.size(); ++i) {
      in.x[i] = P.position[i].x, in.y[i] = P.position[i].y, in.z[i] = P.position[i].z;
      in.value[i] = norm(P.displacement[i]);
    }
    in.vmin = sc.output.colour_min_m;
    in.vmax = sc.output.colour_max_m;
    frame_slope_picture(geometry, in);
    if (monitor && monitor->failed() && !monitor->report().slip_surface.empty()) {
      SideViewPolyline slip;
      for (const SectionPoint& q : monitor->report().slip_surface) {
        slip.x.push_back(q.x);
        slip.z.push_back(q.z);
      }
      slip.label = "detected slip surface";
      in.extra_lines.push_back(slip);
    }
    if (auto le = limit_equilibrium_line(g_level)) in.extra_lines.push_back(*le);
    const double t = trial_time();
    std::string state;
    if (monitor) state = std::string(to_string(monitor->state()));
    const std::string level_start =
        pr.level_t0 > pr.cut_t0
            ? fmt::format(" (this level from {:.5f} s)", pr.level_t0 - pr.cut_t0)
            : std::string();
    in.title = fmt::format("{} — {:g} g — t = {:.5f} s after the cut{} — step {} — {}",
                           sc.name.empty() ? std::string("benched slope") : sc.name, g_level, t,
                           level_start, world.step_count(), state);
    in.width_px = sc.output.picture_width_px;
    const std::string name = fmt::format("pictures/frame_{:04d}.png", pr.frames);
    render_side_view(in, (dir / name).string());
    pr.pictures.push_back(name);
    if (sc.output.vtk) {
      // `sliding`: 1 for the particles of the sliding mass (the monitor's
      // largest connected group of displaced particles, once it counts as one).
      PointField sliding{"sliding", std::vector<float>(P.size(), 0.0f)};
      if (monitor && monitor->report().sliding_mass && monitor->report().d50_m > 0)
        for (std::size_t i :
             find_sliding_mass(world, sc.failure.mass, monitor->report().d50_m).indices)
          sliding.values[i] = 1.0f;
      const std::string vtu = fmt::format("frames/particles_{:04d}.vtu", pr.frames);
      const std::string vtp = fmt::format("frames/contacts_{:04d}.vtp", pr.frames);
      const std::string wvtp = fmt::format("frames/walls_{:04d}.vtp", pr.frames);
      write_particles_vtu(world, (dir / vtu).string(), {sliding});
      write_contacts_vtp(world, (dir / vtp).string());
      write_walls_vtp(world, (dir / wvtp).string());
      pr.vtk_frames.emplace_back(t, vtu);
      pvd.add(t, vtu);
      pvd_contacts.add(t, vtp);
      pvd_walls.add(t, wvtp);
    }
    std::string title = in.title;
    std::replace(title.begin(), title.end(), ',', ';');
    frames_csv += fmt::format("{},{:.17g},{},{:g},{},{}\n", pr.frames, t, world.step_count(),
                              g_level, name, title);
    replace_text_file((dir / "frames.csv").string(), frames_csv);
    say(fmt::format("frame {}: t = {:.5f} s after the cut, step {}, {:g} g ({})", pr.frames, t,
                    world.step_count(), g_level, name));
    ++pr.frames;
  };

  // ---------------------------------------------------------- levels
  while (pr.level < plan.g_levels.size()) {
    const double g = plan.g_levels[pr.level];
    world.set_body_field(slope_field(sc, geometry, g));
    if (!monitor) monitor.emplace(geometry, sc.failure);
    if (world.step_count() == pr.level_first_step && monitor->report().checks == 0) {
      say(fmt::format("level {:g} g: cycling, a check every {} steps, at most {:g} s", g, chunk,
                      ts.max_time_s));
      write_frame(g);
    }
    bool time_limit = false;
    for (;;) {
      // Decisions at checks only (multiples of `chunk` steps into the level),
      // also after a resume mid-chunk.
      const long into = world.step_count() - pr.level_first_step;
      if (into % chunk == 0) {
        const double t = world.time() - pr.level_t0;
        const FailureReport& r = monitor->report();
        if (monitor->stable() && t >= ts.min_time_s) break;
        if (monitor->failed() &&
            (monitor->finished() ||
             (r.onset_time_s && t - *r.onset_time_s >= ts.after_failure_time_s)))
          break;
        if (t >= ts.max_time_s) {
          time_limit = !monitor->failed();
          break;
        }
      }
      advance(chunk - into % chunk);
      const SlopeState before = monitor->state();
      monitor->update(world, world.time() - pr.level_t0);
      if (monitor->failed() && before != SlopeState::failed)
        say(fmt::format("level {:g} g: FAILED, onset t = {:.5f} s, start {}, {} particles moving",
                        g, *monitor->report().onset_time_s,
                        monitor->report().start_zone ? to_string(*monitor->report().start_zone)
                                                     : std::string("?"),
                        monitor->report().particles));
      if (sc.output.frame_interval_steps > 0 && world.step_count() >= pr.next_frame_step) {
        pr.next_frame_step = world.step_count() + sc.output.frame_interval_steps;
        if (world.step_count() > pr.level_first_step) write_frame(g);
      }
      if (seconds_since(last_progress) >= o.progress_interval_s) {
        const FailureReport& q = monitor->report();
        const std::string in_level =
            pr.level_t0 > pr.cut_t0
                ? fmt::format(", {:.5f} s into this level", world.time() - pr.level_t0)
                : std::string();
        say(fmt::format("level {:g} g: t = {:.5f} s after the cut{} (limit {:g} s), step {}, "
                        "slope ratio {:.3g}, {}, largest moved group {} particles, {:.3g} "
                        "particle-steps/s",
                        g, trial_time(), in_level, ts.max_time_s, world.step_count(),
                        q.unbalanced_force_ratio, to_string(q.state), q.largest_group_particles,
                        rate()));
      }
      after_chunk();
    }
    write_frame(g);
    const long steps = world.step_count() - pr.level_first_step;
    const double time_s = world.time() - pr.level_t0;
    pr.done_levels.push_back(
        level_json(g, *monitor, pr.level_first_step, steps, time_s, time_limit));
    const FailureReport& r = monitor->report();
    say(fmt::format("level {:g} g: {}{} after {:.5f} s ({} steps){}", g, to_string(r.state),
                    time_limit ? " (time limit, undecided)" : "", time_s, steps,
                    r.state == SlopeState::failed
                        ? fmt::format("; sliding mass {} particles ({:.1f} % of the slope), "
                                      "start {}, benches {}, runout {:.2f} mm (model {:.1f} mm)",
                                      r.particles, 100 * r.volume_share,
                                      r.start_zone ? to_string(*r.start_zone) : "?",
                                      fmt::format("{}", fmt::join(r.benches_crossed, ",")),
                                      1e3 * r.runout_m, 1e3 * r.runout_model_m)
                        : std::string()));
    if (r.state == SlopeState::failed) ++pr.slides;
    ++pr.level;
    monitor.reset();
    if (pr.slides >= plan.max_slides) break;
    if (pr.level < plan.g_levels.size()) { // stepped: raise g on the same model
      world.reset_displacements();
      pr.level_first_step = world.step_count();
      pr.level_t0 = world.time();
      pr.next_frame_step = world.step_count();
      monitor.emplace(geometry, sc.failure);
    }
  }

  // ---------------------------------------------------------- result
  result.foundation = pr.foundation;
  result.excavated = pr.excavated;
  result.slope_particles = pr.slope_particles;
  for (const json& l : pr.done_levels) result.levels.push_back(level_from(l, geometry, sc.failure));
  result.total_steps = world.step_count();
  result.timestep_s = world.timestep();
  result.wall_seconds = seconds_since(t_start);
  result.particle_steps_per_s = cyc.particle_steps_per_s();
  result.pictures = pr.pictures;

  std::string csv = "g_level,time_s,above_threshold,mass_particles,mass_mean_speed_m_s,"
                    "unbalanced_force_ratio,significant,moving\n";
  for (const LevelResult& l : result.levels)
    for (const FailureCheck& c : l.history)
      csv += fmt::format("{:g},{:.9g},{},{},{:.6g},{:.6g},{},{}\n", l.g_level, c.time_s,
                         c.above_threshold, c.mass_particles, c.mass_mean_speed_m_s,
                         c.unbalanced_force_ratio, c.significant ? 1 : 0, c.moving ? 1 : 0);
  replace_text_file((dir / "checks.csv").string(), csv);
  {
    // The final state, every double exactly (17 significant digits).
    const ParticleStore& P = world.particles();
    std::string st = "id,x_m,y_m,z_m,radius_m,vx_m_s,vy_m_s,vz_m_s,ux_m,uy_m,uz_m\n";
    st.reserve(P.size() * 240);
    for (std::size_t i = 0; i < P.size(); ++i)
      st +=
          fmt::format("{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},"
                      "{:.17g}\n",
                      P.id[i], P.position[i].x, P.position[i].y, P.position[i].z, P.radius[i],
                      P.velocity[i].x, P.velocity[i].y, P.velocity[i].z, P.displacement[i].x,
                      P.displacement[i].y, P.displacement[i].z);
    replace_text_file((dir / "final_state.csv").string(), st);
  }
  replace_text_file((dir / "result.json").string(), to_json(result).dump(2) + "\n");
  std::error_code ec;
  fs::remove(ckpt, ec); // finished: result.json is the record
  return result;
}

json to_json(const SlopeTrialResult& r) {
  json levels = json::array();
  for (const LevelResult& l : r.levels) {
    json j = to_json(l.report);
    j["g_level"] = l.g_level;
    j["first_step"] = l.first_step;
    j["steps"] = l.steps;
    j["level_time_s"] = l.time_s;
    j["time_limit"] = l.time_limit;
    levels.push_back(j);
  }
  const LevelResult* f = r.first_failure();
  return {{"foundation", to_json(r.foundation)},
          {"excavated", r.excavated},
          {"slope_particles", r.slope_particles},
          {"levels", levels},
          {"failed", f != nullptr},
          {"first_failure_g", f ? json(f->g_level) : json(nullptr)},
          {"total_steps", r.total_steps},
          {"timestep_s", r.timestep_s},
          {"wall_seconds", r.wall_seconds},
          {"particle_steps_per_s", r.particle_steps_per_s},
          {"pictures", r.pictures},
          {"resumed", r.resumed}};
}

} // namespace centridem
