// Acceptance 7: a settled column in a box. At static equilibrium the sum of
// the external forces on the balls is zero, so the vertical forces the walls
// carry add up to the total weight sum m g. The side walls are frictionless
// planes with horizontal normals: their contact forces are purely normal,
// i.e. horizontal, so they carry no vertical share and the floor alone
// carries the weight: floor.force.z = -sum m g (the force the balls exert on
// the floor points down). Source: statics (Newton's first law for the whole
// assembly); DESIGN.md "Physics" for the contact law.
#include "physics_test_util.hpp"
#include "procedures/paper_material.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {
using namespace phys_test;

// 300 spheres, radii 0.4-0.6 mm, in a 6 mm x 6 mm box, gravity 9.81, local
// damping 0.7, cycled to a mean unbalanced-force ratio below 1e-5: the
// floor reaction equals the weight within 0.5 %; side walls carry less than
// 1e-12 of the weight vertically.
TEST(PhysicsSettledColumn, FloorCarriesTheWeight) {
  const double r = 0.5e-3, L = 6e-3, g = 9.81;
  const double E = 1e5; // soft (overlaps ~1e-3 r) so that it settles in few steps
  WorldSettings s;
  s.threads = 1;
  s.local_damping = 0.7;
  World w(s);
  ContactProperties bb = props(ContactModel::rrlinear, E, 0.5, 0.1);
  w.set_ball_ball_defaults(bb);
  const ContactProperties floor = props(ContactModel::linear, E, 0.5);
  const ContactProperties side = props(ContactModel::linear, E, 0.0);
  const std::size_t kfloor = w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), floor);
  w.add_wall(Wall::plane("x0", {0, 0, 0}, {1, 0, 0}), side);
  w.add_wall(Wall::plane("x1", {L, 0, 0}, {-1, 0, 0}), side);
  w.add_wall(Wall::plane("y0", {0, 0, 0}, {0, 1, 0}), side);
  w.add_wall(Wall::plane("y1", {0, L, 0}, {0, -1, 0}), side);
  const double spacing = L / 5.0; // 5 x 5 columns, 12 layers
  add_lattice(w, 300, 5, 5, spacing, 0.8 * r, 1.2 * r, 2650,
              {spacing / 2, spacing / 2, spacing / 2}, 0.05, false);
  w.set_body_field(gravity({0, 0, -g}));
  double weight = 0;
  for (double m : w.particles().mass) weight += m * g;
  const long steps = w.cycle_until_equilibrium(1e-5, 400000, 200);
  const double ratio = w.mean_unbalanced_force_ratio();
  const Wall& fl = w.walls()[kfloor];
  ASSERT_LT(ratio, 1e-5) << "did not settle in " << steps << " steps";
  EXPECT_NEAR(-fl.force.z / weight, 1.0, 0.005);
  for (const Wall& wl : w.walls()) {
    if (wl.name != "floor") {
      EXPECT_LT(std::abs(wl.force.z), 1e-12 * weight) << wl.name;
    }
  }
  // It is a column: several layers, all balls inside the box, many contacts.
  EXPECT_GT(w.measure().ball_ball_contacts, 500u);
  for (const Vec3& x : w.particles().position) {
    EXPECT_GT(x.z, 0.0);
    EXPECT_LT(x.x, L);
  }
}

} // namespace
} // namespace centridem
