// The paper's material (Tao et al., Table 1; ../shared/REFERENCE.md): the
// adhesive rolling resistance linear model between balls and a linear model
// against walls. Used as defaults by examples and the benchmark; every value
// can be overridden in a scenario.
#pragma once

#include "physics/contact_properties.hpp"

namespace centridem::paper {

inline constexpr double density_kg_m3 = 2633.0;
inline constexpr double local_damping = 0.7;

inline ContactProperties ball_ball(double attraction_force_N = 1.2e-4) {
  ContactProperties p;
  p.model = ContactModel::arrlinear;
  p.effective_modulus_Pa = 300e6;
  p.stiffness_ratio = 1.5;
  p.friction = 0.5;
  p.rolling_friction = 0.16;
  p.attraction_force_N = attraction_force_N;
  p.attraction_range_m = 0.0;
  return p;
}

inline ContactProperties ball_wall(double friction = 0.0) {
  ContactProperties p;
  p.model = ContactModel::linear;
  p.effective_modulus_Pa = 1e9;
  p.stiffness_ratio = 1.5;
  p.friction = friction;
  return p;
}

} // namespace centridem::paper
