// `centridem run` keeps its work (issue 17), end to end with the binary on a
// small three-stage scenario (216 grains settle in a box, a side wall goes
// and they slump, then they come to rest) that checkpoints at its start and every 7,000 steps:
//   - killed with SIGKILL at 6 random moments (seeded; each after the first
//     checkpoint of its process, so the resumes start in all three stages),
//     each time resumed with --resume: the run ends bit for bit where an uninterrupted run ends
//     (final_state.csv, every double exactly), and its outputs continue
//     without a lost or repeated row or frame (measurements.csv, the stage
//     particle files, the ParaView series and every frame, byte for byte);
//   - SIGINT: a checkpoint, exit code 130, a message naming --resume, status
//     "interrupted" in summary.json; the resumed run ends like the
//     uninterrupted one;
//   - --resume with a scenario, --out or --threads is refused (exit 2, naming
//     it), as is a new run into a folder holding an unfinished one; --resume
//     of a completed run does nothing.
#include "cli_test_util.hpp"

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

const char* kScenario = R"(
[simulation]
local_damping = 0.2
threads = 1
progress_interval_s = 1
checkpoint_interval_min = 0
checkpoint_interval_steps = 7000

[particles]
file = "grains.xyzr"
density_kg_m3 = 2633

[contact.ball_ball]
model = "arrlinear"
effective_modulus_Pa = 10e6
friction = 0.5
rolling_friction = 0.1
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
name = "y0"
type = "plane"
point_m = [0, 0, 0]
normal = [0, 1, 0]
[[walls]]
name = "y1"
type = "plane"
point_m = [0, 0.006, 0]
normal = [0, -1, 0]
[[walls]]
name = "x1"
type = "rectangle"
centre_m = [0.006, 0.003, 0.005]
normal = [-1, 0, 0]
u_direction = [0, 1, 0]
size_m = [0.006, 0.01]

[[stages]]
name = "settle"
steps = 14000
frames_every = 3000
measure_every = 500

[[stages]]
name = "slump"
remove_walls = ["x1"]
contact.ball_ball = { rolling_friction = 0 }
time_s = 0.05
frames_every = 2500
measure_every = 700

[[stages]]
name = "rest"
until_equilibrium = { ratio = 1e-30, max_steps = 8000, check_interval = 500 }
measure_every = 1000
)";

// 6 x 6 x 6 grains of radii 0.33-0.42 mm, jittered off a 1 mm grid (a fixed
// generator: the same file every time).
std::string grains() {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1, 1);
  std::string s;
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i)
        s += fmt::format("{:.9e} {:.9e} {:.9e} {:.9e}\n", 0.0005 + 0.001 * i + 4e-5 * u(rng),
                         0.0005 + 0.001 * j + 4e-5 * u(rng), 0.0006 + 0.001 * k + 4e-5 * u(rng),
                         0.000375 + 0.000045 * u(rng));
  return s;
}

using centridem::testutil::Child;
using centridem::testutil::slurp;
using centridem::testutil::wait_for;

// Starts `centridem run ARGS` with stdout and stderr into `log`.
Child start(const std::vector<std::string>& args, const fs::path& log) {
  std::vector<std::string> all = {"run"};
  all.insert(all.end(), args.begin(), args.end());
  return centridem::testutil::start_centridem(all, log);
}

int run_to_end(const std::vector<std::string>& args, const fs::path& log) {
  return wait_for(start(args, log));
}

// The files of a run folder that must come out byte for byte the same
// (everything but log.txt and summary.json, which hold wall-clock times, and
// scenario.resolved.toml, which names the folder).
std::map<std::string, std::string> outputs(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    const std::string rel = fs::relative(e.path(), dir).string();
    if (rel == "log.txt" || rel == "summary.json" || rel == "scenario.resolved.toml") continue;
    out[rel] = slurp(e.path());
  }
  return out;
}

class RunResume : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / fmt::format("centridem_run_resume_{}", ::getpid());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ / "grains.xyzr") << grains();
    std::ofstream(dir_ / "s.toml") << kScenario;
    // The uninterrupted reference.
    ref_rc_ = run_to_end({(dir_ / "s.toml").string(), "--out", (dir_ / "ref").string()},
                         dir_ / "ref.log");
    if (ref_rc_ == 0) ref_ = outputs(dir_ / "ref");
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  void SetUp() override {
    ASSERT_EQ(ref_rc_, 0) << slurp(dir_ / "ref.log");
    ASSERT_TRUE(ref_.count("final_state.csv"));
    ASSERT_GT(ref_.at("final_state.csv").size(), 216u * 200);
  }
  std::vector<std::string> fresh(const fs::path& out) const {
    return {(dir_ / "s.toml").string(), "--out", out.string()};
  }
  // The folder `out` ended as the reference did.
  void expect_like_reference(const fs::path& out) const {
    const auto got = outputs(out);
    for (const auto& [name, bytes] : ref_) {
      SCOPED_TRACE(name);
      ASSERT_TRUE(got.count(name)) << "missing";
      EXPECT_TRUE(got.at(name) == bytes) << "differs from the uninterrupted run";
    }
    for (const auto& [name, bytes] : got) EXPECT_TRUE(ref_.count(name)) << name << " is extra";
    const auto a = nlohmann::json::parse(slurp(dir_ / "ref" / "summary.json"));
    const auto b = nlohmann::json::parse(slurp(out / "summary.json"));
    EXPECT_EQ(b["status"], "completed");
    ASSERT_EQ(b["stages"].size(), 3u);
    for (std::size_t k = 0; k < 3; ++k)
      for (const char* key : {"first_step", "steps", "end_time_s", "frames", "measurements"})
        EXPECT_EQ(b["stages"][k][key], a["stages"][k][key]) << k << " " << key;
    EXPECT_FALSE(fs::exists(out / "checkpoint.bin"));
  }
  static fs::path dir_;
  static int ref_rc_;
  static std::map<std::string, std::string> ref_;
};

fs::path RunResume::dir_;
int RunResume::ref_rc_ = -1;
std::map<std::string, std::string> RunResume::ref_;

TEST_F(RunResume, SigkillAtRandomMomentsEndsBitForBit) {
  const fs::path out = dir_ / "killed";
  std::mt19937_64 rng(20261117);
  std::uniform_int_distribution<int> delay_ms(0, 100);
  const fs::path ck = out / "checkpoint.bin";
  auto stamp = [&] {
    std::error_code ec;
    const auto t = fs::last_write_time(ck, ec);
    return ec ? fs::file_time_type::min() : t;
  };
  int kills = 0;
  for (int k = 0; k < 6; ++k) {
    const bool started = fs::exists(ck);
    const auto before = stamp();
    const fs::path log = dir_ / fmt::format("kill{}.log", k);
    const Child r =
        start(started ? std::vector<std::string>{"--resume", out.string()} : fresh(out), log);
    // Kill at a random moment after this process wrote a checkpoint (so each
    // round makes progress however loaded the machine is).
    for (int i = 0; i < 6000 && stamp() == before && !fs::exists(out / "final_state.csv"); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    ::kill(r.pid, SIGKILL);
    const int code = wait_for(r);
    if (code == 0) break; // finished before the kill
    ASSERT_EQ(code, 128 + SIGKILL) << slurp(log);
    ++kills;
  }
  EXPECT_EQ(kills, 6) << "the run finished before six kills; lengthen it";
  ASSERT_TRUE(fs::exists(ck));
  const int code = run_to_end({"--resume", out.string()}, dir_ / "last.log");
  ASSERT_EQ(code, 0) << slurp(dir_ / "last.log");
  // Each of the six resumes (five after kills, the last) started later than
  // the one before, and they started in every stage: the log says where.
  std::istringstream log(slurp(out / "log.txt"));
  std::vector<long> resumed_at;
  std::string resumes;
  for (std::string line; std::getline(log, line);)
    if (const auto at = line.find(": from ");
        line.rfind("centridem run --resume", 0) == 0 && at != std::string::npos) {
      resumes += line + "\n";
      resumed_at.push_back(std::stol(line.substr(line.find(" at step ") + 9)));
    }
  ASSERT_EQ(resumed_at.size(), 6u) << resumes;
  for (std::size_t k = 1; k < resumed_at.size(); ++k)
    EXPECT_GT(resumed_at[k], resumed_at[k - 1]) << resumes;
  for (const char* stage : {"stage 0 settle", "stage 1 slump", "stage 2 rest"})
    EXPECT_NE(resumes.find(stage), std::string::npos) << stage << " never resumed:\n" << resumes;
  if (const char* show = std::getenv("CENTRIDEM_SHOW_RESUMES"); show && *show)
    fmt::print("{}", resumes);
  expect_like_reference(out);
}

TEST_F(RunResume, SigintWritesACheckpointAndTheRunResumes) {
  const fs::path out = dir_ / "int";
  const fs::path ck = out / "checkpoint.bin";
  const Child r = start(fresh(out), dir_ / "int.log");
  // Interrupt once the run is cycling (its first checkpoint is there).
  for (int i = 0; i < 3000 && !fs::exists(ck); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ::kill(r.pid, SIGINT);
  const int code = wait_for(r);
  const std::string log = slurp(dir_ / "int.log");
  if (code == 0) GTEST_SKIP() << "finished before the interrupt";
  EXPECT_EQ(code, 130) << log;
  EXPECT_NE(log.find("centridem: interrupted: stopped by signal 2"), std::string::npos) << log;
  EXPECT_NE(log.find("`centridem run --resume " + out.string() + "`"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(ck));
  EXPECT_EQ(nlohmann::json::parse(slurp(out / "summary.json"))["status"], "interrupted");

  // A new run into the folder is refused while it holds an unfinished run.
  EXPECT_EQ(run_to_end(fresh(out), dir_ / "again.log"), 2);
  EXPECT_NE(slurp(dir_ / "again.log").find("--out = " + out.string() + ": holds an unfinished run"),
            std::string::npos)
      << slurp(dir_ / "again.log");

  ASSERT_EQ(run_to_end({"--resume", out.string()}, dir_ / "int2.log"), 0)
      << slurp(dir_ / "int2.log");
  expect_like_reference(out);

  // Once completed, --resume has nothing to do.
  EXPECT_EQ(run_to_end({"--resume", out.string()}, dir_ / "int3.log"), 0);
  EXPECT_NE(slurp(dir_ / "int3.log").find("completed earlier"), std::string::npos);
}

TEST_F(RunResume, ResumeWithAScenarioOrOtherFlagsIsRefused) {
  const fs::path ref = dir_ / "ref";
  struct Case {
    std::vector<std::string> args;
    std::string names;
  };
  const std::vector<Case> cases = {
      {{(dir_ / "s.toml").string(), "--resume", ref.string()}, "scenario = "},
      {{"--resume", ref.string(), "--out", (dir_ / "x").string()}, "--out = "},
      {{"--resume", ref.string(), "--threads", "2"}, "--threads = 2"},
      {{"--resume", (dir_ / "nowhere").string()}, "--resume = "},
      {{}, "scenario = (missing)"},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const fs::path log = dir_ / fmt::format("refused{}.log", k);
    EXPECT_EQ(run_to_end(cases[k].args, log), 2) << slurp(log);
    const std::string msg = slurp(log);
    EXPECT_EQ(msg.rfind("centridem: error: " + cases[k].names, 0), 0u) << msg;
  }
  EXPECT_FALSE(fs::exists(dir_ / "x"));
}

} // namespace
