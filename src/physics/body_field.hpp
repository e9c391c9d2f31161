// Body force fields. Uniform gravity now; the centrifuge field (radial
// acceleration growing with distance from the axis) is planned and will be a
// second alternative here, selected once per step, never per particle.
#pragma once

#include "core/vec3.hpp"

namespace centridem {

inline constexpr double standard_gravity_m_s2 = 9.80665; // g_n (CGPM 1901)

struct BodyField {
  Vec3 gravity_m_s2{}; // uniform acceleration [m/s^2]

  // Acceleration of a particle at x [m/s^2].
  Vec3 acceleration(const Vec3& /*x*/) const { return gravity_m_s2; }

  // Gravity of a centrifuge model of a model of a model (paper section 3.2):
  // n g / s along `down`, with n the g-level and s the size reduction factor.
  static BodyField scaled_gravity(double g_level, double size_reduction_factor,
                                  const Vec3& down = {0, 0, -1}) {
    return {down * (standard_gravity_m_s2 * g_level / size_reduction_factor)};
  }
};

} // namespace centridem
