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

} // namespace
} // namespace centridem
