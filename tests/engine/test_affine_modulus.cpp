// World::affine_modulus_Pa against closed forms (the formula: src/engine/measurements.cpp).
// Under a uniform strain eps_aa every ball-ball branch vector l changes by eps_aa l_a e_a; the
// springs answer df = kn (n . dl) n + ks (dl - (n . dl) n), and the Love-Weber stress gives
//   M_a = (1/V) sum_contacts l_a^2 [kn n_a^2 + ks (1 - n_a^2)]
// for contacts with both centres in the box (half of it, arm . l, with one), kn = pi r^2 E*/L
// (deformability, DESIGN.md). The particles are placed and stepped once with a tiny timestep (the
// lists are built by a step); they move by less than 1e-12 of their size.
#include "../physics/physics_test_util.hpp"
#include "base/errors.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double kR = 1e-3;   // radius [m]
constexpr double kE = 1e8;    // E* [Pa]
constexpr double kRho = 2650; // [kg/m^3]

World still_world() {
  WorldSettings ws;
  ws.threads = 1;
  ws.timestep_s = 1e-12;
  World w(ws);
  w.set_ball_ball_defaults(props(ContactModel::linear, kE, 0.5)); // kn / ks = 1.5
  return w;
}

// A simple cubic lattice, N^3 spheres at spacing d < 2R: the z-contacts have n_z = 1 and
// l_z = d, the others n_z = l_z = 0, so M_z = kn d^2 N^2 (N - 1) / (N d)^3 = kn (N - 1) / (N d).
TEST(AffineModulus, SimpleCubicLatticeGivesTheNormalSpringOverTheSpacing) {
  World w = still_world();
  const int N = 4;
  const double d = 2 * kR * (1 - 1e-3);
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j)
      for (int k = 0; k < N; ++k) w.add_particle({i * d, j * d, k * d}, kR, kRho);
  w.cycle(1);
  const Box box{{-d / 2, -d / 2, -d / 2}, {(N - 0.5) * d, (N - 0.5) * d, (N - 0.5) * d}};
  const double expected = kn_ball_ball(kE, kR, kR) * (N - 1) / (N * d);
  for (int axis = 0; axis < 3; ++axis)
    EXPECT_NEAR(w.affine_modulus_Pa(box, axis), expected, 1e-9 * expected) << "axis " << axis;
}

// One oblique contact, its normal 30 deg from z in the xz-plane: the shear spring enters.
TEST(AffineModulus, AnObliqueContactCountsItsShearSpring) {
  World w = still_world();
  const double theta = std::numbers::pi / 6, l = 2 * kR * (1 - 1e-3);
  const double nx = std::sin(theta), nz = std::cos(theta);
  w.add_particle({0, 0, 0}, kR, kRho);
  w.add_particle({l * nx, 0, l * nz}, kR, kRho);
  w.cycle(1);
  const double kn = kn_ball_ball(kE, kR, kR), ks = kn / 1.5;
  const Box box{{-2 * kR, -2 * kR, -2 * kR}, {4 * kR, 2 * kR, 4 * kR}};
  const double V = box.volume();
  const double Mz = l * l * nz * nz * (kn * nz * nz + ks * nx * nx) / V;
  const double Mx = l * l * nx * nx * (kn * nx * nx + ks * nz * nz) / V;
  EXPECT_NEAR(w.affine_modulus_Pa(box, 2), Mz, 1e-9 * Mz);
  EXPECT_NEAR(w.affine_modulus_Pa(box, 0), Mx, 1e-9 * Mx);
  EXPECT_EQ(w.affine_modulus_Pa(box, 1), 0.0); // n_y = l_y = 0
  // Only the first centre in the box: its arm (l/2, equal spheres) times l.
  const Box lower{{-2 * kR, -2 * kR, -2 * kR}, {4 * kR, 2 * kR, 0.5 * kR}};
  const double half = 0.5 * l * l * nz * nz * (kn * nz * nz + ks * nx * nx) / lower.volume();
  EXPECT_NEAR(w.affine_modulus_Pa(lower, 2), half, 1e-9 * half);
}

// A pair apart (a gap inside the attraction's range) has no spring, and a wall's springs are the
// apparatus: both give 0.
TEST(AffineModulus, GapsAndWallsAddNothing) {
  World w = still_world();
  ContactProperties adhesive = props(ContactModel::arrlinear, kE, 0.5, 0.1);
  adhesive.attraction_force_N = 1e-4;
  adhesive.attraction_range_m = 0.05 * kR; // the gap below is inside it: an active contact
  w.set_ball_ball_defaults(adhesive);
  w.add_particle({0, 0, 3 * kR}, kR, kRho);
  w.add_particle({0, 0, 5.01 * kR}, kR, kRho);       // a gap of 0.01 R
  w.add_particle({5 * kR, 0, 0.999 * kR}, kR, kRho); // pressed on the floor
  w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), props(ContactModel::linear, 1e9, 0.0));
  w.cycle(1);
  ASSERT_EQ(w.measure().ball_wall_contacts, 1u);
  ASSERT_EQ(w.measure().ball_ball_contacts, 1u); // the attracting pair
  const Box box{{-2 * kR, -2 * kR, -2 * kR}, {7 * kR, 2 * kR, 7 * kR}};
  for (int axis = 0; axis < 3; ++axis) EXPECT_EQ(w.affine_modulus_Pa(box, axis), 0.0);
  EXPECT_THROW(w.affine_modulus_Pa(box, 3), InputError);
}

} // namespace
} // namespace centridem
