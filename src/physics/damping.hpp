// Cundall's local non-viscous damping (PFC `damp`; PFC 7 manual, "Local
// Damping"): each component of the unbalanced force (or moment) is opposed by
// a force alpha |F| in the direction opposite to the velocity (or spin)
// component. F is the full unbalanced force, gravity included. [N or N m]
#pragma once

#include "base/vec3.hpp"

namespace centridem {

inline double sign_of(double v) {
  return (v > 0.0) - (v < 0.0);
}

inline Vec3 local_damping_force(const Vec3& unbalanced, const Vec3& velocity, double alpha) {
  return {-alpha * std::abs(unbalanced.x) * sign_of(velocity.x),
          -alpha * std::abs(unbalanced.y) * sign_of(velocity.y),
          -alpha * std::abs(unbalanced.z) * sign_of(velocity.z)};
}

} // namespace centridem
