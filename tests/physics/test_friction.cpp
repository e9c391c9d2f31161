// Acceptance 2: Coulomb friction of a sphere on a plane wall under gravity.
//
// Ball-wall contact (DESIGN.md "Physics"): kn = pi R E*, ks = kn/kratio,
// kr = ks R^2, |Fs| <= mu Fn, |Mr| <= mu_r R Fn.
// Rigid-body results used (any dynamics text, e.g. Goldstein; PFC 7 manual
// "Rolling Resistance Linear Model" for the rolling limit):
//  * block (rotation fixed) pulled by P on a horizontal plane: sticks while
//    P < mu m g, slides with a = (P - mu m g)/m above;
//  * sphere on a slope theta with rolling blocked (mu_r > tan theta): the
//    contact must carry Fs = m g sin(theta) and Mr = m g sin(theta) R, so it
//    sticks while tan(theta) < mu and slides above with
//    a = g (sin(theta) - mu cos(theta));
//  * sphere rolling without slip and without rolling resistance:
//    a = g sin(theta) / (1 + I/(m R^2)) = (5/7) g sin(theta).
#include "physics_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double R = 0.01, rho = 2650, E = 1e8, g = 9.81;

// Fixed timestep well below the critical one of a ball-wall contact:
// omega^2 <= kn/m + ks (1/m + R^2/I) + kr/I = kn/m (1 + 6/kratio).
double safe_dt(double kratio = 1.5) {
  const double m = sphere_mass(R, rho), kn = kn_ball_wall(E, R);
  return 0.2 * 2.0 / std::sqrt(kn / m * (1.0 + 6.0 / kratio));
}

// A sphere resting on a plane through the origin with unit normal n, placed
// at the normal equilibrium overlap m g cos(theta)/kn (so no normal bounce).
struct Slope {
  World w;
  Vec3 n, down; // plane normal; unit vector down the slope
  double theta;
  Slope(double theta_rad, const ContactProperties& wall_props, double damping, bool ramp_gravity)
      : w(make_settings(damping)), theta(theta_rad) {
    n = {std::sin(theta), 0, std::cos(theta)};
    down = {std::cos(theta), 0, -std::sin(theta)};
    w.add_wall(Wall::plane("slope", {0, 0, 0}, n), wall_props);
    const double m = sphere_mass(R, rho);
    const double overlap = ramp_gravity ? 0.0 : m * g * std::cos(theta) / kn_ball_wall(E, R);
    w.add_particle(n * (R - overlap), R, rho, 0, 1);
    if (!ramp_gravity) w.set_body_field(gravity({0, 0, -g}));
  }
  static WorldSettings make_settings(double damping) {
    WorldSettings s;
    s.threads = 1;
    s.local_damping = damping;
    s.timestep_s = safe_dt();
    return s;
  }
  // Gravity grows linearly from 0 to g over `steps` (quasi-static loading).
  void ramp(long steps, int chunks = 200) {
    for (int c = 1; c <= chunks; ++c) {
      w.set_body_field(gravity({0, 0, -g * c / chunks}));
      w.cycle(steps / chunks);
    }
  }
  double along_slope() const { return dot(w.particles().position[idx(w, 1)], down); }
  double speed_down() const { return dot(w.particles().velocity[idx(w, 1)], down); }
};

// Elastic tangential displacement of the centre of a sphere held by the
// shear spring and the rolling spring: Fs/ks + R (Mr/kr) = 2 m g sin/ks.
double elastic_slope_displacement(double theta) {
  const double ks = kn_ball_wall(E, R) / 1.5;
  return 2.0 * sphere_mass(R, rho) * g * std::sin(theta) / ks;
}

// Slope with rolling blocked (rrlinear, mu_r = 1.5 > tan theta), quasi-static
// gravity ramp, local damping 0.7: stays within 3x the elastic displacement
// for tan(theta) = 0.9 mu; slides (displacement > 1e4 x elastic, and
// speeding up) for tan(theta) = 1.1 mu.
TEST(PhysicsFriction, SlopeStaysBelowMuSlidesAbove) {
  const double mu = 0.5;
  const ContactProperties wall = props(ContactModel::rrlinear, E, mu, 1.5);
  for (double ratio : {0.9, 1.1}) {
    const double theta = std::atan(ratio * mu);
    Slope s(theta, wall, 0.7, true);
    const double x0 = s.along_slope();
    s.ramp(20000);
    s.w.cycle(10000);
    const double u1 = s.along_slope() - x0;
    s.w.cycle(10000);
    const double u2 = s.along_slope() - x0;
    const double el = elastic_slope_displacement(theta);
    if (ratio < 1) {
      EXPECT_LT(std::abs(u2), 3.0 * el) << "tan/mu " << ratio << " displacement " << u2;
      EXPECT_NEAR(u2, u1, 1e-3 * el) << "still creeping";
    } else {
      EXPECT_GT(u2, 1e4 * el) << "tan/mu " << ratio << " displacement " << u2;
      EXPECT_GT(u2 - u1, u1) << "sliding should accelerate";
    }
  }
}

// Sliding with rolling blocked, no damping: a = g (sin - mu cos) within 2 %.
// tan(theta) = 0.7 > mu = 0.5, mu_r = 1.5 > tan(theta). The ball starts at
// the normal equilibrium with a down-slope speed of 0.05 m/s, so slip never
// reverses while the rolling spring takes up the friction moment.
TEST(PhysicsFriction, SlopeSlidingAcceleration) {
  const double mu = 0.5, theta = std::atan(0.7);
  Slope s(theta, props(ContactModel::rrlinear, E, mu, 1.5), 0.0, false);
  s.w.particles_mut().velocity[0] = s.down * 0.05;
  s.w.cycle(2000);
  const double v1 = s.speed_down(), t1 = s.w.time();
  s.w.cycle(20000);
  const double v2 = s.speed_down(), t2 = s.w.time();
  const double a = (v2 - v1) / (t2 - t1);
  const double expected = g * (std::sin(theta) - mu * std::cos(theta));
  EXPECT_NEAR(a / expected, 1.0, 0.02) << "a " << a << " expected " << expected;
  // Rolling blocked: spin stays tiny compared with rolling (v/R).
  EXPECT_LT(norm(s.w.particles().spin[0]) * R, 0.01 * v2);
}

// Rolling without slip and without rolling resistance (linear, and rrlinear
// with mu_r = 0): a = (5/7) g sin(theta) within 1 %. tan(theta) = 0.3,
// mu = 0.5 > (2/7) tan(theta), so it rolls.
TEST(PhysicsFriction, SlopeRollingAcceleration) {
  const double mu = 0.5, theta = std::atan(0.3);
  for (ContactModel model : {ContactModel::linear, ContactModel::rrlinear}) {
    Slope s(theta, props(model, E, mu, 0.0), 0.0, false);
    s.w.cycle(1000);
    const double v1 = s.speed_down(), t1 = s.w.time();
    s.w.cycle(20000);
    const double v2 = s.speed_down(), t2 = s.w.time();
    const double a = (v2 - v1) / (t2 - t1);
    const double expected = 5.0 / 7.0 * g * std::sin(theta);
    EXPECT_NEAR(a / expected, 1.0, 0.01) << "model " << to_string(model) << " a " << a;
    // rolls: contact-point speed ~ 0, i.e. spin x R = v
    const double roll_speed = norm(s.w.particles().spin[0]) * R;
    EXPECT_NEAR(roll_speed / v2, 1.0, 0.01);
  }
}

// Horizontal plane, rotation fixed (a sliding block), local damping 0.7 and a
// slow ramp of the pull P: P = 0.98 mu m g sticks (displacement ~ P/ks),
// P = 1.02 mu m g slides. Then, undamped, P = 1.5 mu m g gives
// a = (P - mu m g)/m within 1 %.
TEST(PhysicsFriction, HorizontalPullStickSlip) {
  const double mu = 0.4, m = sphere_mass(R, rho);
  const double N = m * g, ks = kn_ball_wall(E, R) / 1.5;
  auto make = [&](double damping) {
    auto s = std::make_unique<Slope>(0.0, props(ContactModel::linear, E, mu), damping, false);
    s->w.particles_mut().flags[0] = fix_rotation;
    return s;
  };
  for (double ratio : {0.98, 1.02}) {
    auto s = make(0.7);
    const double P = ratio * mu * N;
    for (int c = 1; c <= 200; ++c) {
      s->w.particles_mut().applied_force[idx(s->w, 1)] = {P * c / 200.0, 0, 0};
      s->w.cycle(100);
    }
    s->w.cycle(10000);
    const double u = s->w.particles().position[idx(s->w, 1)].x;
    if (ratio < 1) {
      EXPECT_NEAR(u / (P / ks), 1.0, 0.01) << "sticking: elastic displacement P/ks";
    } else {
      EXPECT_GT(u, 1e3 * P / ks) << "should slide";
    }
  }
  auto s = make(0.0);
  const double P = 1.5 * mu * N;
  s->w.particles_mut().applied_force[0] = {P, 0, 0};
  s->w.cycle(1000);
  const double v1 = s->w.particles().velocity[0].x, t1 = s->w.time();
  s->w.cycle(10000);
  const double v2 = s->w.particles().velocity[0].x, t2 = s->w.time();
  const double a = (v2 - v1) / (t2 - t1);
  EXPECT_NEAR(a / ((P - mu * N) / m), 1.0, 0.01);
}

} // namespace
} // namespace centridem
