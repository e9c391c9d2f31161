// The centrifuge field through a World run (physics/body_field.hpp): in the
// frame of a centrifuge turning at omega about the axis a, a free particle
// accelerates as omega^2 rho - 2 omega a x v (centrifugal + Coriolis), rho
// its perpendicular offset from the axis. In the inertial frame it moves in
// a straight line, so the rotating-frame path has a closed form. A particle
// released at rest at offset -rho0 z from an axis along +y (the model's
// base, below the axis) has, at time t, with wt = omega t,
//   with Coriolis:    x = rho0 (sin wt - wt cos wt),  z = -rho0 (cos wt + wt sin wt)
//   without Coriolis: x = 0,                          z = -rho0 cosh wt
// (y unchanged), relative to the axis. For small wt the Coriolis term
// deflects the outward-falling particle towards +x: x ~ rho0 (wt)^3/3.
// Source: the inertial straight line X(t) = (-omega rho0 t, 0, -rho0) seen
// in the frame rotated by -omega t about y; e.g. Goldstein, Classical
// Mechanics, ch. 4.10 (motion in a rotating frame).
#include "physics_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {
using namespace phys_test;

// Path relative to the axis (x along the deflection, z away from the axis
// is negative) [m].
Vec3 rotating_frame_path(double rho0, double wt, bool coriolis) {
  if (coriolis)
    return {rho0 * (std::sin(wt) - wt * std::cos(wt)), 0.0,
            -rho0 * (std::cos(wt) + wt * std::sin(wt))};
  return {0.0, 0.0, -rho0 * std::cosh(wt)};
}

// The paper's centrifuge (50 g at 2.5 m, DEM model 1/15.9) built by
// BodyField::centrifuge, a 0.1 mm ball released at rest at the model base;
// 20,000 steps to omega t = 1, the position compared with the closed form
// at 10 instants: within 1e-4 rho0 (the leapfrog with the Coriolis term at
// the half-step velocity is first order: error ~ omega dt = 5e-5). Without
// Coriolis the x deflection is exactly 0. The deflection at wt = 1 is
// 0.30 rho0 (and 1.38 rho0 outwards): a sign flip of either term misses the
// closed form by far more than the tolerance.
TEST(PhysicsRotatingFrame, FreeParticlePathWithAndWithoutCoriolis) {
  const double s = 0.063, R_base = 2.5;
  for (const bool coriolis : {true, false}) {
    const BodyField f = BodyField::centrifuge(50, s, 2.5, R_base, {}, {0, 1, 0}, coriolis);
    const double omega = f.omega_rad_s, rho0 = s * R_base;
    ASSERT_NEAR(f.axis_point.z, rho0, 1e-15) << "axis above the base";
    const int steps = 20000;
    const double dt = 1.0 / omega / steps;
    WorldSettings ws;
    ws.threads = 1;
    World w(ws);
    w.set_ball_ball_defaults(props(ContactModel::linear, 1e6, 0.0));
    w.set_fixed_timestep(dt);
    w.set_body_field(f);
    w.add_particle({0, 0, 0}, 1e-4, 2633, 0, 1);
    // Leapfrog start: the stored velocity is v(-dt/2) = -a(0) dt/2.
    w.particles_mut().velocity[0] = -0.5 * dt * f.acceleration({}, {});
    double worst = 0;
    for (int k = 1; k <= 10; ++k) {
      w.cycle(steps / 10);
      const double wt = omega * w.time();
      const Vec3 x = w.particles().position[0] - f.axis_point;
      worst = std::max(worst, norm(x - rotating_frame_path(rho0, wt, coriolis)) / rho0);
      if (!coriolis) EXPECT_EQ(x.x, 0.0);
      EXPECT_EQ(x.y, 0.0);
    }
    EXPECT_LT(worst, 1e-4) << (coriolis ? "with" : "without") << " Coriolis";
    const Vec3 x = w.particles().position[0] - f.axis_point;
    if (coriolis) EXPECT_GT(x.x, 0.25 * rho0) << "deflected towards +x";
    EXPECT_LT(x.z, -1.3 * rho0) << "thrown outwards";
  }
}

} // namespace
} // namespace centridem
