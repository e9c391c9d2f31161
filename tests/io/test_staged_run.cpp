// A small 3-stage scenario run end to end through the library API (run
// folder, ParaView files read back as XML), and the `centridem run` binary on
// a bad scenario (exit code 2 and the message).
#include "base/errors.hpp"
#include "io/scenario.hpp"
#include "io/vtk.hpp"
#include "procedures/staged_run.hpp"
#include "vtk_test_util.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace centridem;

namespace {

using vtktest::read_file;
using vtktest::Xml;

std::unique_ptr<Xml> read_xml(const fs::path& p) {
  return vtktest::XmlParser(vtktest::read_file(p)).document();
}

std::vector<double> numbers(const std::string& text) {
  std::vector<double> v;
  std::istringstream in(text);
  double x;
  while (in >> x) v.push_back(x);
  EXPECT_TRUE(in.eof()) << "a DataArray holds something that is not a number";
  return v;
}

// Checks a .vtu: well-formed, binary (appended, compressed), every array
// sized for its points/cells; returns the number of points.
std::size_t check_vtu(const fs::path& p) {
  const vtktest::VtkFile f = vtktest::read_vtk(p);
  const auto& doc = f.doc;
  EXPECT_EQ(doc->name, "VTKFile");
  EXPECT_EQ(doc->attr.at("type"), "UnstructuredGrid");
  EXPECT_EQ(doc->attr.at("compressor"), "vtkZLibDataCompressor");
  const Xml* piece = doc->child("UnstructuredGrid")->child("Piece");
  const std::size_t n = std::stoul(piece->attr.at("NumberOfPoints"));
  EXPECT_EQ(std::stoul(piece->attr.at("NumberOfCells")), n);
  std::vector<const Xml*> arrays;
  piece->find_all("DataArray", arrays);
  std::map<std::string, std::size_t> seen;
  for (const Xml* a : arrays) {
    const std::size_t comps =
        a->attr.count("NumberOfComponents") ? std::stoul(a->attr.at("NumberOfComponents")) : 1;
    EXPECT_EQ(a->attr.at("format"), "appended");
    EXPECT_EQ(vtktest::values(f, *a).size(), n * comps) << a->attr.at("Name");
    seen[a->attr.at("Name")] = comps;
  }
  for (const auto& [name, comps] : std::map<std::string, std::size_t>{{"radius", 1},
                                                                      {"id", 1},
                                                                      {"group", 1},
                                                                      {"velocity", 3},
                                                                      {"displacement", 3},
                                                                      {"spin", 3},
                                                                      {"force", 3},
                                                                      {"Points", 3},
                                                                      {"connectivity", 1},
                                                                      {"offsets", 1},
                                                                      {"types", 1}})
    EXPECT_EQ(seen[name], comps) << name;
  return n;
}

// Checks a .vtp: lines between existing points, cell data per line.
std::size_t check_vtp(const fs::path& p) {
  const vtktest::VtkFile f = vtktest::read_vtk(p);
  EXPECT_EQ(f.doc->attr.at("type"), "PolyData");
  const Xml* piece = f.doc->child("PolyData")->child("Piece");
  const std::size_t np = std::stoul(piece->attr.at("NumberOfPoints"));
  const std::size_t nl = std::stoul(piece->attr.at("NumberOfLines"));
  std::vector<const Xml*> arrays;
  piece->find_all("DataArray", arrays);
  for (const Xml* a : arrays) {
    const std::string name = a->attr.count("Name") ? a->attr.at("Name") : "";
    const auto v = vtktest::values(f, *a);
    if (name == "Points") EXPECT_EQ(v.size(), 3 * np);
    if (name == "force_N") EXPECT_EQ(v.size(), 3 * nl);
    if (name == "normal_force_N" || name == "overlap_m" || name == "offsets")
      EXPECT_EQ(v.size(), nl) << name;
    if (name == "connectivity") {
      EXPECT_EQ(v.size(), 2 * nl);
      for (double k : v) EXPECT_LT(k, static_cast<double>(np));
    }
  }
  return nl;
}

std::vector<std::pair<double, std::string>> read_pvd(const fs::path& p) {
  const auto doc = read_xml(p);
  EXPECT_EQ(doc->attr.at("type"), "Collection");
  std::vector<std::pair<double, std::string>> out;
  for (const auto& d : doc->child("Collection")->children)
    out.emplace_back(std::stod(d->attr.at("timestep")), d->attr.at("file"));
  return out;
}

class StagedRunTest : public ::testing::Test {
protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           fmt::format("centridem_run_{}_{}_{}", getpid(), info->test_suite_name(), info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // 3 x 3 x 3 spheres of radius 0.4 mm at a pitch of 1 mm in a 3 mm box.
    std::string grains;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i)
          grains += fmt::format("{} {} {} 0.0004\n", 0.0005 + 0.001 * i, 0.0005 + 0.001 * j,
                                0.0005 + 0.001 * k);
    std::ofstream(dir_ / "grains.xyzr") << grains;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return dir_ / name;
  }
  fs::path dir_;
};

const char* kThreeStages = R"(
[simulation]
local_damping = 0.7
threads = 1
progress_interval_s = 0

[particles]
file = "grains.xyzr"
density_kg_m3 = 2633
group = 3

[contact.ball_ball]
model = "arrlinear"
effective_modulus_Pa = 10e6
friction = 0.5
rolling_friction = 0.16
attraction_force_N = 1e-5

[contact.ball_wall]
model = "linear"
effective_modulus_Pa = 10e6
friction = 0.2

[gravity]
g_level = 100

[[walls]]
name = "floor"
type = "plane"
point_m = [0, 0, 0]
normal = [0, 0, 1]
[[walls]]
name = "x0"
type = "plane"
point_m = [0, 0, 0]
normal = [1, 0, 0]
[[walls]]
name = "x1"
type = "rectangle"
centre_m = [0.003, 0.0015, 0.0015]
normal = [-1, 0, 0]
u_direction = [0, 1, 0]
size_m = [0.003, 0.003]

[[stages]]
name = "settle"
steps = 600
frames_every = 200
measure_every = 50

[[stages]]
name = "change"
contact.ball_ball = { attraction_force_N = 0 }
modify_contacts = { set = { rolling_friction = 0 } }
walls = { x0 = { velocity_m_per_s = [0.001, 0, 0], contact = { friction = 0.1 } } }
until_equilibrium = { ratio = 1e-30, max_steps = 200, check_interval = 50 } # below round-off: runs to max_steps
frames_every = 100

[[stages]]
name = "excavate"
remove_walls = ["x1"]
remove_particles = { region = { lo = [0, 0, 0.0011], hi = [1, 1, 1] } }
reset_displacements = true
walls = { x0 = { velocity_m_per_s = [0, 0, 0] } }
time_s = 2e-4
frames_every = 40
measure_every = 0
)";

} // namespace

TEST_F(StagedRunTest, ThreeStagesWriteTheRunFolder) {
  Scenario sc = load_scenario(write("three.toml", kThreeStages).string());
  const fs::path out = dir_ / "out";
  RunOptions o;
  o.output_dir = out.string();
  o.out = o.err = nullptr; // quiet: everything still goes to log.txt
  const RunReport r = run_scenario(sc, o);

  ASSERT_EQ(r.stages.size(), 3u);
  EXPECT_EQ(r.stages[0].steps, 600);
  EXPECT_EQ(r.stages[1].steps, 200);
  EXPECT_FALSE(r.stages[1].reached_equilibrium);
  EXPECT_GT(r.stages[1].contacts_modified, 0u);
  EXPECT_GE(r.stages[2].time_s, 2e-4);
  EXPECT_LT(r.stages[2].time_s, 2e-4 + 2 * r.stages[2].end_state.timestep_s);
  EXPECT_GT(r.stages[2].particles_removed, 0u);
  const std::size_t left = r.stages[2].end_state.particles;
  EXPECT_EQ(left + r.stages[2].particles_removed, 27u);

  for (const char* f :
       {"log.txt", "summary.json", "measurements.csv", "scenario.resolved.toml", "particles.pvd",
        "contacts.pvd", "walls.pvd", "stage_00_settle_particles.txt",
        "stage_01_change_particles.txt", "stage_02_excavate_particles.txt"})
    EXPECT_TRUE(fs::is_regular_file(out / f)) << f;

  // The .pvd series list every frame, in time order, and the files exist.
  const auto particles = read_pvd(out / "particles.pvd");
  const auto contacts = read_pvd(out / "contacts.pvd");
  std::size_t frames = 0;
  for (const StageReport& s : r.stages) frames += s.frames;
  // settle: steps 0..600 every 200 -> 4; change: 100, 200 (its start is the
  // same step as settle's end) -> 2; excavate: its start replaces change's
  // end frame, then every 40 steps and the end.
  EXPECT_EQ(r.stages[0].frames, 4u);
  EXPECT_EQ(r.stages[1].frames, 2u);
  ASSERT_EQ(particles.size(), frames);
  ASSERT_EQ(contacts.size(), frames);
  for (std::size_t k = 0; k < particles.size(); ++k) {
    EXPECT_EQ(particles[k].second, fmt::format("frames/particles_{:06d}.vtu", k));
    EXPECT_EQ(contacts[k].second, fmt::format("frames/contacts_{:06d}.vtp", k));
    if (k > 0) EXPECT_GT(particles[k].first, particles[k - 1].first);
    EXPECT_EQ(particles[k].first, contacts[k].first);
  }
  EXPECT_EQ(particles.front().first, 0.0);
  EXPECT_NEAR(particles.back().first, r.stages[2].start_time_s + r.stages[2].time_s, 1e-15);

  // Every frame parses; the first holds all particles, the last those left.
  for (std::size_t k = 0; k < particles.size(); ++k) {
    SCOPED_TRACE(particles[k].second);
    const std::size_t n = check_vtu(out / particles[k].second);
    check_vtp(out / contacts[k].second);
    if (k == 0) EXPECT_EQ(n, 27u);
    if (k + 1 == particles.size()) EXPECT_EQ(n, left);
  }
  EXPECT_GT(check_vtp(out / contacts[3].second), 0u); // settled: force chains

  // The walls as surfaces: one quadrilateral per wall, on its plane; x1 (a
  // 3 mm x 3 mm rectangle at x = 3 mm) is gone after the excavation.
  const auto walls = read_pvd(out / "walls.pvd");
  ASSERT_EQ(walls.size(), frames);
  for (std::size_t k = 0; k < walls.size(); ++k) {
    SCOPED_TRACE(walls[k].second);
    EXPECT_EQ(walls[k].first, particles[k].first);
    const vtktest::VtkFile f = vtktest::read_vtk(out / walls[k].second);
    const Xml* piece = f.doc->child("PolyData")->child("Piece");
    const std::size_t nw = std::stoul(piece->attr.at("NumberOfPolys"));
    // The excavation's first frame replaces the change stage's last (same step).
    const std::size_t walls_removed_at = r.stages[0].frames + r.stages[1].frames - 1;
    EXPECT_EQ(nw, k >= walls_removed_at ? 2u : 3u);
    const auto a = vtktest::arrays(f);
    ASSERT_EQ(a.at("Points").size(), 12 * nw);
    ASSERT_EQ(a.at("offsets").size(), nw);
    EXPECT_EQ(a.at("offsets").back(), 4.0 * static_cast<double>(nw));
    for (int c = 0; c < 4; ++c) EXPECT_EQ(a.at("Points")[3 * c + 2], 0.0) << "floor corner " << c;
    if (nw == 3) {
      for (int c = 0; c < 4; ++c) EXPECT_DOUBLE_EQ(a.at("Points")[24 + 3 * c], 0.003);
      double ymin = 1, ymax = -1;
      for (int c = 0; c < 4; ++c)
        ymin = std::min(ymin, a.at("Points")[25 + 3 * c]),
        ymax = std::max(ymax, a.at("Points")[25 + 3 * c]);
      EXPECT_NEAR(ymax - ymin, 0.003, 1e-15); // the rectangle's own size
    }
    // The floor carries the grains' weight once they rest on it.
    if (k == 3) EXPECT_LT(a.at("force_N")[2], 0.0);
  }

  // summary.json
  const auto j = nlohmann::json::parse(read_file(out / "summary.json"));
  EXPECT_EQ(j["status"], "completed");
  ASSERT_EQ(j["stages"].size(), 3u);
  EXPECT_EQ(j["stages"][1]["name"], "change");
  EXPECT_EQ(j["stages"][1]["reached_equilibrium"], false);
  for (const char* key : {"coordination_number", "mean_unbalanced_force_ratio", "kinetic_energy_J",
                          "ball_ball_contacts", "walls"})
    EXPECT_TRUE(j["stages"][0]["measurements"].contains(key)) << key;
  EXPECT_TRUE(j["stages"][0]["measurements"]["walls"].contains("x1"));
  EXPECT_FALSE(j["stages"][2]["measurements"]["walls"].contains("x1")); // removed
  EXPECT_GT(j["stages"][0]["particle_steps_per_s"].get<double>(), 0.0);

  // measurements.csv: a header with each wall's force, rows of equal width.
  std::istringstream csv(read_file(out / "measurements.csv"));
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(
      header.rfind("step,time_s,stage,ratio,kinetic_energy_J,coordination_number,contacts", 0), 0u);
  EXPECT_NE(header.find("x1_force_z_N"), std::string::npos);
  const auto width = std::count(header.begin(), header.end(), ',');
  int rows = 0;
  while (std::getline(csv, line)) {
    EXPECT_EQ(std::count(line.begin(), line.end(), ','), width) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 12 + 1 + 1); // settle every 50 steps; change and excavate at their ends

  // Stage particle files: x y z r vx vy vz per particle.
  std::istringstream last(read_file(out / "stage_02_excavate_particles.txt"));
  std::size_t n = 0;
  while (std::getline(last, line))
    if (!line.empty() && line[0] != '#') {
      EXPECT_EQ(numbers(line).size(), 7u);
      ++n;
    }
  EXPECT_EQ(n, left);

  // The log holds what was printed; the resolved scenario reads back.
  const std::string log = read_file(out / "log.txt");
  EXPECT_NE(log.find("stage 2 excavate done"), std::string::npos);
  EXPECT_NO_THROW(load_scenario((out / "scenario.resolved.toml").string()));

  // Same scenario, same threads: the same result, bit for bit.
  o.output_dir = (dir_ / "again").string();
  run_scenario(sc, o);
  EXPECT_EQ(read_file(dir_ / "again" / "stage_02_excavate_particles.txt"),
            read_file(out / "stage_02_excavate_particles.txt"));
}

TEST_F(StagedRunTest, BinaryExitsWithCode2OnBadInput) {
  std::string bad = kThreeStages;
  bad.replace(bad.find("friction = 0.5"), 14, "frcition = 0.5");
  const fs::path scenario = write("bad.toml", bad);
  const fs::path err = dir_ / "stderr.txt";
  const std::string cmd =
      fmt::format("'{}' run '{}' --out '{}' 2> '{}' > /dev/null", CENTRIDEM_BINARY,
                  scenario.string(), (dir_ / "out").string(), err.string());
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const std::string msg = read_file(err);
  EXPECT_EQ(msg.rfind("centridem: error: ", 0), 0u) << msg;
  EXPECT_NE(msg.find("contact.ball_ball.frcition"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean \"friction\""), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(dir_ / "out")); // nothing written for bad input
}

TEST_F(StagedRunTest, BinaryRunsAScenario) {
  std::string quick = kThreeStages;
  quick.replace(quick.find("steps = 600"), 11, "steps = 20");
  const fs::path scenario = write("quick.toml", quick);
  const std::string cmd =
      fmt::format("'{}' run '{}' --out '{}' --threads 1 > '{}' 2>&1", CENTRIDEM_BINARY,
                  scenario.string(), (dir_ / "out").string(), (dir_ / "stdout.txt").string());
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << read_file(dir_ / "stdout.txt");
  EXPECT_TRUE(fs::is_regular_file(dir_ / "out" / "summary.json"));
  EXPECT_NE(read_file(dir_ / "stdout.txt").find("stage 0 settle done: 20 steps"),
            std::string::npos);
  // Again into the same folder: what the first run left and this one does
  // not write goes; other files stay.
  std::ofstream(dir_ / "out" / "frames" / "particles_999999.vtu") << "old";
  std::ofstream(dir_ / "out" / "stage_07_old_particles.txt") << "old";
  std::ofstream(dir_ / "out" / "notes.txt") << "mine";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_FALSE(fs::exists(dir_ / "out" / "frames" / "particles_999999.vtu"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "stage_07_old_particles.txt"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "notes.txt"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "frames" / "particles_000000.vtu"));
}

// The paper's stage semantics through a stage's changes: `contact.ball_ball =
// { attraction_force_N = 0 }` gives new contacts no adhesion while the old
// keep theirs; `modify_contacts` changes existing contacts in its region only.
TEST_F(StagedRunTest, NewContactsCopyTheStageDefaultsOldKeepTheirs) {
  const double r = 0.0005;
  std::ofstream(dir_ / "three.xyzr")
      << fmt::format("0 0 0 {0}\n{1} 0 0 {0}\n{1} 0 {2} {0}\n", r, 2 * r - 1e-7, 2 * r + 1e-6);
  const Scenario sc = load_scenario(write("s.toml", R"(
[particles]
file = "three.xyzr"
density_kg_m3 = 2633
[contact.ball_ball]
model = "arrlinear"
effective_modulus_Pa = 10e6
rolling_friction = 0.16
attraction_force_N = 1e-5
[[stages]]
name = "before"
steps = 10
[[stages]]
name = "after"
contact.ball_ball = { attraction_force_N = 0 }
modify_contacts = { region = { lo = [-0.001, -0.001, -0.001], hi = [0.0015, 0.001, 0.0005] }, set = { friction = 0.4 } }
steps = 300
)")
                                        .string());
  World world = build_world(sc);
  ParticleStore& p = world.particles_mut();
  for (std::size_t i = 0; i < p.size(); ++i) p.flags[i] = fix_translation | fix_rotation;
  p.velocity[*world.index_of(3)] = {0, 0, -0.01}; // the third comes down onto the second
  world.cycle(sc.stages[0].steps);
  ASSERT_EQ(world.ball_ball_contacts().size(), 1u);

  const StageChanges c = apply_stage_changes(world, sc.stages[1], "stages[1]");
  EXPECT_EQ(c.contacts_modified, 1u); // the one contact, inside the region
  world.cycle(sc.stages[1].steps);

  const auto contacts = world.ball_ball_contacts();
  ASSERT_EQ(contacts.size(), 2u);
  for (const ContactView& v : contacts) {
    const std::int64_t a = std::min(p.id[v.i], p.id[v.j]), b = std::max(p.id[v.i], p.id[v.j]);
    const ContactProperties& props = world.property_set(v.properties);
    if (a == 1 && b == 2) { // old: keeps its adhesion, modified friction
      EXPECT_EQ(props.attraction_force_N, 1e-5);
      EXPECT_EQ(props.friction, 0.4);
    } else { // new (2-3): the stage's defaults, outside the region
      EXPECT_EQ(a, 2);
      EXPECT_EQ(b, 3);
      EXPECT_EQ(props.attraction_force_N, 0.0);
      EXPECT_EQ(props.friction, 0.0);
      EXPECT_EQ(props.rolling_friction, 0.16);
    }
  }
}

TEST(Vtk, EmptyWorldWritesValidFiles) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("centridem_vtk_{}", getpid());
  fs::create_directories(dir);
  World w;
  write_particles_vtu(w, (dir / "p.vtu").string());
  write_contacts_vtp(w, (dir / "c.vtp").string());
  EXPECT_EQ(check_vtu(dir / "p.vtu"), 0u);
  EXPECT_EQ(check_vtp(dir / "c.vtp"), 0u);
  PvdSeries s((dir / "s.pvd").string());
  s.add(0.0, "p.vtu");
  s.add(1e-3, "p.vtu");
  EXPECT_EQ(read_pvd(dir / "s.pvd").size(), 2u);
  fs::remove_all(dir);
}
