// Body force fields: uniform gravity, or the field of a geotechnical
// centrifuge (centrifugal acceleration growing with distance from the axis,
// plus optional Coriolis). The kind is a plain tag tested per particle (the
// branch is loop-invariant); the struct is trivially copyable (checkpoints).
#pragma once

#include "base/vec3.hpp"

#include <cmath>
#include <cstdint>

namespace centridem {

inline constexpr double standard_gravity_m_s2 = 9.80665; // g_n (CGPM 1901)

struct BodyField {
  enum class Kind : std::uint8_t { uniform, centrifuge };
  Vec3 gravity_m_s2{}; // uniform: the acceleration [m/s^2] (first: BodyField{g} is uniform)
  Kind kind = Kind::uniform;
  // centrifuge: rotation about the line through axis_point along axis_direction
  Vec3 axis_point;              // a point on the rotation axis [m]
  Vec3 axis_direction{1, 0, 0}; // unit vector along the axis (right-hand rule gives the sense)
  double omega_rad_s = 0.0;     // angular speed [rad/s]
  bool coriolis = false;        // add -2 omega x v

  // Acceleration of a particle at x moving with v [m/s^2].
  Vec3 acceleration(const Vec3& x, const Vec3& v) const {
    if (kind == Kind::uniform) return gravity_m_s2;
    // Centrifugal: omega^2 times the perpendicular vector from the axis to x.
    const Vec3 r = x - axis_point;
    const Vec3 rho = r - dot(r, axis_direction) * axis_direction;
    Vec3 a = (omega_rad_s * omega_rad_s) * rho;
    if (coriolis) a -= 2.0 * omega_rad_s * cross(axis_direction, v);
    return a;
  }

  // Gravity of a centrifuge model of a model (paper section 3.2): n g / s
  // along `down`, with n the g-level and s the size reduction factor.
  static BodyField scaled_gravity(double g_level, double size_reduction_factor,
                                  const Vec3& down = {0, 0, -1}) {
    BodyField f;
    f.gravity_m_s2 = down * (standard_gravity_m_s2 * g_level / size_reduction_factor);
    return f;
  }

  // The field of a beam centrifuge spinning a model (z up, towards the axis)
  // at g-level n measured at the reference radius, for a DEM model s times
  // smaller than the centrifuge model (the radii scale by s too, so the field
  // varies over the DEM model's height as over the real model's):
  //   omega^2 = n g / (s^2 R_ref),  so |a| = n g / s at DEM radius s R_ref.
  // The axis lies s R_base above the model base point `base_point` (R_base:
  // real radius of the model base), along `axis_direction` (horizontal).
  static BodyField centrifuge(double g_level, double size_reduction_factor,
                              double reference_radius_m, double base_radius_m,
                              const Vec3& base_point, const Vec3& axis_direction = {0, 1, 0},
                              bool coriolis = false) {
    BodyField f;
    f.kind = Kind::centrifuge;
    const double s = size_reduction_factor;
    f.omega_rad_s = std::sqrt(g_level * standard_gravity_m_s2 / (s * s * reference_radius_m));
    f.axis_direction = axis_direction / norm(axis_direction);
    f.axis_point = base_point + Vec3{0, 0, s * base_radius_m};
    f.coriolis = coriolis;
    return f;
  }
};

} // namespace centridem
