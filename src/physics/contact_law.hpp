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
// The law is written once for a lane type T (physics/lanes.hpp): T = double is
// one contact, T = ContactLanes a batch of contacts side by side in SIMD
// registers with per-lane geometry and state and one set of properties. The
// branches on the properties are ordinary ifs; those on the geometry are
// selects, which give each lane what the scalar branch would, bit for bit.
//
// Sources: PFC 7 manual, "Linear Model", "Rolling Resistance Linear Model";
// Gilabert, Roux & Castellanos (2007) Phys. Rev. E 75, 011303 for the
// attraction law; ../shared/DESIGN.md section "Physics".
#pragma once

#include "base/vec3.hpp"
#include "physics/contact_properties.hpp"
#include "physics/lanes.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace centridem {

// Geometry of one pair (or of one pair per lane) at this step, computed by the engine.
template <class T> struct ContactGeometryT {
  LaneVec<T> normal;            // unit normal, end 1 -> end 2
  T overlap_m;                  // > 0 when the surfaces interpenetrate; < 0 is a gap [m]
  LaneVec<T> relative_velocity; // velocity of end 2 minus end 1 at the contact point [m/s]
  LaneVec<T> relative_spin;     // omega2 - omega1 [rad/s]
  T contact_radius_m;           // r of the contact area A = pi r^2 (ball-ball: min(R1,R2); wall: R)
  T contact_length_m;           // L in kn = A E*/L (ball-ball: R1 + R2; ball-wall: R)
  T rolling_radius_m;           // R-bar = R1 R2/(R1+R2) (ball-wall: R)
  T effective_mass_kg;          // mc = m1 m2/(m1+m2) (ball-wall: m); only read by dashpots
};
using ContactGeometry = ContactGeometryT<double>;

// History stored per contact, carried across steps and neighbour rebuilds.
template <class T> struct ContactStateT {
  LaneVec<T> shear_force;    // Fs on end 2 [N]
  LaneVec<T> rolling_moment; // Mr on end 2 [N m]
};
using ContactState = ContactStateT<double>;

// What the engine applies.
template <class T> struct ContactResultT {
  LaneVec<T> force;    // total force on end 2 (normal + shear + dashpots) [N]
  LaneVec<T> moment;   // pure moment on end 2 (rolling resistance) [N m]
  T normal_force_N;    // signed normal force on end 2 along n (attraction < 0) [N]
  LaneMask<T> sliding; // Coulomb limit reached this step
};
using ContactResult = ContactResultT<double>;

// Stiffnesses of a pair. PFC "deformability method": kn = A E*/L with A = pi r^2,
// ks = kn/kappa*; rolling stiffness kr = ks R-bar^2 (PFC rrlinear). [N/m, N/m, N m/rad]
template <class T> struct ContactStiffnessT { T kn, ks, kr; };
using ContactStiffness = ContactStiffnessT<double>;

template <class T>
ContactStiffnessT<T> contact_stiffness(const ContactProperties& p, const ContactGeometryT<T>& g) {
  T kn, ks;
  if (p.stiffness_method == StiffnessMethod::deformability) {
    const T area = T(std::numbers::pi) * g.contact_radius_m * g.contact_radius_m;
    kn = area * T(p.effective_modulus_Pa) / g.contact_length_m;
    ks = kn / T(p.stiffness_ratio);
  } else {
    kn = T(p.normal_stiffness_N_per_m);
    ks = T(p.shear_stiffness_N_per_m);
  }
  const T kr =
      p.model == ContactModel::linear ? T(0.0) : ks * g.rolling_radius_m * g.rolling_radius_m;
  return {kn, ks, kr};
}

// Whether the properties use a dashpot (the engine then supplies the
// effective mass, which costs a division).
inline bool has_dashpot(const ContactProperties& p) {
  return p.dashpot_normal_ratio > 0.0 || p.dashpot_shear_ratio > 0.0;
}

// Whether a pair at this geometry is (still) a contact under properties p:
// overlapping, or an adhesive contact whose gap is below the attraction range.
template <class T> LaneMask<T> contact_active(const ContactProperties& p, const T& overlap_m) {
  if (!(p.attraction_force_N > 0.0)) return overlap_m > T(0.0);
  return overlap_m > T(0.0) || -overlap_m < T(p.attraction_range_m);
}

// Attraction (Gilabert et al. 2007, as DESIGN.md fixes it): F0 while the
// surfaces overlap, falling linearly to zero at gap D0. [N]
template <class T> T attraction_force(const ContactProperties& p, const T& overlap_m) {
  if (p.attraction_force_N <= 0.0) return T(0.0);
  const T F0(p.attraction_force_N), D0(p.attraction_range_m);
  const T gap = -overlap_m;
  const T in_gap = F0 * (T(1.0) - gap / D0); // not read where the gap is >= D0 (D0 = 0 too)
  return select(overlap_m >= T(0.0), F0, select(gap >= D0, T(0.0), in_gap));
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
// moment in the contact's local frame, which is this rotation). A zero
// vector stays zero; one along n (no tangential part left) becomes zero.
template <class V> [[gnu::always_inline]] inline V rotate_into_plane(const V& v, const V& n) {
  using T = decltype(dot(v, n));
  const T m0 = norm2(v);
  const T vn = dot(v, n);
  const V t = v - vn * n;
  const T m1 = m0 - vn * vn; // |t|^2
  // Rescale to the old magnitude. The pair turns by a tiny angle per step,
  // so x = vn^2/m1 is tiny and sqrt(m0/m1) = sqrt(1 + x) ~ 1 + x/2 - x^2/8
  // to round-off; the exact form is kept for larger turns.
  const T x = vn * vn / m1;
  T scale = T(1.0) + x * (T(0.5) - T(0.125) * x);
  if (const auto large = !(x < T(1e-5)); any_lane(large))
    scale = select(large, lane_sqrt(m0 / m1), scale);
  return select(m0 == T(0.0), v, select(!(m1 > T(0.0)), V{}, t * scale));
}

// One step of the contact law. dt is the timestep [s].
template <class T>
[[gnu::always_inline]] inline ContactResultT<T> contact_law(const ContactProperties& p,
                                                            const ContactGeometryT<T>& g,
                                                            ContactStateT<T>& state, double dt) {
  using V = LaneVec<T>;
  const V& n = g.normal;
  const ContactStiffnessT<T> k = contact_stiffness(p, g);

  // Normal: linear spring, never tensile by itself; attraction subtracts.
  const T spring_normal = k.kn * lane_max(g.overlap_m, T(0.0));
  const T attraction = attraction_force(p, g.overlap_m);
  const T limit_normal =
      lane_max(p.limits_use_net_force ? spring_normal - attraction : spring_normal, T(0.0));

  // Relative velocity split into normal (positive = separating) and tangential parts.
  const T vn = dot(g.relative_velocity, n);
  const V vt = g.relative_velocity - vn * n;

  // Shear: incremental Fs <- Fs - ks dUs with dUs = vt dt, Coulomb slip at mu Fn.
  V fs = rotate_into_plane(state.shear_force, n) - (k.ks * T(dt)) * vt;
  const T fs_limit = T(p.friction) * limit_normal;
  const T fs2 = norm2(fs);
  const LaneMask<T> sliding = fs2 > fs_limit * fs_limit;
  if (any_lane(sliding))
    fs = select(sliding, fs * select(fs2 > T(0.0), fs_limit / lane_sqrt(fs2), T(0.0)), fs);
  state.shear_force = fs;

  // Dashpots (PFC dp_nratio, dp_sratio): c = 2 beta sqrt(mc k).
  T dashpot_normal(0.0);
  V dashpot_shear{};
  if (p.dashpot_normal_ratio > 0.0) {
    dashpot_normal = T(-2.0 * p.dashpot_normal_ratio) * lane_sqrt(g.effective_mass_kg * k.kn) * vn;
    if (p.dashpot_mode == 1 || p.dashpot_mode == 3) // no-tension: spring + dashpot >= 0
      dashpot_normal = lane_max(dashpot_normal, -spring_normal);
  }
  if (p.dashpot_shear_ratio > 0.0) {
    const V c_vt = (T(-2.0 * p.dashpot_shear_ratio) * lane_sqrt(g.effective_mass_kg * k.ks)) * vt;
    dashpot_shear = p.dashpot_mode >= 2 ? select(sliding, V{}, c_vt) : c_vt; // off while sliding
  }

  // Rolling resistance (PFC rrlinear): Mr <- Mr - kr dTheta_b, |Mr| <= mu_r R-bar Fn.
  // Only the bending part of the relative rotation is resisted, not the twist.
  V moment{};
  if (p.model != ContactModel::linear) {
    if (const LaneMask<T> rolls = k.kr > T(0.0); any_lane(rolls)) {
      const V dtheta = g.relative_spin * T(dt);
      const V dtheta_bend = dtheta - dot(dtheta, n) * n;
      V mr = rotate_into_plane(state.rolling_moment, n) - k.kr * dtheta_bend;
      const T mr_limit = T(p.rolling_friction) * g.rolling_radius_m * limit_normal;
      const T mr2 = norm2(mr);
      if (const LaneMask<T> over = mr2 > mr_limit * mr_limit; any_lane(over))
        mr = select(over, mr * select(mr2 > T(0.0), mr_limit / lane_sqrt(mr2), T(0.0)), mr);
      state.rolling_moment = select(rolls, mr, state.rolling_moment);
      moment = select(rolls, mr, V{});
    }
  }

  const T normal = spring_normal - attraction + dashpot_normal;
  return {normal * n + fs + dashpot_shear, moment, normal, sliding};
}

} // namespace centridem
