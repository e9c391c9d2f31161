// Procedures write the particle store between World::cycle calls (placing,
// growing, restoring particles), and the next step must see what they wrote,
// with no rebuild in between: an engine that keeps its own copy of the
// particles for the contact pass (one was tried, 2026-12-04, see
// docs/results/bench.md) must refresh it. Closed form: two fixed balls of radius R overlapping by
// d feel kn d each, kn = pi E* R1 R2/(R1 + R2) (ball-ball deformability,
// DESIGN.md "Physics"), along the line of centres.
#include "physics_test_util.hpp"

#include <gtest/gtest.h>

namespace centridem {
namespace {
using namespace phys_test;

TEST(PhysicsStoreBetweenCycles, BallMovedAndGrownBetweenCallsIsFeltAtTheNextStep) {
  constexpr double R = 1e-3, rho = 2650, E = 1e8, d = 1e-3 * R;
  WorldSettings s;
  s.threads = 1;
  s.timestep_s = 1e-7;
  World w(s);
  w.set_ball_ball_defaults(props(ContactModel::linear, E, 0.5));
  // Neighbours (gap 0.1 R, inside the skin) but not touching.
  w.add_particle({0, 0, 0}, R, rho, 0, 1);
  w.add_particle({2.1 * R, 0, 0}, R, rho, 0, 2);
  for (int k = 0; k < 2; ++k) w.particles_mut().flags[k] = fix_translation | fix_rotation;
  w.cycle(2);
  const std::size_t a = idx(w, 1), b = idx(w, 2);
  ASSERT_EQ(norm(w.particles().force[a]), 0.0);
  const long rebuilds = w.neighbour_rebuilds();

  // Moved into contact by writing the store: overlap d.
  w.particles_mut().position[b].x = 2 * R - d;
  w.cycle(1);
  const double f1 = kn_ball_ball(E, R, R) * d;
  EXPECT_LT(rel(w.particles().force[a], {-f1, 0, 0}, f1), 1e-9)
      << "force on ball 1 " << w.particles().force[a].x << " N, expected " << -f1 << " N";
  EXPECT_LT(rel(w.particles().force[b], {f1, 0, 0}, f1), 1e-9);

  // Ball 1 grown by d/2 by writing the store: overlap 3d/2.
  w.particles_mut().radius[a] = R + 0.5 * d;
  w.cycle(1);
  const double f2 = kn_ball_ball(E, R + 0.5 * d, R) * 1.5 * d;
  EXPECT_LT(rel(w.particles().force[a], {-f2, 0, 0}, f2), 1e-9)
      << "force on ball 1 " << w.particles().force[a].x << " N, expected " << -f2 << " N";
  // No rebuild came between: the copy itself had to be refreshed.
  EXPECT_EQ(w.neighbour_rebuilds(), rebuilds);
}

// The contact pass skips the applied-load arrays while they hold only +0.0,
// found at the start of each cycle() call (2026-12-05, issue 18). Loads set,
// changed and removed between calls must be felt at the next step. Closed
// form: a free sphere without gravity gains v = F dt / m and w = M dt / I per
// step (central differences), and keeps them once the loads are gone.
TEST(PhysicsStoreBetweenCycles, AppliedLoadsSetAndRemovedBetweenCallsAreFeltAtTheNextStep) {
  constexpr double R = 1e-3, rho = 2650, dt = 1e-6;
  WorldSettings s;
  s.threads = 1;
  s.timestep_s = dt;
  World w(s);
  w.set_ball_ball_defaults(props(ContactModel::linear, 1e8, 0.5));
  w.add_particle({0, 0, 0}, R, rho, 0, 1);
  w.cycle(3); // no loads: at rest
  ASSERT_EQ(norm(w.particles().velocity[0]), 0.0);
  const double m = w.particles().mass[0], I = w.particles().inertia[0];
  const Vec3 F{1e-3, -2e-3, 0}, M{0, 0, 3e-9};
  w.particles_mut().applied_force[0] = F;
  w.particles_mut().applied_moment[0] = M;
  w.cycle(2);
  EXPECT_LT(rel(w.particles().velocity[0], 2 * dt / m * F, 2 * dt / m * norm(F)), 1e-12);
  EXPECT_LT(rel(w.particles().spin[0], 2 * dt / I * M, 2 * dt / I * norm(M)), 1e-12);
  EXPECT_LT(rel(w.particles().force[0], F, norm(F)), 1e-15);
  // Only the moment left: the velocity stays, the spin keeps growing.
  w.particles_mut().applied_force[0] = {};
  w.cycle(1);
  EXPECT_LT(rel(w.particles().velocity[0], 2 * dt / m * F, 2 * dt / m * norm(F)), 1e-12);
  EXPECT_LT(rel(w.particles().spin[0], 3 * dt / I * M, 3 * dt / I * norm(M)), 1e-12);
  EXPECT_EQ(norm(w.particles().force[0]), 0.0);
  // Both gone: nothing changes.
  w.particles_mut().applied_moment[0] = {};
  w.cycle(1);
  EXPECT_LT(rel(w.particles().spin[0], 3 * dt / I * M, 3 * dt / I * norm(M)), 1e-12);
  EXPECT_EQ(norm(w.particles().moment[0]), 0.0);
}

} // namespace
} // namespace centridem
