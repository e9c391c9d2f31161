// The contact law: PFC-compatible linear / rrlinear / arrlinear in one small,
// stateless, inlinable function. THIS FILE IS THE COMMENTED EXEMPLAR: a new
// contact model follows the same shape (see docs/ARCHITECTURE.md, "Adding a
// contact model"):
//
//   geometry (const, computed by the engine) + stored state + properties
//       -> force and pure moment on end 2 + new state
//
// The function touches no engine data: no particle arrays, no neighbour list,
// no globals. The engine computes the geometry of a ball-ball or a ball-wall
// pair, calls this, and applies the result (force on end 2, the opposite on
// end 1; moments from the lever arms plus the pure rolling moment). A wall is
// the infinite-radius, infinite-mass limit of a ball, so the same kernel
// serves both: ball-wall contacts differ only in the geometry the engine
// passes (contact radius, rolling radius, effective mass).
//
// Sign conventions: the normal n points from end 1 to end 2; the stored shear
// force and rolling moment are those acting ON END 2, in the global frame.
// Positive normal force is compressive (pushes end 2 along +n).
//
// Sources: PFC 7 manual, "Linear Model", "Rolling Resistance Linear Model";
// Gilabert, Roux & Castellanos (2007) Phys. Rev. E 75, 011303 for the
// attraction law; ../shared/DESIGN.md section "Physics".
#pragma once

#include "base/vec3.hpp"
#include "physics/contact_properties.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace centridem {

// Geometry of one pair at this step, computed by the engine.
struct ContactGeometry {
  Vec3 normal;              // unit normal, end 1 -> end 2
  double overlap_m;         // > 0 when the surfaces interpenetrate; < 0 is a gap [m]
  Vec3 relative_velocity;   // velocity of end 2 minus end 1 at the contact point [m/s]
  Vec3 relative_spin;       // omega2 - omega1 [rad/s]
  double contact_radius_m;  // r of the contact area A = pi r^2 (ball-ball: min(R1,R2); wall: R)
  double contact_length_m;  // L in kn = A E*/L (ball-ball: R1 + R2; ball-wall: R)
  double rolling_radius_m;  // R-bar = R1 R2/(R1+R2) (ball-wall: R)
  double effective_mass_kg; // mc = m1 m2/(m1+m2) (ball-wall: m); only read by dashpots
};

// History stored per contact, carried across steps and neighbour rebuilds.
struct ContactState {
  Vec3 shear_force;    // Fs on end 2 [N]
  Vec3 rolling_moment; // Mr on end 2 [N m]
};

// What the engine applies.
struct ContactResult {
  Vec3 force;            // total force on end 2 (normal + shear + dashpots) [N]
  Vec3 moment;           // pure moment on end 2 (rolling resistance) [N m]
  double normal_force_N; // signed normal force on end 2 along n (attraction < 0) [N]
  bool sliding;          // Coulomb limit reached this step
};

// Stiffnesses of a pair. PFC "deformability method": kn = A E*/L with A = pi r^2,
// ks = kn/kappa*; rolling stiffness kr = ks R-bar^2 (PFC rrlinear). [N/m, N/m, N m/rad]
struct ContactStiffness {
  double kn, ks, kr;
};

inline ContactStiffness contact_stiffness(const ContactProperties& p, const ContactGeometry& g) {
  double kn, ks;
  if (p.stiffness_method == StiffnessMethod::deformability) {
    const double area = std::numbers::pi * g.contact_radius_m * g.contact_radius_m;
    kn = area * p.effective_modulus_Pa / g.contact_length_m;
    ks = kn / p.stiffness_ratio;
  } else {
    kn = p.normal_stiffness_N_per_m;
    ks = p.shear_stiffness_N_per_m;
  }
  const double kr =
      p.model == ContactModel::linear ? 0.0 : ks * g.rolling_radius_m * g.rolling_radius_m;
  return {kn, ks, kr};
}

// Whether the properties use a dashpot (the engine then supplies the
// effective mass, which costs a division).
inline bool has_dashpot(const ContactProperties& p) {
  return p.dashpot_normal_ratio > 0.0 || p.dashpot_shear_ratio > 0.0;
}

// Whether a pair at this geometry is (still) a contact under properties p:
// overlapping, or an adhesive contact whose gap is below the attraction range.
inline bool contact_active(const ContactProperties& p, double overlap_m) {
  return overlap_m > 0.0 || (p.attraction_force_N > 0.0 && -overlap_m < p.attraction_range_m);
}

// Attraction (Gilabert et al. 2007, as DESIGN.md fixes it): F0 while the
// surfaces overlap, falling linearly to zero at gap D0. [N]
inline double attraction_force(const ContactProperties& p, double overlap_m) {
  if (p.attraction_force_N <= 0.0) return 0.0;
  if (overlap_m >= 0.0) return p.attraction_force_N;
  const double gap = -overlap_m;
  if (gap >= p.attraction_range_m) return 0.0;
  return p.attraction_force_N * (1.0 - gap / p.attraction_range_m);
}

// Potential energy of the attraction, U(d) = -integral_{-D0}^{d} F_att(x) dx,
// zero beyond the range, so that F_att = -dU/d(overlap) acts like a
// potential force: -F0 (D0 + d)^2/(2 D0) in the gap (-D0 < d < 0) and
// -F0 (D0/2 + d) while overlapping (D0 = 0: -F0 d). [J]
inline double attraction_potential(const ContactProperties& p, double overlap_m) {
  if (p.attraction_force_N <= 0.0) return 0.0;
  const double F0 = p.attraction_force_N, D0 = p.attraction_range_m;
  if (overlap_m >= 0.0) return -F0 * (0.5 * D0 + overlap_m);
  const double gap = -overlap_m;
  if (gap >= D0) return 0.0;
  return -F0 * (D0 - gap) * (D0 - gap) / (2.0 * D0);
}

// Rotate a stored vector into the plane normal to n, keeping its magnitude
// (the contact plane turns with the pair; PFC keeps shear force and rolling
// moment in the contact's local frame, which is this rotation).
inline Vec3 rotate_into_plane(const Vec3& v, const Vec3& n) {
  const double m0 = norm2(v);
  if (m0 == 0.0) return v;
  const double vn = dot(v, n);
  const Vec3 t = v - vn * n;
  const double m1 = m0 - vn * vn; // |t|^2
  if (!(m1 > 0.0)) return Vec3{};
  // Rescale to the old magnitude. The pair turns by a tiny angle per step,
  // so x = vn^2/m1 is tiny and sqrt(m0/m1) = sqrt(1 + x) ~ 1 + x/2 - x^2/8
  // to round-off; the exact form is kept for larger turns.
  const double x = vn * vn / m1;
  return t * (x < 1e-5 ? 1.0 + x * (0.5 - 0.125 * x) : std::sqrt(m0 / m1));
}

// One step of the contact law. dt is the timestep [s].
[[gnu::always_inline]] inline ContactResult
contact_law(const ContactProperties& p, const ContactGeometry& g, ContactState& state, double dt) {
  const Vec3& n = g.normal;
  const ContactStiffness k = contact_stiffness(p, g);

  // Normal: linear spring, never tensile by itself; attraction subtracts.
  const double spring_normal = k.kn * std::max(g.overlap_m, 0.0);
  const double attraction = attraction_force(p, g.overlap_m);
  const double limit_normal =
      std::max(p.limits_use_net_force ? spring_normal - attraction : spring_normal, 0.0);

  // Relative velocity split into normal (positive = separating) and tangential parts.
  const double vn = dot(g.relative_velocity, n);
  const Vec3 vt = g.relative_velocity - vn * n;

  // Shear: incremental Fs <- Fs - ks dUs with dUs = vt dt, Coulomb slip at mu Fn.
  Vec3 fs = rotate_into_plane(state.shear_force, n) - (k.ks * dt) * vt;
  const double fs_limit = p.friction * limit_normal;
  bool sliding = false;
  if (const double fs2 = norm2(fs); fs2 > fs_limit * fs_limit) {
    fs *= fs2 > 0.0 ? fs_limit / std::sqrt(fs2) : 0.0;
    sliding = true;
  }
  state.shear_force = fs;

  // Dashpots (PFC dp_nratio, dp_sratio): c = 2 beta sqrt(mc k).
  double dashpot_normal = 0.0;
  Vec3 dashpot_shear{};
  if (p.dashpot_normal_ratio > 0.0) {
    dashpot_normal = -2.0 * p.dashpot_normal_ratio * std::sqrt(g.effective_mass_kg * k.kn) * vn;
    if (p.dashpot_mode == 1 || p.dashpot_mode == 3) // no-tension: spring + dashpot >= 0
      dashpot_normal = std::max(dashpot_normal, -spring_normal);
  }
  if (p.dashpot_shear_ratio > 0.0 && !(sliding && (p.dashpot_mode >= 2)))
    dashpot_shear = (-2.0 * p.dashpot_shear_ratio * std::sqrt(g.effective_mass_kg * k.ks)) * vt;

  // Rolling resistance (PFC rrlinear): Mr <- Mr - kr dTheta_b, |Mr| <= mu_r R-bar Fn.
  // Only the bending part of the relative rotation is resisted, not the twist.
  Vec3 moment{};
  if (k.kr > 0.0) {
    const Vec3 dtheta = g.relative_spin * dt;
    const Vec3 dtheta_bend = dtheta - dot(dtheta, n) * n;
    Vec3 mr = rotate_into_plane(state.rolling_moment, n) - k.kr * dtheta_bend;
    const double mr_limit = p.rolling_friction * g.rolling_radius_m * limit_normal;
    if (const double mr2 = norm2(mr); mr2 > mr_limit * mr_limit)
      mr *= mr2 > 0.0 ? mr_limit / std::sqrt(mr2) : 0.0;
    state.rolling_moment = mr;
    moment = mr;
  }

  const double normal = spring_normal - attraction + dashpot_normal;
  return {normal * n + fs + dashpot_shear, moment, normal, sliding};
}

} // namespace centridem
