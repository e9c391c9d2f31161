// Long runs that survive (issue 6), end to end with the `centridem slope`
// binary on a tiny slope trial that checkpoints every 1,000 steps:
//   - killed with SIGKILL at 5 random moments, each time resumed with
//     --resume: the checkpoint is never corrupt and the trial ends bit for bit
//     where an uninterrupted run ends (final_state.csv, checks.csv);
//   - a checkpoint with one flipped byte is refused (exit 2, a clear message);
//   - SIGINT: checkpoint, exit code 130 and a message naming --resume; the
//     resumed run ends like the uninterrupted one.
#include "cli_test_util.hpp"
#include "scenario_fixtures.hpp"

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

using centridem::testutil::Child;
using centridem::testutil::kTinySlope;
using centridem::testutil::slurp;
using centridem::testutil::wait_for;

// Starts `centridem slope ARGS` with stdout and stderr into `log`.
Child start(const std::vector<std::string>& args, const fs::path& log) {
  std::vector<std::string> all = {"slope"};
  all.insert(all.end(), args.begin(), args.end());
  return centridem::testutil::start_centridem(all, log);
}

class KillResume : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           fmt::format("centridem_kill_{}_{}", ::getpid(),
                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ / "tiny.toml") << kTinySlope;
    // The uninterrupted reference.
    const Child ref = start({(dir_ / "tiny.toml").string(), "--out", (dir_ / "ref").string(),
                             "--cache", (dir_ / "cache").string()},
                            dir_ / "ref.log");
    ASSERT_EQ(wait_for(ref), 0) << slurp(dir_ / "ref.log");
    ref_state_ = slurp(dir_ / "ref" / "trial_20g" / "final_state.csv");
    ref_checks_ = slurp(dir_ / "ref" / "trial_20g" / "checks.csv");
    ASSERT_GT(ref_state_.size(), 1000u);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::vector<std::string> fresh(const fs::path& out) const {
    return {(dir_ / "tiny.toml").string(), "--out", out.string(), "--cache",
            (dir_ / "cache").string()};
  }
  fs::path dir_;
  std::string ref_state_, ref_checks_;
};

TEST_F(KillResume, SigkillAtRandomMomentsNeverLosesTheRun) {
  const fs::path out = dir_ / "killed";
  std::mt19937_64 rng(20261122);
  std::uniform_int_distribution<int> delay_ms(0, 300);
  const fs::path ck = out / "trial_20g" / "checkpoint.bin";
  auto stamp = [&] {
    std::error_code ec;
    const auto t = fs::last_write_time(ck, ec);
    return ec ? fs::file_time_type::min() : t;
  };
  int kills = 0, checkpoints_seen = 0;
  for (int k = 0; k < 5; ++k) {
    // Start, or resume once the run folder exists.
    const bool started = fs::exists(out / "campaign.json");
    const auto before = stamp();
    const Child r = start(started ? std::vector<std::string>{"--resume", out.string()} : fresh(out),
                          dir_ / fmt::format("kill{}.log", k));
    // Kill at a random moment after this process wrote a checkpoint (so each
    // round makes progress however loaded the machine is).
    for (int i = 0; i < 6000 && stamp() == before && !fs::exists(out / "trial_20g" / "result.json");
         ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (stamp() != before) ++checkpoints_seen;
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    ::kill(r.pid, SIGKILL);
    const int code = wait_for(r);
    if (code == 0) break; // finished before the kill
    ASSERT_EQ(code, 128 + SIGKILL) << slurp(dir_ / fmt::format("kill{}.log", k));
    ++kills;
  }
  EXPECT_EQ(kills, 5) << "the trial finished before five kills; lengthen it";
  EXPECT_GE(checkpoints_seen, 4);
  // Finish from the last checkpoint.
  const Child last = start({"--resume", out.string()}, dir_ / "last.log");
  ASSERT_EQ(wait_for(last), 0) << slurp(dir_ / "last.log");
  EXPECT_EQ(slurp(out / "trial_20g" / "final_state.csv"), ref_state_);
  EXPECT_EQ(slurp(out / "trial_20g" / "checks.csv"), ref_checks_);
  EXPECT_FALSE(fs::exists(out / "trial_20g" / "checkpoint.bin"));
}

TEST_F(KillResume, FlippedByteInTheCheckpointIsRefused) {
  const fs::path out = dir_ / "flip";
  const Child r = start(fresh(out), dir_ / "flip.log");
  const fs::path ck = out / "trial_20g" / "checkpoint.bin";
  // The first checkpoint comes 1,000 steps into the trial: a second or two in Release, much
  // later under the sanitizers; wait for it (up to 5 minutes), then kill.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (!fs::exists(ck) && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(r.pid, SIGKILL);
  wait_for(r);
  ASSERT_TRUE(fs::exists(ck)) << slurp(dir_ / "flip.log");
  std::string bytes = slurp(ck);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x10);
  std::ofstream(ck, std::ios::binary | std::ios::trunc) << bytes;
  const Child again = start({"--resume", out.string()}, dir_ / "flip2.log");
  EXPECT_EQ(wait_for(again), 2);
  const std::string log = slurp(dir_ / "flip2.log");
  EXPECT_NE(log.find("checkpoint.bin"), std::string::npos) << log;
  EXPECT_NE(log.find("checksum"), std::string::npos) << log;
}

TEST_F(KillResume, SigintWritesACheckpointAndTheRunResumes) {
  const fs::path out = dir_ / "int";
  const Child r = start(fresh(out), dir_ / "int.log");
  // Interrupt once the trial is cycling (its folder exists).
  for (int i = 0; i < 500 && !fs::exists(out / "trial_20g" / "log.txt"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  ::kill(r.pid, SIGINT);
  const int code = wait_for(r);
  const std::string log = slurp(dir_ / "int.log");
  if (code == 0) GTEST_SKIP() << "finished before the interrupt";
  EXPECT_EQ(code, 130) << log;
  EXPECT_NE(log.find("--resume"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(out / "trial_20g" / "checkpoint.bin"));
  const Child again = start({"--resume", out.string()}, dir_ / "int2.log");
  ASSERT_EQ(wait_for(again), 0) << slurp(dir_ / "int2.log");
  EXPECT_EQ(slurp(out / "trial_20g" / "final_state.csv"), ref_state_);
}

} // namespace

// The summary says how the run was started and the critical g in words (no
// placeholder, no raw JSON; issue 19).
TEST_F(KillResume, SummarySaysTheCommandAndTheCriticalGInWords) {
  const std::string md = slurp(dir_ / "ref" / "summary.md");
  const std::string command = "Command: `centridem slope " + (dir_ / "tiny.toml").string() +
                              " --out " + (dir_ / "ref").string() + " --cache " +
                              (dir_ / "cache").string() + "`";
  EXPECT_NE(md.find(command), std::string::npos) << md;
  const auto at = md.find("Critical g: ");
  ASSERT_NE(at, std::string::npos) << md;
  const std::string line = md.substr(at, md.find('\n', at) - at);
  EXPECT_EQ(line.find('{'), std::string::npos) << line;
  EXPECT_EQ(line, "Critical g: at or below 20 g: the lowest level tried already fails.")
      << "the tiny slope (no friction after the cut) fails at 20 g, its only level";
  // The wall time, of the command and of its one trial.
  const std::regex wall(R"(Wall time: [0-9.]+ (s|min|h) for this command \(1 trial\(s\) at once; )"
                        R"(each trial's own: 20 g: [0-9.]+ (s|min|h)\)\.)");
  EXPECT_TRUE(std::regex_search(md, wall)) << md;
}
