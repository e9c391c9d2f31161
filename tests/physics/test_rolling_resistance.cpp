// Acceptance 3: rolling resistance (PFC `rrlinear`; DESIGN.md "Physics"):
//   Mr <- Mr - kr dtheta_bend, kr = ks Rbar^2, |Mr| <= mu_r Rbar Fn,
// Rbar = R1 R2/(R1+R2) (ball-wall: R). The twist part of the relative
// rotation is not resisted.
//
// Statics used below (derived here, small rotations, linear springs):
//  * Sphere on a plane, free to translate, applied moment M about a
//    horizontal axis: horizontal equilibrium forces the shear force to zero,
//    so the contact point does not slip (centre moves R' phi) and the whole
//    moment is carried by the rolling spring: phi = M/kr, kr = ks R^2.
//    It turns (no equilibrium) once M > mu_r R Fn; then, rolling without
//    slip, (I + m R'^2) alpha = M - mu_r R Fn (R' = R - overlap/2, the arm).
//  * Two spheres with fixed centres, normal n = x, moments +M on sphere 2
//    and -M on sphere 1 about the bend axis y: by symmetry phi1 = -phi2, so
//    the contact points move together (R' phi2 + R' phi1 = 0, no shear) and
//    M = kr (phi2 - phi1): relative rotation = M/kr, kr = ks (R/2)^2.
//  * Same pair with sphere 1's rotation fixed, M on sphere 2 only: the
//    shear displacement is R' phi2 (R' = R - overlap/2), so
//    M = (kr + ks R'^2) phi2.
// Source: PFC 7 manual "Rolling Resistance Linear Model"; the statics are
// elementary and derived above.
#include "physics_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double R = 0.01, rho = 2650, E = 1e8, g = 9.81;

WorldSettings settings(double damping, double dt) {
  WorldSettings s;
  s.threads = 1;
  s.local_damping = damping;
  s.timestep_s = dt;
  return s;
}

// Well below the critical timestep of a ball-wall rrlinear contact (see test_friction).
double safe_dt_wall() {
  return 0.2 * 2.0 / std::sqrt(kn_ball_wall(E, R) / sphere_mass(R, rho) * 5.0);
}

// Ball on a horizontal floor at its normal equilibrium overlap.
struct Floor {
  World w;
  double overlap;
  Floor(double mu, double mu_r, double damping)
      : w(settings(damping, safe_dt_wall())),
        overlap(sphere_mass(R, rho) * g / kn_ball_wall(E, R)) {
    w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}),
               props(ContactModel::rrlinear, E, mu, mu_r));
    w.add_particle({0, 0, R - overlap}, R, rho, 0, 1);
    w.set_body_field(gravity({0, 0, -g}));
  }
  // Steps one at a time, integrating the spin into a rotation angle about y.
  double phi = 0;
  void step(long n) {
    for (long k = 0; k < n; ++k) {
      w.cycle(1);
      phi += w.particles().spin[0].y * w.timestep();
    }
  }
  void set_moment(double My) { w.particles_mut().applied_moment[0] = {0, My, 0}; }
};

// Below the limit: M = 0.95 mu_r R Fn (ramped, damping 0.7) -> equilibrium
// rotation M/kr with kr = ks R^2 (within 1 %); above: 1.05 mu_r R Fn keeps
// turning (rotation > 100 M/kr and spin not decaying).
TEST(PhysicsRollingResistance, SphereOnPlaneTurnsOnlyAboveLimit) {
  const double mu = 0.5, mu_r = 0.1;
  const double m = sphere_mass(R, rho), Fn = m * g;
  const double kr = kn_ball_wall(E, R) / 1.5 * R * R;
  const double Mlim = mu_r * R * Fn;
  for (double ratio : {0.95, 1.05}) {
    Floor f(mu, mu_r, 0.7);
    const double M = ratio * Mlim;
    for (int c = 1; c <= 100; ++c) {
      f.set_moment(M * c / 100.0);
      f.step(100);
    }
    f.step(5000);
    const double phi1 = f.phi;
    f.step(2000);
    if (ratio < 1) {
      EXPECT_NEAR(f.phi / (M / kr), 1.0, 0.01) << "rotation under M below the limit";
      EXPECT_NEAR(f.phi, phi1, 1e-4 * M / kr) << "still turning";
    } else {
      EXPECT_GT(f.phi, 100 * M / kr) << "should turn above the limit";
      EXPECT_GT(f.phi - phi1, 0.1 * phi1) << "spin should keep growing";
    }
  }
}

// Above the limit, undamped, M = 1.5 mu_r R Fn: rolling without slip with
// (I + m R'^2) alpha = M - mu_r R Fn (within 2 %), and the contact's rolling
// moment, recovered from the unbalanced moment, equals mu_r R Fn (within
// 1e-6 relative) and opposes the spin.
TEST(PhysicsRollingResistance, SteadyRollingMomentAndAcceleration) {
  const double mu = 0.5, mu_r = 0.1;
  Floor f(mu, mu_r, 0.0);
  const double m = sphere_mass(R, rho), I = sphere_inertia(R, rho);
  const double kn = kn_ball_wall(E, R), Fn = kn * f.overlap;
  const double Mlim = mu_r * R * Fn, M = 1.5 * Mlim;
  const double arm = R - 0.5 * f.overlap;
  f.set_moment(M);
  f.step(2000);
  const double w1 = f.w.particles().spin[0].y, t1 = f.w.time();
  f.step(20000);
  const double w2 = f.w.particles().spin[0].y, t2 = f.w.time();
  const double alpha = (w2 - w1) / (t2 - t1);
  const double expected = (M - Mlim) / (I + m * arm * arm);
  EXPECT_NEAR(alpha / expected, 1.0, 0.02);

  // Rolling moment on the ball: unbalanced moment - applied - arm x (contact force).
  const auto& P = f.w.particles();
  const Vec3 contact_force = P.force[0] - P.mass[0] * Vec3{0, 0, -g};
  const double ov = R - P.position[0].z;
  const Vec3 arm_vec{0, 0, -(R - 0.5 * ov)};
  const Vec3 mr = P.moment[0] - Vec3{0, M, 0} - cross(arm_vec, contact_force);
  EXPECT_NEAR(norm(mr) / (mu_r * R * kn * ov), 1.0, 1e-6);
  EXPECT_LT(mr.y, 0.0) << "rolling moment must oppose the spin";
  // No slip: contact-point speed small compared with the rolling speed.
  const double slip = P.velocity[0].x - arm * P.spin[0].y;
  EXPECT_LT(std::abs(slip), 0.01 * std::abs(P.velocity[0].x));
}

// Two spheres, centres fixed, equal and opposite bend moments: relative
// rotation M/kr with kr = ks (R/2)^2, within 0.5 %. Sphere 1's rotation
// fixed instead: phi2 = M/(kr + ks R'^2), within 0.5 %.
TEST(PhysicsRollingResistance, BendStiffnessOfFixedPair) {
  const double mu = 0.5, mu_r = 0.5;
  const double kn = kn_ball_ball(E, R, R), ks = kn / 1.5, kr = ks * (R / 2) * (R / 2);
  const double overlap = 1e-4 * R;
  const double Fn = kn * overlap, Mlim = mu_r * (R / 2) * Fn;
  const double m = sphere_mass(R, rho);
  const double dt = 0.2 * 2.0 / std::sqrt(kn / m * 10.0);
  for (bool fix_first : {false, true}) {
    World w(settings(0.7, dt));
    w.set_ball_ball_defaults(props(ContactModel::rrlinear, E, mu, mu_r));
    w.add_particle({0, 0, 0}, R, rho, 0, 1);
    w.add_particle({2 * R - overlap, 0, 0}, R, rho, 0, 2);
    auto& P = w.particles_mut();
    P.flags[0] = fix_translation | (fix_first ? fix_rotation : 0);
    P.flags[1] = fix_translation;
    const double M = 0.3 * Mlim;
    P.applied_moment[1] = {0, M, 0};
    if (!fix_first) P.applied_moment[0] = {0, -M, 0};
    double phi1 = 0, phi2 = 0;
    for (int k = 0; k < 6000; ++k) {
      w.cycle(1);
      phi1 += w.particles().spin[idx(w, 1)].y * w.timestep();
      phi2 += w.particles().spin[idx(w, 2)].y * w.timestep();
    }
    const double arm = R - 0.5 * overlap;
    const double expected = fix_first ? M / (kr + ks * arm * arm) : M / kr;
    const double measured = fix_first ? phi2 : phi2 - phi1;
    EXPECT_NEAR(measured / expected, 1.0, 5e-3) << (fix_first ? "one fixed" : "symmetric");
    if (!fix_first) {
      EXPECT_NEAR(phi1, -phi2, 1e-3 * std::abs(phi2));
    }
  }
}

// Twist (relative rotation about the normal) is not resisted: fixed centres,
// +M on sphere 2 and -M on sphere 1 about the normal, undamped: each spins up
// at M/I (within 1e-9 relative).
TEST(PhysicsRollingResistance, TwistNotResisted) {
  const double kn = kn_ball_ball(E, R, R), m = sphere_mass(R, rho), I = sphere_inertia(R, rho);
  const double dt = 0.2 * 2.0 / std::sqrt(kn / m * 10.0);
  World w(settings(0.0, dt));
  w.set_ball_ball_defaults(props(ContactModel::rrlinear, E, 0.5, 0.5));
  w.add_particle({0, 0, 0}, R, rho, 0, 1);
  w.add_particle({2 * R - 1e-4 * R, 0, 0}, R, rho, 0, 2);
  auto& P = w.particles_mut();
  P.flags[0] = P.flags[1] = fix_translation;
  const double M = 1e-3;
  P.applied_moment[0] = {-M, 0, 0};
  P.applied_moment[1] = {M, 0, 0};
  w.cycle(1000);
  const double expected = M / I * w.time();
  EXPECT_NEAR(w.particles().spin[idx(w, 2)].x / expected, 1.0, 1e-9);
  EXPECT_NEAR(w.particles().spin[idx(w, 1)].x / -expected, 1.0, 1e-9);
}

} // namespace
} // namespace centridem
