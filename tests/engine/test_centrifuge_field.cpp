// The centrifuge field through World runs (physics/body_field.hpp, the slope's
// [field] in procedures/slope_config.hpp): free particles, no contacts, a few steps of
// a fixed timestep, the acceleration read as the change of velocity over the
// time. With 10 steps of 1e-8 s a particle moves less than 1e-10 m, so the
// field it samples is the field at its start to about 1e-9 relative; the
// tolerances (1e-6, and 2e-3 where the velocity itself changes) leave room for
// that and nothing else. Closed forms, for the paper's scaling (DEM model s
// times the centrifuge model, n g at the reference radius R_ref):
//   omega^2 = n g / (s^2 R_ref);  |a| = omega^2 rho at DEM distance rho from the axis,
// so n g / s at rho = s R_ref; the ratio top / base = (R_base - H) / R_base; off
// the centre line by x in the plane of rotation the field leans outwards by
// x / rho; and a particle moving outwards at v is pushed against the sense of
// rotation by the Coriolis acceleration 2 omega v.
#include "engine/world.hpp"
#include "procedures/slope_config.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {

constexpr double kDt = 1e-8;
constexpr int kSteps = 10;

World free_particles(const BodyField& f) {
  WorldSettings ws;
  ws.threads = 1;
  World w(ws);
  w.set_fixed_timestep(kDt);
  w.set_body_field(f);
  return w;
}

// Mean acceleration of particle i over the run [m/s^2].
Vec3 measured_acceleration(World& w, std::size_t i) {
  const Vec3 v0 = w.particles().velocity[i];
  w.cycle(kSteps);
  return (w.particles().velocity[i] - v0) * (1.0 / (kSteps * kDt));
}

constexpr double n = 50, s = 0.063, R_base = 2.5, H = 0.18; // H: the paper's model height [m]

// The g-level is n where field.reference puts it: the base, one third of the
// model's depth below its top (the default), or a radius given.
TEST(CentrifugeField, FreeParticleAtTheReferenceRadiusAcceleratesAtNgOverS) {
  FieldSpec spec;
  spec.kind = FieldKind::centrifuge;
  spec.base_radius_m = R_base;
  EXPECT_EQ(spec.reference, FieldReference::third_depth) << "the documented default";
  EXPECT_NEAR(spec.reference_radius(H), R_base - H + H / 3, 1e-15);
  for (const FieldReference ref :
       {FieldReference::base, FieldReference::third_depth, FieldReference::radius}) {
    spec.reference = ref;
    spec.reference_radius_m = 2.45;
    const double r_ref = spec.reference_radius(H);
    const BodyField f = BodyField::centrifuge(n, s, r_ref, R_base, {}, {0, 1, 0});
    World w = free_particles(f);
    // DEM height of the reference radius above the base: s (R_base - R_ref).
    w.add_particle({0, 0, s * (R_base - r_ref)}, 1e-4, 2633);
    const Vec3 a = measured_acceleration(w, 0);
    EXPECT_NEAR(-a.z, n * standard_gravity_m_s2 / s, 1e-6 * n * standard_gravity_m_s2 / s)
        << "reference radius " << r_ref << " m";
    EXPECT_EQ(a.x, 0.0);
    EXPECT_EQ(a.y, 0.0);
  }
}

// Two particles, at the model's base and at its top: their accelerations are
// in the ratio of their radii; uniform gravity would give 1.
TEST(CentrifugeField, TopAndBaseOfTheModelAccelerateInTheRatioOfTheirRadii) {
  const BodyField f = BodyField::centrifuge(n, s, R_base, R_base, {}, {0, 1, 0});
  World w = free_particles(f);
  w.add_particle({0, 0, 0}, 1e-4, 2633, 0, 1);
  w.add_particle({0, 0, s * H}, 1e-4, 2633, 0, 2);
  w.cycle(kSteps); // from rest: the velocity after the run over its time is the acceleration
  const auto& v = w.particles().velocity;
  const double a_base = -v[*w.index_of(1)].z / (kSteps * kDt);
  const double a_top = -v[*w.index_of(2)].z / (kSteps * kDt);
  EXPECT_NEAR(a_top / a_base, (R_base - H) / R_base, 1e-6); // 0.928: 7 % less at the top
  EXPECT_NEAR(a_base, n * standard_gravity_m_s2 / s, 1e-6 * a_base);
}

// Off the centre line in the plane of rotation the field leans outwards by
// x / rho; along the axis it does not lean. Axis "y" (the default): it fans out
// along the section (x); axis "x": across the breadth (y).
TEST(CentrifugeField, FieldFansOutSidewaysByOffsetOverRadius) {
  const double off = 0.005; // 5 mm DEM = 79 mm in the centrifuge model
  const double rho = s * R_base;
  for (const Vec3 axis : {Vec3{0, 1, 0}, Vec3{1, 0, 0}}) {
    const BodyField f = BodyField::centrifuge(n, s, R_base, R_base, {}, axis);
    World w = free_particles(f);
    const Vec3 across = axis.y != 0 ? Vec3{1, 0, 0} : Vec3{0, 1, 0}; // in the plane of rotation
    w.add_particle(off * across, 1e-4, 2633, 0, 1);                  // leans along `across`
    w.add_particle(off * axis, 1e-4, 2633, 0, 2); // along the axis: does not lean
    w.cycle(kSteps); // from rest (particles are re-ordered by the neighbour search: by id)
    const Vec3 a0 = w.particles().velocity[*w.index_of(1)] * (1.0 / (kSteps * kDt));
    const Vec3 a1 = w.particles().velocity[*w.index_of(2)] * (1.0 / (kSteps * kDt));
    EXPECT_NEAR(dot(a0, across) / -a0.z, off / rho, 1e-6 * off / rho);
    EXPECT_EQ(dot(a1, across), 0.0);
    EXPECT_EQ(dot(a1, axis), 0.0);
  }
}

// A particle thrown outwards at v = 1 m/s at the model base: with Coriolis on,
// it is pushed sideways by 2 omega v (444 m/s^2 here, 5.7 % of the field)
// against the sense of rotation, i.e. opposite to omega x r, the velocity of
// the model itself at that point; without Coriolis, not at all.
TEST(CentrifugeField, ParticleMovingOutwardsIsDeflectedAgainstTheRotationByTwoOmegaV) {
  for (const bool coriolis : {true, false}) {
    const BodyField f = BodyField::centrifuge(n, s, R_base, R_base, {}, {0, 1, 0}, coriolis);
    World w = free_particles(f);
    w.add_particle({0, 0, 0}, 1e-4, 2633);
    const double v = 1.0;
    w.particles_mut().velocity[0] = {0, 0, -v}; // outwards: away from the axis above
    const Vec3 a = measured_acceleration(w, 0);
    const Vec3 r = w.particles().position[0] - f.axis_point; // from the axis [m]
    const Vec3 rotation = f.omega_rad_s * f.axis_direction;  // omega [rad/s]
    const Vec3 model_motion = cross(rotation, r) / norm(cross(rotation, r));
    ASSERT_GT(norm(cross(rotation, r)), 0.0);
    if (coriolis) {
      EXPECT_NEAR(dot(a, model_motion), -2 * f.omega_rad_s * v, 2e-3 * 2 * f.omega_rad_s * v);
    } else {
      EXPECT_EQ(dot(a, model_motion), 0.0);
    }
    EXPECT_EQ(a.y, 0.0); // nothing along the axis
  }
}

} // namespace
} // namespace centridem
