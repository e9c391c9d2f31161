// Ball-wall contacts go through the law in SIMD batches (engine/contact_pass.cpp,
// the wall stage), and a batch may hold contacts with different walls, each
// with its own properties; every lane must get its own wall's law. Closed
// form: a ball at rest pressed into a plane wall by the overlap d = R - h (h
// the distance of its centre from the plane) feels kn d along the wall's
// normal, kn = pi R E* (ball-wall deformability, DESIGN.md "Physics"), and no
// shear (no relative motion).
#include "physics_test_util.hpp"

#include "engine/contacts.hpp"

#include <gtest/gtest.h>

#include <string>

namespace centridem {
namespace {
using namespace phys_test;

TEST(PhysicsWallContacts, BallsOnTwoWallsOfDifferentStiffnessEachFeelTheirOwnWall) {
  constexpr double R = 1e-3, rho = 2650, E_floor = 1e8, E_side = 3e8;
  constexpr int n = 20; // more than a batch (8 lanes with AVX-512), floor and side mixed in each
  WorldSettings s;
  s.threads = 1;
  s.timestep_s = 1e-7;
  World w(s);
  w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), props(ContactModel::linear, E_floor, 0.5));
  w.add_wall(Wall::plane("x0", {0, 0, 0}, {1, 0, 0}), props(ContactModel::linear, E_side, 0.5));
  // A row of balls along y, 3R apart (no ball-ball contacts), each sunk into
  // the floor by 1-4e-3 R; every other one pressed into the side wall too.
  for (int k = 0; k < n; ++k) {
    const double sink = (1 + k % 4) * 1e-3 * R;
    const double x = k % 2 == 0 ? R - (1 + k % 3) * 1e-3 * R : 2 * R;
    w.add_particle({x, 3 * R * k, R - sink}, R, rho, 0, k + 1);
  }
  for (int k = 0; k < n; ++k) w.particles_mut().flags[k] = fix_translation | fix_rotation;
  w.cycle(1);

  EXPECT_EQ(w.walls()[0].contact_count, n);
  EXPECT_EQ(w.walls()[1].contact_count, n / 2);
  const ParticleStore& P = w.particles();
  for (int k = 0; k < n; ++k) {
    const std::size_t i = idx(w, k + 1);
    const Vec3 x = P.position[i];
    const double fz = kn_ball_wall(E_floor, R) * (R - x.z);
    const double fx = k % 2 == 0 ? kn_ball_wall(E_side, R) * (R - x.x) : 0.0;
    const Vec3 expected{fx, 0.0, fz};
    EXPECT_LT(rel(P.force[i], expected, norm(expected)), 1e-12)
        << "ball " << k << ": force (" << P.force[i].x << ", " << P.force[i].y << ", "
        << P.force[i].z << ") N, expected (" << fx << ", 0, " << fz << ") N";
  }
}

// A ball with more ball-wall entries than the wall stage holds
// (kContactStageSize, engine/contacts.hpp) goes through it in pieces, its sums
// carried across them. Closed form: N coincident floors, each sunk into the
// ball by d: N kn d upwards on the ball, kn d down on each floor. A piece left
// out or added twice moves the ball's force by kn d or more.
TEST(PhysicsWallContacts, BallOnMoreWallsThanTheStageHoldsFeelsEveryOne) {
  constexpr double R = 1e-3, rho = 2650, E = 1e8, d = 2e-3 * R;
  constexpr int walls = static_cast<int>(kContactStageSize) + 5;
  WorldSettings s;
  s.threads = 1;
  s.timestep_s = 1e-7;
  World w(s);
  for (int k = 0; k < walls; ++k)
    w.add_wall(Wall::plane("floor" + std::to_string(k), {0, 0, 0}, {0, 0, 1}),
               props(ContactModel::linear, E, 0.5));
  w.add_particle({0, 0, R - d}, R, rho, 0, 1);
  w.particles_mut().flags[0] = fix_translation | fix_rotation;
  w.cycle(1);

  const double f = kn_ball_wall(E, R) * (R - w.particles().position[0].z); // one floor [N]
  for (int k = 0; k < walls; ++k) {
    ASSERT_EQ(w.walls()[k].contact_count, 1u) << "floor " << k;
    ASSERT_LT(rel(w.walls()[k].force, {0, 0, -f}, f), 1e-12) << "floor " << k;
  }
  const Vec3 expected{0, 0, walls * f};
  EXPECT_LT(rel(w.particles().force[0], expected, norm(expected)), 1e-12)
      << "force on the ball " << w.particles().force[0].z << " N, expected " << expected.z << " N";
}

} // namespace
} // namespace centridem
