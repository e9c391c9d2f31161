// The command line a user meets first (issue 19): --version; an unknown subcommand or flag
// refused with the nearest real one; ranges written as people write them; an output folder that
// is a file refused with exit 2; `--set KEY=VALUE` and `--check` on run, generate, shear and
// slope (the value lands in the resolved scenario, a misspelt key is named); OpenMP's wait
// chosen by the program (passive beside busy tasks) unless the environment sets one; and the
// benchmark's `--skin` (issue 18).
#include "cli_test_util.hpp"
#include "physics/lanes.hpp"

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <sched.h>
#include <string>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;
using centridem::testutil::run_centridem;
using centridem::testutil::slurp;
using centridem::testutil::TempDir;

std::string ex(const std::string& rel) {
  return (fs::path(CENTRIDEM_SOURCE_DIR) / "examples" / rel).string();
}

// Balls from p.xyzr on a floor, beside a wall at x = -2 mm, 20 steps at 1 g.
constexpr const char* kBallsOnAFloor = R"(
[simulation]
threads = 1
progress_interval_s = 0
[particles]
file = "p.xyzr"
density_kg_m3 = 2633
[contact.ball_ball]
model = "linear"
effective_modulus_Pa = 1e8
[contact.ball_wall]
model = "linear"
effective_modulus_Pa = 1e8
[gravity]
g_level = 1
[[walls]]
name = "floor"
type = "plane"
point_m = [0, 0, 0]
normal = [0, 0, 1]
[[walls]]
name = "left"
type = "plane"
point_m = [-0.002, 0, 0]
normal = [1, 0, 0]
[[stages]]
name = "sit"
steps = 20
)";

bool has(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

// Eight spheres of radius 0.2 mm on a cubic lattice of 1 mm (x, y, z in 1..2
// mm): 12 pairs 1 mm apart (edges), 12 at sqrt(2) mm (face diagonals), 4 at
// sqrt(3) mm; none touching.
fs::path tiny_lattice(const fs::path& dir) {
  std::ofstream f(dir / "tiny.xyzr");
  for (int k = 0; k < 8; ++k)
    f << 1e-3 * (1 + k % 2) << ' ' << 1e-3 * (1 + k / 2 % 2) << ' ' << 1e-3 * (1 + k / 4) << ' '
      << 2e-4 << '\n';
  return dir / "tiny.xyzr";
}

TEST(CommandLine, VersionIsPrinted) {
  TempDir dir("centridem_cli_version");
  const auto r = run_centridem({"--version"}, dir / "log");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output.rfind("centridem 0.", 0), 0u) << r.output;
}

TEST(CommandLine, UnknownSubcommandOrFlagIsRefusedWithTheNearest) {
  TempDir dir("centridem_cli_unknown");
  const auto sub = run_centridem({"slop", "x.toml"}, dir / "log");
  EXPECT_EQ(sub.code, 2) << sub.output;
  EXPECT_TRUE(has(sub.output, "unknown subcommand \"slop\" (did you mean \"slope\"?)"))
      << sub.output;

  const auto none = run_centridem({}, dir / "log");
  EXPECT_EQ(none.code, 2) << none.output;
  EXPECT_TRUE(has(none.output, "give a subcommand: ")) << none.output;
  EXPECT_TRUE(has(none.output, "shear")) << none.output;

  const auto flag = run_centridem({"run", ex("demo_settle.toml"), "--thread", "1"}, dir / "log");
  EXPECT_EQ(flag.code, 2) << flag.output;
  EXPECT_TRUE(has(flag.output, "--thread")) << flag.output;
  EXPECT_TRUE(has(flag.output, "did you mean --threads?")) << flag.output;
}

TEST(CommandLine, RangesReadAsPeopleWriteThem) {
  TempDir dir("centridem_cli_ranges");
  const auto t = run_centridem({"run", ex("demo_settle.toml"), "--threads", "-1"}, dir / "log");
  EXPECT_EQ(t.code, 2) << t.output;
  EXPECT_TRUE(has(t.output, "--threads: -1 is not allowed: a whole number from 0 to 1024"))
      << t.output;
  EXPECT_LT(t.output.size(), 300u) << "no 309-digit bounds: " << t.output;
  const auto p =
      run_centridem({"slope", ex("demo_slope.toml"), "--progress", "nan", "--check"}, dir / "log");
  EXPECT_EQ(p.code, 2) << p.output;
  EXPECT_TRUE(has(p.output, "--progress: nan is not allowed: a number > 0")) << p.output;
  const auto s =
      run_centridem({"slope", ex("demo_slope.toml"), "--scale", "2", "--check"}, dir / "log");
  EXPECT_EQ(s.code, 2) << s.output;
  EXPECT_TRUE(has(s.output, "--scale: 2 is not allowed: a number > 0 and <= 1")) << s.output;
}

TEST(CommandLine, AnOutputFolderThatIsAFileIsBadInput) {
  TempDir dir("centridem_cli_outfile");
  std::ofstream(dir / "taken") << "a file\n";
  const std::string taken = (dir / "taken").string();
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"shear", ex("shear_small.toml"), "--out", taken},
        std::vector<std::string>{"shear", ex("shear_small.toml"), "--out", taken, "--check"},
        std::vector<std::string>{"slope", ex("demo_slope.toml"), "--out", taken, "--check"},
        std::vector<std::string>{"generate", ex("specimens/paper_shear_box.toml"), "--out", taken,
                                 "--check"},
        std::vector<std::string>{"run", ex("demo_settle.toml"), "--out", taken, "--check"}}) {
    const auto r = run_centridem(args, dir / "log", 120);
    EXPECT_EQ(r.code, 2) << args[0] << ": " << r.output;
    EXPECT_TRUE(has(r.output, taken)) << r.output;
  }
}

// --set and --check on each subcommand that reads a scenario: the value is in the resolved
// scenario printed by --check, and a misspelt key is refused naming it and the nearest key.
TEST(CommandLine, SetAndCheckOnEverySubcommand) {
  TempDir dir("centridem_cli_set");
  struct Sub {
    std::string name, scenario, set, expect, bad_key;
  };
  const std::vector<Sub> subs = {{"run", ex("demo_settle.toml"), "simulation.local_damping=0.35",
                                  "local_damping = 0.35", "simulation.local_dampin"},
                                 {"generate", ex("specimens/paper_shear_box.toml"),
                                  "specimen.seed=77", "seed = 77", "specimen.sed"},
                                 {"shear", ex("shear_small.toml"),
                                  "contact.ball_ball.friction=0.31", "friction = 0.31",
                                  "contact.ball_ball.frictio"},
                                 {"slope", ex("demo_slope.toml"), "trial.min_time_s=0.012",
                                  "min_time_s = 0.012", "trial.min_time"}};
  for (const Sub& s : subs) {
    const auto ok =
        run_centridem({s.name, s.scenario, "--set", s.set, "--check"}, dir / "log", 120);
    EXPECT_EQ(ok.code, 0) << s.name << ": " << ok.output;
    EXPECT_TRUE(has(ok.output, s.expect)) << s.name << ": " << ok.output;
    EXPECT_TRUE(has(ok.output, "nothing")) << s.name << ": --check says it ran nothing";
    const auto bad =
        run_centridem({s.name, s.scenario, "--set", s.bad_key + "=1", "--check"}, dir / "log", 120);
    EXPECT_EQ(bad.code, 2) << s.name << ": " << bad.output;
    const std::string last = s.bad_key.substr(s.bad_key.rfind('.') + 1);
    EXPECT_TRUE(has(bad.output, last)) << s.name << ": " << bad.output;
    EXPECT_TRUE(has(bad.output, "did you mean")) << s.name << ": " << bad.output;
  }
}

// A g-level that overflows n g / s (found by the fuzz of issue 17: 1e308 gave NaN positions) is
// refused with its key, as is a size reduction factor that makes a slope's gravity absurd.
TEST(CommandLine, GravityBeyondAnyCentrifugeIsRefused) {
  TempDir dir("centridem_cli_gravity");
  const auto g = run_centridem(
      {"run", ex("demo_settle.toml"), "--set", "gravity.g_level=1e308", "--check"}, dir / "log");
  EXPECT_EQ(g.code, 2) << g.output;
  EXPECT_TRUE(has(g.output, "gravity.g_level")) << g.output;
  EXPECT_TRUE(has(g.output, "(1e6 g)")) << g.output;
  const auto ok = run_centridem(
      {"run", ex("demo_settle.toml"), "--set", "gravity.g_level=1e5", "--check"}, dir / "log");
  EXPECT_EQ(ok.code, 0) << ok.output;
  const auto s = run_centridem(
      {"slope", ex("demo_slope.toml"), "--set", "slope.size_reduction_factor=1e-300", "--check"},
      dir / "log");
  EXPECT_EQ(s.code, 2) << s.output;
  EXPECT_TRUE(has(s.output, "slope.size_reduction_factor")) << s.output;
}

// `run --set` on a real run: the value changes the run and is recorded in its resolved scenario.
TEST(CommandLine, RunSetIsRecordedInTheResolvedScenario) {
  TempDir dir("centridem_cli_run_set");
  std::ofstream(dir / "p.xyzr") << "0 0 0.0005 0.0005\n";
  std::ofstream(dir / "s.toml") << kBallsOnAFloor;
  const auto r = run_centridem({"run", (dir / "s.toml").string(), "--out", (dir / "out").string(),
                                "--set", "gravity.g_level=7"},
                               dir / "log", 120);
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string resolved = slurp(dir / "out" / "scenario.resolved.toml");
  EXPECT_TRUE(has(resolved, "g_level = 7")) << resolved;
}

// Sanity before work (issue 19): a particle line given twice, a particle file written in mm
// (positions and radii: through the walls placed in m; radii alone: every neighbour overlapped),
// and a specimen region in mm are refused with exit 2 and a message that says what is wrong and
// hints at the unit; a density written in g/cm^3 is a warning (density scaling is legitimate).
TEST(CommandLine, MistakesOfUnitAndDuplicatesAreCaughtBeforeWork) {
  TempDir dir("centridem_cli_sanity");

  std::ofstream(dir / "s.toml") << kBallsOnAFloor;
  auto check = [&](const std::string& particles) {
    std::ofstream(dir / "p.xyzr") << particles;
    return run_centridem({"run", (dir / "s.toml").string(), "--check"}, dir / "log", 60);
  };
  // Three balls of 0.5 mm on the floor, 1.5 mm apart: accepted.
  const std::string good = "0 0 0.0005 0.0005\n0.0015 0 0.0005 0.0005\n0.003 0 0.0005 0.0005\n";
  EXPECT_EQ(check(good).code, 0);
  // The first line again at the end: both lines named.
  const auto dup = check(good + "0 0 0.0005 0.0005\n");
  EXPECT_EQ(dup.code, 2) << dup.output;
  EXPECT_TRUE(has(dup.output, "p.xyzr:1 and line 4")) << dup.output;
  EXPECT_TRUE(has(dup.output, "a line given twice")) << dup.output;
  // Everything in mm: the first ball sits 0.5 m up and 0.5 m wide, through the left wall.
  const auto mm = check("0 0 0.5 0.5\n1.5 0 0.5 0.5\n3 0 0.5 0.5\n");
  EXPECT_EQ(mm.code, 2) << mm.output;
  EXPECT_TRUE(has(mm.output, "wall \"left\"")) << mm.output;
  EXPECT_TRUE(has(mm.output, "mm")) << mm.output;
  // Radii alone in mm: neighbours 1.5 mm apart with radii of 0.5 m.
  const auto radii = check("0 0 0.6 0.5\n0.0015 0 0.6 0.5\n");
  EXPECT_EQ(radii.code, 2) << radii.output;
  EXPECT_TRUE(has(radii.output, "radii written in mm")) << radii.output;
  // A density in g/cm^3: a warning, and the check goes on.
  std::ofstream(dir / "p.xyzr") << good;
  const auto density = run_centridem(
      {"run", (dir / "s.toml").string(), "--set", "particles.density_kg_m3=2.633", "--check"},
      dir / "log", 60);
  EXPECT_EQ(density.code, 0) << density.output;
  EXPECT_TRUE(has(density.output, "centridem: warning: particles.density_kg_m3 = 2.633"))
      << density.output;
  EXPECT_TRUE(has(density.output, "g/cm^3")) << density.output;
  // A shear box's region in mm: about 1e12 particles, refused before anything is allocated.
  const auto region =
      run_centridem({"generate", ex("shear_small.toml"), "--set",
                     "specimen.region={lo_m=[0,0,0],hi_m=[6,6,3]}", "--out", (dir / "g").string()},
                    dir / "log", 60);
  EXPECT_EQ(region.code, 2) << region.output;
  EXPECT_TRUE(has(region.output, "specimen.region = 6 x 6 x 3 m")) << region.output;
  EXPECT_TRUE(has(region.output, "mm")) << region.output;
  EXPECT_TRUE(has(region.output, "specimen.max_particles")) << region.output;
  EXPECT_FALSE(fs::exists(dir / "g" / "specimen.vtu"));
}

// Each value of NAME that libgomp prints with OMP_DISPLAY_ENV, in order (once as
// the program loads, once more after its restart for the wait policy).
std::vector<std::string> values_printed(const std::string& out, const std::string& name) {
  std::vector<std::string> found;
  const std::string key = name + " = '";
  for (auto p = out.find(key); p != std::string::npos; p = out.find(key, p + 1)) {
    const auto b = p + key.size();
    found.push_back(out.substr(b, out.find('\'', b) - b));
  }
  return found;
}

// The last GOMP_SPINCOUNT that libgomp prints with OMP_DISPLAY_ENV=verbose: "0" under the
// passive policy, 3000 for centridem's short spin, 300000 or more when the threads spin long.
std::string spin_count(const std::string& out) {
  const std::vector<std::string> v = values_printed(out, "GOMP_SPINCOUNT");
  return v.empty() ? "(not printed)" : v.back();
}

// Beside busy tasks the program's threads wait passively (the choice is made
// from the runnable tasks as it starts: here this test's own spinning
// threads, one per CPU, keep the machine busy). A user's OMP_WAIT_POLICY or
// GOMP_SPINCOUNT is kept. The other branch, the short spin on an idle
// machine, cannot be arranged under a parallel ctest; docs/results/bench.md
// has its measurement.
TEST(CommandLine, OpenMPWaitsPassivelyBesideBusyTasksAndKeepsTheUsersSetting) {
  TempDir dir("centridem_cli_wait");
  std::atomic<bool> stop{false};
  std::vector<std::thread> busy;
  for (unsigned k = 0; k < std::max(1u, std::thread::hardware_concurrency()); ++k)
    busy.emplace_back([&] {
      while (!stop.load(std::memory_order_relaxed)) {
      }
    });
  const auto def = run_centridem({"--version"}, dir / "log", 60,
                                 {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "OMP_DISPLAY_ENV=verbose"});
  stop = true;
  for (std::thread& t : busy) t.join();
  EXPECT_EQ(def.code, 0) << def.output;
  EXPECT_EQ(spin_count(def.output), "0") << def.output;
  const auto active = run_centridem({"--version"}, dir / "log", 60,
                                    {"OMP_WAIT_POLICY=active", "OMP_DISPLAY_ENV=verbose"});
  EXPECT_EQ(active.code, 0) << active.output;
  EXPECT_NE(spin_count(active.output), "0") << active.output;
  EXPECT_NE(spin_count(active.output), "(not printed)") << active.output;
  const auto own =
      run_centridem({"--version"}, dir / "log", 60,
                    {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT=1234", "OMP_DISPLAY_ENV=verbose"});
  EXPECT_EQ(own.code, 0) << own.output;
  EXPECT_EQ(spin_count(own.output), "1234") << own.output;
  // The benchmark reports the wait it ran with.
  const auto bench = run_centridem({"bench", "--packing", tiny_lattice(dir.path()).string(),
                                    "--steps", "2", "--warmup", "0", "--threads", "1"},
                                   dir / "log", 60, {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT=1234"});
  EXPECT_EQ(bench.code, 0) << bench.output;
  EXPECT_TRUE(bench.output.find("openmp_wait: GOMP_SPINCOUNT=1234\n") != std::string::npos)
      << bench.output;
}

// A user who binds threads (OMP_PROC_BIND, OMP_PLACES) keeps every place
// through the restart that sets the wait policy: libgomp binds the first
// thread to the first place as the program loads, and before the fix the
// restarted program saw one CPU and ran all its threads there.
TEST(CommandLine, ThreadBindingKeepsEveryPlaceThroughTheRestart) {
  cpu_set_t mask;
  ASSERT_EQ(::sched_getaffinity(0, sizeof mask, &mask), 0);
  if (CPU_COUNT(&mask) < 2) GTEST_SKIP() << "needs two CPUs to bind to";
  TempDir dir("centridem_cli_bind");
  const auto r = run_centridem({"--version"}, dir / "log", 60,
                               {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "OMP_PROC_BIND=spread",
                                "OMP_PLACES=threads", "OMP_DISPLAY_ENV=true"});
  EXPECT_EQ(r.code, 0) << r.output;
  const std::vector<std::string> places = values_printed(r.output, "OMP_PLACES");
  ASSERT_EQ(places.size(), 2u) << "loaded, then restarted once:\n" << r.output;
  EXPECT_EQ(places.back(), places.front()) << r.output;
  EXPECT_NE(places.back().find(','), std::string::npos) << "two places or more: " << r.output;
  EXPECT_EQ(r.output.find("Number of places reduced"), std::string::npos) << r.output;
}

// A speed means little without the machine that made it: the benchmark names
// the CPU (/proc/cpuinfo's model name, read here too) and the SIMD lanes the
// contact law ran in (this build's ContactLanes).
TEST(CommandLine, BenchNamesTheCpuAndTheSimdLanes) {
  TempDir dir("centridem_cli_bench_cpu");
  const auto bench = run_centridem({"bench", "--packing", tiny_lattice(dir.path()).string(),
                                    "--steps", "2", "--warmup", "0", "--threads", "1"},
                                   dir / "log");
  ASSERT_EQ(bench.code, 0) << bench.output;
  std::string model = "unknown";
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);)
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find_first_not_of(" \t", line.find(':') + 1));
      break;
    }
  EXPECT_NE(bench.output.find("\ncpu: " + model + "\n"), std::string::npos) << bench.output;
  const std::string simd = std::string("\nsimd: ") + centridem::ContactLanes::arch_type::name() +
                           ", " + std::to_string(centridem::ContactLanes::size) + " doubles\n";
  EXPECT_NE(bench.output.find(simd), std::string::npos) << simd << bench.output;
}

// `bench --skin` sets the reach of the neighbour lists: pairs within r_i + r_j
// + skin are listed, so on the lattice the entry count steps from none (the
// default skin, half the radius: reach 0.5 mm) to the 12 edges (reach 1.1 mm)
// and then the 12 face diagonals too (reach 1.5 mm); 0 is refused.
TEST(CommandLine, BenchSkinSetsTheReachOfTheNeighbourLists) {
  TempDir dir("centridem_cli_bench_skin");
  const std::string packing = tiny_lattice(dir.path()).string();
  const auto entries = [&](std::vector<std::string> extra, const std::string& want_skin) {
    std::vector<std::string> args{"bench",    "--packing", packing,     "--steps", "2",
                                  "--warmup", "0",         "--threads", "1"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_centridem(args, dir / "log");
    EXPECT_EQ(r.code, 0) << r.output;
    EXPECT_TRUE(has(r.output, "skin_m: " + want_skin + "\n")) << r.output;
    const std::string key = "neighbour_entries_per_particle: ";
    const std::size_t at = r.output.find(key);
    return at == std::string::npos ? -1.0 : std::stod(r.output.substr(at + key.size()));
  };
  EXPECT_DOUBLE_EQ(entries({}, "0.0001"), 0.0);
  EXPECT_DOUBLE_EQ(entries({"--skin", "7e-4"}, "0.0007"), 12.0 / 8.0);
  EXPECT_DOUBLE_EQ(entries({"--skin", "1.1e-3"}, "0.0011"), 24.0 / 8.0);
  const auto zero = run_centridem({"bench", "--packing", packing, "--skin", "0"}, dir / "log");
  EXPECT_EQ(zero.code, 2) << zero.output;
  EXPECT_TRUE(has(zero.output, "--skin: 0 is not allowed: a number > 0 and <= 0.01"))
      << zero.output;
}

} // namespace
