// Acceptance 1: binary normal impact of two unequal spheres, no gravity.
//
// Linear spring (PFC `linear`, DESIGN.md "Physics"): the overlap obeys
// mc d''(t) = -kn d - c d', mc = m1 m2/(m1+m2), c = 2 beta sqrt(mc kn), so for
// an approach speed v0:
//   no damping:  d(t) = (v0/w) sin(w t), w = sqrt(kn/mc); contact duration
//                T = pi sqrt(mc/kn); rebound speed = v0 (energy conserved);
//   dashpot beta (PFC dp_nratio, dp_mode 0): w_d = w sqrt(1-beta^2),
//                T = pi/w_d, restitution e = exp(-pi beta/sqrt(1-beta^2)).
// Source: textbook damped oscillator; PFC 7 manual "Linear Model" (dp_nratio).
#include "physics_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {
using namespace phys_test;

struct ImpactResult {
  double duration_s = 0;    // contact duration (linear interpolation of the zero crossings)
  double rebound_speed = 0; // |relative normal velocity| after separation
  double impact_speed = 0;
};

struct ImpactSetup {
  double R1 = 0.01, R2 = 0.006, rho = 2650, E = 1e8, v0 = 0.1, beta = 0.0;
};

double analytic_duration(const ImpactSetup& s) {
  const double m1 = sphere_mass(s.R1, s.rho), m2 = sphere_mass(s.R2, s.rho);
  const double mc = m1 * m2 / (m1 + m2);
  const double kn = kn_ball_ball(s.E, s.R1, s.R2);
  return pi * std::sqrt(mc / kn) / std::sqrt(1.0 - s.beta * s.beta);
}

ImpactResult run_impact(const ImpactSetup& s) {
  const double T = analytic_duration(s);
  WorldSettings ws;
  ws.threads = 1;
  ws.timestep_s = T / 2000.0; // small fixed timestep
  World w(ws);
  ContactProperties p = props(ContactModel::linear, s.E, 0.0);
  p.dashpot_normal_ratio = s.beta;
  p.dashpot_mode = 0; // full dashpot: the damped oscillator the formula assumes
  w.set_ball_ball_defaults(p);
  const double gap = 0.05 * s.v0 * T; // closes in ~100 steps
  w.add_particle({0, 0, 0}, s.R1, s.rho, 0, 1);
  w.add_particle({s.R1 + s.R2 + gap, 0, 0}, s.R2, s.rho, 0, 2);
  {
    auto& P = w.particles_mut();
    const double m1 = P.mass[0], m2 = P.mass[1];
    // zero total momentum, relative speed v0
    P.velocity[0] = {s.v0 * m2 / (m1 + m2), 0, 0};
    P.velocity[1] = {-s.v0 * m1 / (m1 + m2), 0, 0};
  }
  auto overlap = [&] {
    const Vec3 d = w.particles().position[idx(w, 2)] - w.particles().position[idx(w, 1)];
    return s.R1 + s.R2 - norm(d);
  };
  ImpactResult r;
  r.impact_speed = s.v0;
  double prev = overlap(), prev_t = w.time();
  double t_in = -1, t_out = -1;
  for (int k = 0; k < 20000 && t_out < 0; ++k) {
    w.cycle(1);
    const double ov = overlap(), t = w.time();
    if (t_in < 0 && prev <= 0 && ov > 0) t_in = prev_t + (t - prev_t) * (-prev) / (ov - prev);
    if (t_in >= 0 && prev > 0 && ov <= 0) t_out = prev_t + (t - prev_t) * prev / (prev - ov);
    prev = ov, prev_t = t;
  }
  w.cycle(50); // well separated
  r.duration_s = t_out - t_in;
  const Vec3 vrel = w.particles().velocity[idx(w, 2)] - w.particles().velocity[idx(w, 1)];
  r.rebound_speed = vrel.x; // separating: positive
  EXPECT_GT(t_in, 0.0);
  EXPECT_GT(t_out, t_in);
  return r;
}

// Undamped: T = pi sqrt(mc/kn) within 1 %, rebound speed = impact speed within 0.1 %.
TEST(PhysicsNormalImpact, UndampedDurationAndRebound) {
  ImpactSetup s;
  const ImpactResult r = run_impact(s);
  const double T = analytic_duration(s);
  EXPECT_NEAR(r.duration_s / T, 1.0, 0.01) << "duration " << r.duration_s << " vs " << T;
  EXPECT_NEAR(r.rebound_speed / r.impact_speed, 1.0, 1e-3);
}

// Normal dashpot beta = 0.2 and 0.5: e = exp(-pi beta/sqrt(1-beta^2)) within 2 %,
// duration pi/(w sqrt(1-beta^2)) within 1 %.
TEST(PhysicsNormalImpact, DashpotRestitution) {
  for (double beta : {0.2, 0.5}) {
    ImpactSetup s;
    s.beta = beta;
    const ImpactResult r = run_impact(s);
    const double e = std::exp(-pi * beta / std::sqrt(1.0 - beta * beta));
    EXPECT_NEAR(r.rebound_speed / r.impact_speed / e, 1.0, 0.02)
        << "beta " << beta << " e measured " << r.rebound_speed / r.impact_speed << " expected "
        << e;
    EXPECT_NEAR(r.duration_s / analytic_duration(s), 1.0, 0.01) << "beta " << beta;
  }
}

} // namespace
} // namespace centridem
