// Body fields: the centrifuge field against its closed form.
#include "engine/world.hpp"

#include <gtest/gtest.h>

using namespace centridem;

// |a| = omega^2 rho with omega^2 = n g /(s^2 R_ref): n g / s at the DEM
// reference radius s R_ref, growing linearly with distance from the axis,
// directed away from it (the model's "down" at its centre line).
TEST(BodyField, CentrifugeFieldGrowsLinearlyWithRadius) {
  const double n = 50, s = 0.063, Rref = 2.5, Rbase = 2.5;
  const Vec3 base{0.01, 0.005, 0.0};
  const BodyField f = BodyField::centrifuge(n, s, Rref, Rbase, base, {0, 1, 0});
  const Vec3 at_base = f.acceleration(base, {});
  EXPECT_NEAR(at_base.z, -n * standard_gravity_m_s2 / s, 1e-9 * n * standard_gravity_m_s2 / s);
  EXPECT_NEAR(at_base.x, 0.0, 1e-12);
  EXPECT_NEAR(at_base.y, 0.0, 1e-12); // along the axis: no component
  const double h = 0.011;             // 11 mm up the DEM model = 175 mm in the real model
  const Vec3 up = f.acceleration(base + Vec3{0, 0, h}, {});
  EXPECT_NEAR(up.z / at_base.z, (s * Rbase - h) / (s * Rbase), 1e-12);
  // Off the centre line in the plane of rotation: a lateral, outward component.
  const Vec3 side = f.acceleration(base + Vec3{0.005, 0, 0}, {});
  EXPECT_NEAR(side.x / std::abs(side.z), 0.005 / (s * Rbase), 1e-12);
}

TEST(BodyField, CoriolisIsPerpendicularToVelocity) {
  BodyField f = BodyField::centrifuge(50, 0.063, 2.5, 2.5, {}, {0, 1, 0}, true);
  const Vec3 v{0, 0, 0.3}; // moving towards the axis
  const Vec3 a = f.acceleration({}, v) - f.acceleration({}, {});
  EXPECT_NEAR(dot(a, v), 0.0, 1e-12);
  EXPECT_NEAR(norm(a), 2 * f.omega_rad_s * 0.3, 1e-9);
}

// A free particle in the centrifuge field falls with the local acceleration.
TEST(BodyField, ParticleFallsWithLocalCentrifugalAcceleration) {
  World w;
  const BodyField f = BodyField::centrifuge(40, 0.063, 2.5, 2.5, {}, {0, 1, 0});
  w.set_body_field(f);
  w.set_fixed_timestep(5e-7);
  w.add_particle({0, 0, 0.005}, 1e-4, 2633);
  w.cycle(100);
  const double expected = f.acceleration({0, 0, 0.005}, {}).z;
  EXPECT_NEAR(w.particles().velocity[0].z / (100 * 5e-7), expected, 1e-3 * std::abs(expected));
}
