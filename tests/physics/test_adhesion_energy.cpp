// World::energy() with adhesion (arrlinear): the attraction is a potential
// force, so kinetic + strain + attraction potential is conserved in an
// undamped, frictionless run. The potential (attraction_potential_J in
// physics_test_util.hpp) is -integral of the attraction over the approach,
// zero beyond the range D0: -F0 (D0 + d)^2/(2 D0) in the gap (d < 0),
// -F0 (D0/2 + d) while overlapping (D0 = 0: -F0 d).
// Leapfrog (central differences) conserves energy up to O(w dt) here (the
// kinetic energy is taken at the half step), bounded and small for
// dt = T_contact/1000. Source: Hairer, Lubich & Wanner, Geometric Numerical
// Integration; Gilabert, Roux & Castellanos 2007 for the attraction law.
#include "physics_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double R = 0.01, rho = 2650, E = 1e8, F0 = 0.5;

struct PairRun {
  double E0 = 0, max_dE = 0, min_attraction = 0, min_gap = 1, max_gap = -1;
};

// Two equal balls, frictionless arrlinear, no damping, no gravity, starting
// at rest with overlap d0 (a gap when < 0); `steps` steps of T_contact/1000,
// the energy sampled every 10 steps.
PairRun run_pair(double D0, double d0, long steps) {
  const double m = sphere_mass(R, rho), mc = 0.5 * m, kn = kn_ball_ball(E, R, R);
  WorldSettings s;
  s.threads = 1;
  s.timestep_s = pi * std::sqrt(mc / kn) / 1000.0;
  World w(s);
  ContactProperties p = props(ContactModel::arrlinear, E, 0.0);
  p.attraction_force_N = F0;
  p.attraction_range_m = D0;
  w.set_ball_ball_defaults(p);
  w.add_particle({0, 0, 0}, R, rho, 0, 1);
  w.add_particle({2 * R - d0, 0, 0}, R, rho, 0, 2);
  w.cycle(1); // the contact is born (energy() counts active contacts)
  PairRun r;
  r.E0 = w.energy().total();
  for (long k = 0; k < steps; k += 10) {
    w.cycle(10);
    const Energy e = w.energy();
    r.max_dE = std::max(r.max_dE, std::abs(e.total() - r.E0));
    r.min_attraction = std::min(r.min_attraction, e.attraction_J);
    const double gap =
        norm(w.particles().position[idx(w, 2)] - w.particles().position[idx(w, 1)]) - 2 * R;
    r.min_gap = std::min(r.min_gap, gap), r.max_gap = std::max(r.max_gap, gap);
  }
  return r;
}

// The potential of one contact at rest against the closed form (1e-12):
// at overlap F0/kn (D0 = R/20 and 0) and at a gap of D0/2.
TEST(PhysicsAdhesionEnergy, AttractionPotentialMatchesClosedForm) {
  const double kn = kn_ball_ball(E, R, R);
  for (const double D0 : {0.05 * R, 0.0}) {
    const std::vector<double> overlaps =
        D0 > 0 ? std::vector<double>{F0 / kn, -0.5 * D0} : std::vector<double>{F0 / kn};
    for (const double d : overlaps) {
      WorldSettings s;
      s.threads = 1;
      World w(s);
      ContactProperties p = props(ContactModel::arrlinear, E, 0.0);
      p.attraction_force_N = F0;
      p.attraction_range_m = D0;
      w.set_ball_ball_defaults(p);
      w.add_particle({0, 0, 0}, R, rho, 0, 1);
      w.add_particle({2 * R - d, 0, 0}, R, rho, 0, 2);
      w.particles_mut().flags[0] = w.particles_mut().flags[1] = fix_translation | fix_rotation;
      w.cycle(1);
      ASSERT_EQ(w.ball_ball_contacts().size(), 1u);
      const double expected = attraction_potential_J(F0, D0, d);
      EXPECT_NEAR(w.energy().attraction_J / expected, 1.0, 1e-9) << "D0 " << D0 << " d " << d;
      EXPECT_NEAR(w.energy().total(), 0.5 * kn * std::max(d, 0.0) * std::max(d, 0.0) + expected,
                  1e-9 * std::abs(expected));
    }
  }
}

// D0 = R/20: the pair starts at rest at a gap of D0/2, is pulled together,
// collides and rebounds to the same gap, over and over. The energy
// (kinetic + strain + attraction) stays within 1 % of the well depth
// F0 D0/2, while the attraction's share swings over most of it.
TEST(PhysicsAdhesionEnergy, BalanceHoldsWithRangedAttraction) {
  const double D0 = 0.05 * R;
  const PairRun r = run_pair(D0, -0.5 * D0, 40000);
  const double depth = 0.5 * F0 * D0;
  EXPECT_LT(r.max_dE, 0.01 * depth);
  EXPECT_LT(r.min_attraction, -0.9 * depth) << "not vacuous: the pair came together";
  EXPECT_LT(r.min_gap, 0.0) << "the surfaces touched";
  EXPECT_GT(r.max_gap, 0.4 * D0) << "and came apart again";
}

// D0 = 0 (the paper's law): F0 only while overlapping. Start at rest at a
// small overlap 0.05 F0/kn: the pair oscillates between it and ~1.95 F0/kn
// about F0/kn. The energy stays within 1 % of the well depth F0^2/(2 kn),
// while the strain energy alone swings by more than the depth.
TEST(PhysicsAdhesionEnergy, BalanceHoldsWithContactAttraction) {
  const double kn = kn_ball_ball(E, R, R);
  const PairRun r = run_pair(0.0, 0.05 * F0 / kn, 20000);
  const double depth = F0 * F0 / (2.0 * kn);
  EXPECT_LT(r.max_dE, 0.01 * depth);
  EXPECT_LT(r.min_attraction, -1.8 * F0 * F0 / kn) << "not vacuous: overlap reached ~2 F0/kn";
  EXPECT_LT(r.max_gap, 0.0) << "stays in contact";
}

} // namespace
} // namespace centridem
