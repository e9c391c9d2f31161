// When the neighbour lists are rebuilt: at the start of the step after the
// first one in which a particle has moved more than half the skin from where
// the lists were built (engine/integration.cpp). Within a cycle() call the
// engine measures those distances only when its bound on them (the sum of
// each step's largest move) could fail the test (2026-12-06, issue 18); the
// rebuild must still come at exactly that step, neither later (contacts
// missed) nor earlier. Closed form: a free ball without gravity keeps its
// velocity v (central differences, no force), so after k steps it has moved
// k v dt; with a slower ball beside it, the bound is the fast one's.
#include "engine/world.hpp"

#include <cmath>
#include <gtest/gtest.h>

using namespace centridem;

namespace {

constexpr double kSkin = 1e-4;      // [m]
constexpr double kDt = 1e-6;        // [s]
constexpr double kSpeed = 0.3;      // fast ball [m/s]: 3e-7 m per step
constexpr double kSlowSpeed = 0.05; // [m/s]

// The rebuilds after `steps` steps in one cycle() call from a fresh world.
long rebuilds_after(long steps, double wall_speed = 0.0) {
  WorldSettings s;
  s.threads = 1;
  s.timestep_s = kDt;
  s.neighbour_skin_m = kSkin;
  World w(s);
  ContactProperties p;
  p.effective_modulus_Pa = 1e8;
  p.friction = 0.5;
  w.set_ball_ball_defaults(p);
  w.add_particle({0, 0, 0}, 1e-3, 2650, 0, 1);
  w.add_particle({0, 5e-3, 0}, 1e-3, 2650, 0, 2);
  w.particles_mut().velocity[0] = {kSpeed, 0, 0};
  w.particles_mut().velocity[1] = {0, 0, kSlowSpeed};
  if (wall_speed != 0.0) {
    Wall wall = Wall::plane("far", {0, 0, -0.1}, {0, 0, 1});
    wall.velocity = {0, 0, wall_speed};
    w.add_wall(wall, p);
  }
  w.cycle(steps);
  return w.neighbour_rebuilds();
}

} // namespace

TEST(RebuildTrigger, FirstStepPastHalfTheSkinRebuildsAtTheNextStep) {
  // 2 k v dt > skin first at k = 167 (166: 9.96e-5 m, 167: 1.002e-4 m).
  const long k = static_cast<long>(std::floor(kSkin / (2.0 * kSpeed * kDt))) + 1;
  ASSERT_EQ(k, 167);
  const long first = rebuilds_after(1);
  EXPECT_EQ(first, 1);
  EXPECT_EQ(rebuilds_after(k), first) << "rebuilt before the step after step " << k;
  EXPECT_EQ(rebuilds_after(k + 1), first + 1) << "not rebuilt at the step after step " << k;
  // The next one, a further half skin on (the lists built at the start of
  // step k + 1, the ball then k v dt from its start).
  EXPECT_EQ(rebuilds_after(2 * k), first + 1);
  EXPECT_EQ(rebuilds_after(2 * k + 1), first + 2);
}

TEST(RebuildTrigger, AWallAndABallTogetherASkinApartRebuildAtTheNextStep) {
  // A wall far away moving at 0.6 m/s: ball and wall together cover the skin
  // at 9e-7 m per step, first past it at k = 112 (111: 9.99e-5 m), before the
  // ball alone covers half of it.
  const double wall_speed = 0.6;
  const long k = static_cast<long>(std::floor(kSkin / ((kSpeed + wall_speed) * kDt))) + 1;
  ASSERT_EQ(k, 112);
  EXPECT_EQ(rebuilds_after(k, wall_speed), 1);
  EXPECT_EQ(rebuilds_after(k + 1, wall_speed), 2);
}
