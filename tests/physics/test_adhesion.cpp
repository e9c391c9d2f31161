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
#include <string>
#include <vector>

#include <fmt/format.h>

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

// ---------------------------------------------------------------------------
// Friction and rolling limits of an adhesive contact, both settings of
// limits_use_net_force (closed forms in physics_test_util.hpp): a ball
// (R = 1 cm, E* = 1e8 Pa) on an arrlinear floor, no gravity, pressed by an
// applied normal load N = F0 = 0.1 N (so mu (N + F0) = 2 mu N: the two
// settings differ by a factor of two), and N = 0 (mu F0 against 0).
constexpr double Rw = 0.01, rho_w = 2650, E_w = 1e8, F0_w = 0.1, mu_w = 0.5, mu_r_w = 0.1;

struct AdhesiveFloor {
  World w;
  double kn, ks, kr;
  AdhesiveFloor(bool net, double N, bool fix_spin)
      : w([] {
          WorldSettings s;
          s.threads = 1;
          s.local_damping = 0.7;
          const double m = sphere_mass(Rw, rho_w);
          s.timestep_s = 0.2 * 2.0 / std::sqrt(kn_ball_wall(E_w, Rw) / m * 5.0);
          return s;
        }()) {
    ContactProperties p = props(ContactModel::arrlinear, E_w, mu_w, mu_r_w);
    p.attraction_force_N = F0_w;
    p.attraction_range_m = 0.0;
    p.limits_use_net_force = net;
    kn = kn_ball_wall(E_w, Rw), ks = kn / 1.5, kr = ks * Rw * Rw;
    w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), p);
    w.add_particle({0, 0, Rw - (N + F0_w) / kn}, Rw, rho_w, 0, 1); // at rest: kn d = N + F0
    w.particles_mut().applied_force[0] = {0, 0, -N};
    if (fix_spin) w.particles_mut().flags[0] = fix_rotation;
  }
  // Steps one at a time, integrating the spin into a rotation angle about y.
  double phi = 0;
  void step(long n) {
    for (long k = 0; k < n; ++k) {
      w.cycle(1);
      phi += w.particles().spin[0].y * w.timestep();
    }
  }
};

struct LimitCase {
  bool net;
  double N;
};
constexpr LimitCase limit_cases[] = {{false, F0_w}, {true, F0_w}, {false, 0.0}, {true, 0.0}};

// Rotation fixed, tangential pull T ramped slowly (damping 0.7): T = 0.97 L
// holds with the elastic displacement T/ks (within 1 %), T = 1.03 L slides
// (displacement > 1e3 T/ks), with L = mu (N + F0) (spring force) or mu N
// (net force). With N = 0 and the net force the limit is 0: a pull of
// 0.05 mu F0 slides.
TEST(PhysicsAdhesion, FrictionLimitUnderLoadBothSettings) {
  for (const LimitCase& c : limit_cases) {
    const double L = adhesive_shear_limit_N(mu_w, c.N, F0_w, c.net);
    const std::vector<double> pulls =
        L > 0 ? std::vector<double>{0.97 * L, 1.03 * L} : std::vector<double>{0.05 * mu_w * F0_w};
    for (const double T : pulls) {
      AdhesiveFloor f(c.net, c.N, true);
      for (int k = 1; k <= 200; ++k) {
        f.w.particles_mut().applied_force[0].x = T * k / 200.0;
        f.w.cycle(100);
      }
      f.w.cycle(10000);
      const double u = f.w.particles().position[0].x;
      const std::string what = fmt::format("net {} N {} T {} limit {}", c.net, c.N, T, L);
      if (T < L) {
        EXPECT_NEAR(u / (T / f.ks), 1.0, 0.01) << what << ": should stick, u = T/ks";
      } else {
        EXPECT_GT(u, 1e3 * T / f.ks) << what << ": should slide";
      }
    }
  }
}

// Free ball, applied moment M about y ramped slowly (damping 0.7):
// M = 0.97 L holds with the rotation M/kr, kr = ks R^2 (within 1 %);
// M = 1.03 L keeps turning (rotation > 100 M/kr), with L = mu_r R (N + F0)
// or mu_r R N (ball-wall: Rbar = R). N = 0, net force: L = 0, a moment of
// 0.05 mu_r R F0 turns the ball.
TEST(PhysicsAdhesion, RollingLimitUnderLoadBothSettings) {
  for (const LimitCase& c : limit_cases) {
    const double L = adhesive_rolling_limit_N_m(mu_r_w, Rw, c.N, F0_w, c.net);
    const std::vector<double> moments = L > 0 ? std::vector<double>{0.97 * L, 1.03 * L}
                                              : std::vector<double>{0.05 * mu_r_w * Rw * F0_w};
    for (const double M : moments) {
      AdhesiveFloor f(c.net, c.N, false);
      for (int k = 1; k <= 100; ++k) {
        f.w.particles_mut().applied_moment[0] = {0, M * k / 100.0, 0};
        f.step(100);
      }
      f.step(5000);
      const double phi1 = f.phi;
      f.step(2000);
      const std::string what = fmt::format("net {} N {} M {} limit {}", c.net, c.N, M, L);
      if (M < L) {
        EXPECT_NEAR(f.phi / (M / f.kr), 1.0, 0.01) << what << ": should hold, phi = M/kr";
        EXPECT_NEAR(f.phi, phi1, 1e-4 * M / f.kr) << what << ": still turning";
      } else {
        EXPECT_GT(f.phi, 100 * M / f.kr) << what << ": should turn";
        EXPECT_GT(f.phi - phi1, 0.1 * phi1) << what << ": spin should keep growing";
      }
    }
  }
}

// Attraction within the range, D0 = R/20 > 0: a ball moved at a prescribed
// speed towards a floor (ball-wall) or a fixed ball (ball-ball), from a gap
// of 1.5 D0 to touching and back out. At every step the normal force equals
// -F0 (1 - gap/D0) for gap < D0 (to 1e-9 F0), the contact exists exactly
// while gap < D0 (formed on approach before the surfaces touch, gone on
// leaving the range), and the force is zero beyond.
TEST(PhysicsAdhesion, AttractionDecaysLinearlyWithinRange) {
  const double D0 = Rw / 20.0;
  ContactProperties p = props(ContactModel::arrlinear, E_w, mu_w, mu_r_w);
  p.attraction_force_N = F0_w;
  p.attraction_range_m = D0;
  WorldSettings s;
  s.threads = 1;
  const double dt = 1e-5, steps = 300;
  s.timestep_s = dt;
  const double v = 1.5 * D0 / (steps * dt); // crosses 1.5 D0 in 300 steps
  for (const bool wall : {true, false}) {
    World w(s);
    if (wall) {
      w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), p);
      w.add_particle({0, 0, Rw + 1.5 * D0}, Rw, rho_w, 0, 2);
    } else {
      w.set_ball_ball_defaults(p);
      w.add_particle({0, 0, 0}, Rw, rho_w, 0, 1);
      w.add_particle({0, 0, 2 * Rw + 1.5 * D0}, Rw, rho_w, 0, 2);
      w.particles_mut().flags[idx(w, 1)] = fix_translation | fix_rotation;
    }
    w.particles_mut().flags[idx(w, 2)] = fix_translation | fix_rotation;
    int inside = 0, outside = 0;
    for (const double dir : {-1.0, 1.0}) { // approach to a 1e-3 D0 gap, then leave
      w.particles_mut().velocity[idx(w, 2)] = {0, 0, dir * v};
      for (int k = 0; k < steps; ++k) {
        const double z1 = wall ? Rw : w.particles().position[idx(w, 1)].z + 2 * Rw;
        const double gap = w.particles().position[idx(w, 2)].z - z1; // at the force evaluation
        if (dir < 0 && gap < 1e-3 * D0) break;
        w.cycle(1);
        // Signed normal force on the moving ball along the normal away from
        // the other body (positive = repulsive).
        double fn = 0;
        std::size_t contacts = 0;
        if (wall) {
          fn = w.walls()[0].force.z; // force on the wall: the ball pulls it up
          fn = -fn;
          contacts = w.walls()[0].contact_count;
        } else {
          const auto views = w.ball_ball_contacts();
          contacts = views.size();
          for (const ContactView& cv : views)
            fn = (w.particles().id[cv.j] == 2 ? 1.0 : -1.0) * cv.force_on_j.z;
        }
        const std::string what = fmt::format("{} gap/D0 {}", wall ? "wall" : "ball", gap / D0);
        // (the spring kn d once the surfaces touch: at the last step, d ~ 1e-16 m)
        const double kn = wall ? kn_ball_wall(E_w, Rw) : kn_ball_ball(E_w, Rw, Rw);
        EXPECT_NEAR(fn, kn * std::max(-gap, 0.0) - attraction_N(F0_w, D0, -gap), 1e-9 * F0_w)
            << what;
        EXPECT_EQ(contacts, gap < D0 ? 1u : 0u) << what;
        (gap < D0 ? inside : outside) += 1;
      }
    }
    EXPECT_GT(inside, 300) << "not vacuous: many steps inside the range";
    EXPECT_GT(outside, 100) << "and beyond it, on both sides";
  }
}

} // namespace
} // namespace centridem
