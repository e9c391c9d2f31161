// Acceptance 4: adhesion (arrlinear; Gilabert, Roux & Castellanos 2007, as
// DESIGN.md "Physics" fixes it): the attraction is F0 while the surfaces
// overlap and falls linearly to zero at gap D0; the net normal force on a
// pair is kn d - F0 (d > 0). Hence
//   * at rest with no external load: kn d = F0, overlap d = F0/kn;
//   * under a pull P along the normal: d = (F0 - P)/kn, which reaches 0 at
//     P = F0; for P > F0 there is no equilibrium (the attraction never
//     exceeds F0), so the pull-off force is F0 (for any D0 >= 0).
// kn = pi R^2 E*/(2R) for two equal spheres. Values: the paper's material
// (Tao et al. Table 1: E* = 300 MPa, F0 = 1.2e-4 N, R = 1 mm, rho = 2633).
#include "physics_test_util.hpp"
#include "procedures/paper_material.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double R = 1e-3, rho = paper::density_kg_m3;

struct Pair {
  World w;
  double kn, F0;
  Pair(double D0, double damping, bool fix_first, double initial_overlap_over_F0kn)
      : w([&] {
          WorldSettings s;
          s.threads = 1;
          s.local_damping = damping;
          return s;
        }()) {
    ContactProperties p = paper::ball_ball();
    p.attraction_range_m = D0;
    F0 = p.attraction_force_N;
    kn = kn_ball_ball(p.effective_modulus_Pa, R, R);
    const double m = sphere_mass(R, rho);
    w.set_fixed_timestep(0.2 * 2.0 / std::sqrt(kn / m * 10.0));
    w.set_ball_ball_defaults(p);
    w.add_particle({0, 0, 0}, R, rho, 0, 1);
    w.add_particle({2 * R - initial_overlap_over_F0kn * F0 / kn, 0, 0}, R, rho, 0, 2);
    if (fix_first) w.particles_mut().flags[0] = fix_translation;
  }
  double overlap() const {
    return 2 * R - norm(w.particles().position[idx(w, 2)] - w.particles().position[idx(w, 1)]);
  }
  void pull(double P) { w.particles_mut().applied_force[idx(w, 2)] = {P, 0, 0}; }
};

// Free pair, no load, damping 0.7: overlap = F0/kn within 1 %.
TEST(PhysicsAdhesion, RestOverlapIsF0OverKn) {
  for (double start : {0.1, 3.0}) { // start below and above the equilibrium overlap
    Pair p(0.0, 0.7, false, start);
    p.w.cycle(20000);
    EXPECT_NEAR(p.overlap() / (p.F0 / p.kn), 1.0, 0.01) << "start " << start;
    EXPECT_EQ(p.w.ball_ball_contacts().size(), 1u);
  }
}

// Sphere 1 fixed, pull P on sphere 2 raised slowly from 0.9 F0 (damping 0.7):
// the pair holds with overlap (F0 - P)/kn until P = F0 and lets go there:
// the surfaces part at P within 1 % of F0 (and not below F0 by more than
// 0.1 %), after which the pair escapes the attraction range under that pull.
// D0 = 0 (the paper) and D0 = R/100.
TEST(PhysicsAdhesion, PullOffForceIsF0) {
  for (double D0 : {0.0, 0.01 * R}) {
    Pair p(D0, 0.7, true, 1.0);
    for (int c = 1; c <= 100; ++c) { // load slowly: no dynamic overshoot
      p.pull(0.9 * p.F0 * c / 100.0);
      p.w.cycle(50);
    }
    p.w.cycle(2000);
    EXPECT_NEAR(p.overlap() / (0.1 * p.F0 / p.kn), 1.0, 0.01) << "held overlap (F0-P)/kn";
    double P_break = -1;
    const int chunks = 4000;
    for (int c = 0; c <= chunks && P_break < 0; ++c) {
      const double P = p.F0 * (0.9 + 0.2 * c / chunks);
      p.pull(P);
      p.w.cycle(10);
      if (p.overlap() < 0) P_break = P; // surfaces apart: past the stable branch
    }
    // Once apart it keeps going under that same pull (the gap grows) ...
    const double gap0 = -p.overlap();
    p.w.cycle(20000);
    EXPECT_GT(-p.overlap(), 10.0 * gap0) << "separated surfaces came back";
    // ... and, pulled a little harder, leaves the attraction range: contact gone.
    p.pull(1.05 * p.F0);
    for (int k = 0; k < 400 && -p.overlap() <= D0; ++k) p.w.cycle(100);
    EXPECT_GT(-p.overlap(), D0) << "did not escape the attraction range";
    EXPECT_TRUE(p.w.ball_ball_contacts().empty());
    ASSERT_GT(P_break, 0.0) << "never separated up to 1.1 F0";
    EXPECT_NEAR(P_break / p.F0, 1.0, 0.01) << "D0 " << D0;
    EXPECT_GT(P_break / p.F0, 0.999) << "let go below F0";
  }
}

} // namespace
} // namespace centridem
