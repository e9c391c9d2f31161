// Runs that blow up (base/errors.hpp: InstabilityError, exit code 3): an
// overlap beyond max_overlap_fraction of the smaller radius (ball-ball and
// ball-wall) and a non-finite position. The World names the particles, the
// step and a likely cause; `centridem run` prints it after
// "centridem: unstable: " and exits with 3.
//
// Closed form used: a ball of mass m resting on a soft floor (kn = pi R E*)
// under gravity a sinks to the overlap m a/kn; with m a/kn > 2 x 0.5 R
// (the dynamic overshoot reaches twice the static overlap) it must pass the
// guard 0.5 R, so the run is stopped within the first half period
// pi sqrt(m/kn) of the contact.
#include "base/errors.hpp"
#include "cli_test_util.hpp"
#include "engine/world.hpp"
#include "physics/contact_properties.hpp"
#include "scenario_fixtures.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <numbers>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace centridem {
namespace {

ContactProperties soft(double E) {
  ContactProperties p;
  p.model = ContactModel::linear;
  p.effective_modulus_Pa = E;
  p.friction = 0.5;
  return p;
}

std::string message_of(World& w, long steps) {
  try {
    w.cycle(steps);
  } catch (const InstabilityError& e) {
    return e.what();
  }
  return {};
}

// Two balls pushed into each other by opposite applied forces, far beyond
// what their soft contact carries: InstabilityError naming both ids, the
// step and the likely cause; the guard trips at 0.5 R (default).
TEST(Instability, BallBallOverlapBeyondTheGuard) {
  WorldSettings s;
  s.threads = 1;
  World w(s);
  w.set_ball_ball_defaults(soft(1e5));
  const double R = 1e-3;
  w.add_particle({0, 0, 0}, R, 2650, 0, 7);
  w.add_particle({2 * R, 0, 0}, R, 2650, 0, 9);
  const double kn = std::numbers::pi * R * R * 1e5 / (2 * R);
  const double F = 10.0 * kn * R; // static overlap 10 R: no equilibrium below the guard
  w.particles_mut().applied_force[*w.index_of(7)] = {F, 0, 0};
  w.particles_mut().applied_force[*w.index_of(9)] = {-F, 0, 0};
  w.set_fixed_timestep(0.02 * w.critical_timestep()); // resolves the approach
  const std::string msg = message_of(w, 100000);
  ASSERT_FALSE(msg.empty()) << "no InstabilityError";
  EXPECT_NE(msg.find("balls id 7 and id 9"), std::string::npos) << msg;
  EXPECT_NE(msg.find(fmt::format("unstable at step {}", w.step_count())), std::string::npos) << msg;
  EXPECT_NE(msg.find("Likely cause"), std::string::npos) << msg;
  EXPECT_GT(w.step_count(), 0);
  EXPECT_GT(w.measure().max_overlap_ratio, 0.5);
}

// A ball on a soft floor under 1000 g (static overlap m a/kn = 17 R),
// automatic timestep: stopped naming the ball and the wall, at the default
// guard 0.5 R and at a guard raised to 2 R, each passed when it trips.
TEST(Instability, BallWallOverlapBeyondTheGuard) {
  const double R = 0.5e-3, E = 1e3, rho = 2633, a = 1000 * 9.80665;
  const double m = 4.0 / 3.0 * std::numbers::pi * R * R * R * rho;
  const double kn = std::numbers::pi * R * E;
  ASSERT_GT(m * a / kn, 2 * 2.0 * R) << "the closed form says it must pass both guards";
  for (const double guard : {0.5, 2.0}) {
    WorldSettings s;
    s.threads = 1;
    s.max_overlap_fraction = guard;
    World w(s);
    w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), soft(E));
    w.add_particle({0, 0, R}, R, rho, 0, 3);
    BodyField g;
    g.gravity_m_s2 = {0, 0, -a};
    w.set_body_field(g);
    const std::string msg = message_of(w, 100000);
    ASSERT_FALSE(msg.empty()) << "no InstabilityError, guard " << guard;
    EXPECT_NE(msg.find("ball id 3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("and a wall"), std::string::npos) << msg;
    EXPECT_NE(msg.find(fmt::format("by more than {} of the smaller radius", guard)),
              std::string::npos)
        << msg;
    const double overlap = R - w.particles().position[0].z;
    EXPECT_GT(overlap, guard * R);
    EXPECT_LT(w.time(), std::sqrt(2.0 * 2.0 * guard * R / a) + std::numbers::pi * std::sqrt(m / kn))
        << "stopped late";
  }
}

// An infinite force (an applied force that overflows the velocity) gives a
// non-finite position: InstabilityError naming the particle and the step.
TEST(Instability, NonFinitePositionNamesTheParticle) {
  WorldSettings s;
  s.threads = 1;
  World w(s);
  w.set_ball_ball_defaults(soft(1e6));
  w.add_particle({0, 0, 0}, 1e-3, 2650, 0, 1);
  w.add_particle({0.1, 0, 0}, 1e-3, 2650, 0, 42);
  w.particles_mut().applied_force[*w.index_of(42)] = {1e308, 0, 0};
  const std::string msg = message_of(w, 10);
  ASSERT_FALSE(msg.empty()) << "no InstabilityError";
  EXPECT_NE(msg.find("particle id 42"), std::string::npos) << msg;
  EXPECT_NE(msg.find("non-finite"), std::string::npos) << msg;
  EXPECT_NE(msg.find(fmt::format("unstable at step {}", w.step_count())), std::string::npos) << msg;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// `centridem run` on the ball of BallWallOverlapBeyondTheGuard (soft floor,
// 1000 g, automatic timestep): exit code 3, stderr "centridem: unstable: "
// naming the ball, the wall, the step and the likely cause.
TEST(Instability, RunCommandExitsWith3) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("centridem_unstable_{}", ::getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "ball.xyzr") << "0 0 0.0005 0.0005\n";
  std::ofstream(dir / "s.toml") << R"(
[simulation]
threads = 1
progress_interval_s = 0

[particles]
file = "ball.xyzr"
density_kg_m3 = 2633

[contact.ball_ball]
model = "linear"
effective_modulus_Pa = 1e3

[contact.ball_wall]
model = "linear"
effective_modulus_Pa = 1e3
friction = 0.5

[gravity]
g_level = 1000

[[walls]]
name = "floor"
type = "plane"
point_m = [0, 0, 0]
normal = [0, 0, 1]

[[stages]]
name = "sink"
steps = 100000
)";
  const std::string cmd = fmt::format("'{}' run '{}' --out '{}' > '{}' 2> '{}'", CENTRIDEM_BINARY,
                                      (dir / "s.toml").string(), (dir / "out").string(),
                                      (dir / "stdout.txt").string(), (dir / "stderr.txt").string());
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3) << slurp(dir / "stderr.txt") << slurp(dir / "stdout.txt");
  const std::string err = slurp(dir / "stderr.txt");
  EXPECT_EQ(err.rfind("centridem: unstable: unstable at step ", 0), 0u) << err;
  EXPECT_NE(err.find("ball id 1"), std::string::npos) << err;
  EXPECT_NE(err.find("and a wall"), std::string::npos) << err;
  EXPECT_NE(err.find("Likely cause"), std::string::npos) << err;
  fs::remove_all(dir);
}

// The step named in "unstable at step N", or -1.
long unstable_step(const std::string& out) {
  const auto p = out.find("unstable at step ");
  return p == std::string::npos ? -1 : std::atol(out.c_str() + p + 17);
}

// A small shear box (about 1,000 particles, the box of examples/shear_small.toml) whose contacts
// turn 300,000 times softer when shearing starts (`--set` of shear.during_shear): under 100 kPa
// the servo presses the grains into each other beyond the overlap guard. The run must stop with
// exit 3 naming the particles, the step and the likely cause, keep the checkpoint written at the
// start of shearing, and `--resume` from it must reach the same instability at the same step
// (the checkpoint is intact and the run deterministic), with the two threads it was started with.
// (30,000 times softer, as this test had it until 2026-12-04, the guard tripped within the
// shearing or not depending on the last bits of the run: with the neighbour skin fixed at 20 and
// 5 um it tripped, at 100 um and with an automatic skin tried that day it did not. 300,000 times
// softer it tripped with the automatic skin, 100 um, 20 um and the engine as it is; 5 um was not
// tried at that softening.)
TEST(Instability, ShearCommandExitsWith3AndKeepsAResumableCheckpoint) {
  testutil::TempDir dir("centridem_unstable_shear");
  std::ofstream(dir / "box.toml") << testutil::kSmallShearBox;
  const std::string out = (dir / "out").string();
  const auto first =
      testutil::run_centridem({"shear", (dir / "box.toml").string(), "--out", out, "--threads", "2",
                               "--set", "shear.during_shear={effective_modulus_Pa=1e3}"},
                              dir / "first.log", 600);
  ASSERT_EQ(first.code, 3) << first.output;
  EXPECT_NE(first.output.find("centridem: unstable: "), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("Likely cause"), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("ball"), std::string::npos) << first.output;
  const long step = unstable_step(first.output);
  ASSERT_GT(step, 0) << first.output;
  const fs::path ckpt = dir / "out" / "shear_100kPa.checkpoint.bin";
  ASSERT_TRUE(fs::exists(ckpt)) << "the checkpoint written before the instability is gone";

  const auto again = testutil::run_centridem({"shear", "--resume", out}, dir / "again.log", 600);
  EXPECT_EQ(again.code, 3) << again.output;
  EXPECT_NE(again.output.find("resuming"), std::string::npos) << again.output;
  // The resume runs with the threads it was started with (pressures.json), not shear.threads.
  EXPECT_NE(again.output.find("2 thread(s) per run"), std::string::npos) << again.output;
  EXPECT_EQ(unstable_step(again.output), step) << again.output;
}

// The tiny slope of the kill-and-resume tests, its contacts made 300,000 times softer after the
// cut (`--set trial.after_cut`, which replaces the file's after-cut patch): the slope sinks into
// itself beyond the overlap guard. Exit 3 with the message, the trial's checkpoint (every 1,000
// steps) kept, and `--resume` reaching the same instability at the same step.
TEST(Instability, SlopeCommandExitsWith3AndKeepsAResumableCheckpoint) {
  testutil::TempDir dir("centridem_unstable_slope");
  std::ofstream(dir / "tiny.toml") << testutil::kTinySlope;
  const std::string out = (dir / "out").string(), cache = (dir / "cache").string();
  const auto first =
      testutil::run_centridem({"slope", (dir / "tiny.toml").string(), "--out", out, "--cache",
                               cache, "--set", "trial.after_cut={effective_modulus_Pa=1e3}"},
                              dir / "first.log", 600);
  ASSERT_EQ(first.code, 3) << first.output;
  EXPECT_NE(first.output.find("centridem: unstable: "), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("Likely cause"), std::string::npos) << first.output;
  const long step = unstable_step(first.output);
  ASSERT_GT(step, 0) << first.output;
  ASSERT_TRUE(fs::exists(dir / "out" / "trial_20g" / "checkpoint.bin"))
      << "the checkpoint written before the instability is gone";

  const auto again = testutil::run_centridem({"slope", "--resume", out}, dir / "again.log", 600);
  EXPECT_EQ(again.code, 3) << again.output;
  EXPECT_NE(again.output.find("resuming"), std::string::npos) << again.output;
  EXPECT_EQ(unstable_step(again.output), step) << again.output;
}

} // namespace
} // namespace centridem
