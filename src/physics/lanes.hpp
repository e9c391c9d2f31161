// Lanes: the few operations the contact law needs, for one contact (double)
// or for a batch of contacts side by side in SIMD registers
// (xsimd::batch<double>, Debian's libxsimd-dev: 8 doubles with AVX-512, 4
// with AVX2, 2 with SSE2). The law (contact_law.hpp) is written once on these
// and instantiated for both, so the formulas live in one place.
//
// Each lane of a batch performs the same IEEE operations, in the same order,
// as the scalar code, and the engine is built without contraction into fused
// multiply-adds (-ffp-contract=off): a contact's result is the same bits
// whether it was computed alone or in any lane of any batch. Conditionals are
// written as selects between the results of both sides; the helpers below
// reproduce std::max / std::min exactly (which operand wins on ties, signed
// zeros and NaN), not the instructions' own rules.
#pragma once

#include "base/vec3.hpp"

#include <cmath>
#include <cstdint>
#include <type_traits>
// GCC 12 warns that the intentionally undefined first operand of the AVX-512
// intrinsics xsimd calls (_mm512_undefined_pd) "may be used uninitialized";
// it is not read. Off for the lines of those headers only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <xsimd/xsimd.hpp>
#pragma GCC diagnostic pop

namespace centridem {

// The batch the engine computes contacts in: the widest the build's target has.
using ContactLanes = xsimd::batch<double>;

// A 3-vector of batches: component k of lane l is contact l's component k.
template <class T> struct LaneVec3 {
  T x{}, y{}, z{};

  friend LaneVec3 operator+(const LaneVec3& a, const LaneVec3& b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
  }
  friend LaneVec3 operator-(const LaneVec3& a, const LaneVec3& b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
  }
  friend LaneVec3 operator-(const LaneVec3& a) { return {-a.x, -a.y, -a.z}; }
  friend LaneVec3 operator*(const LaneVec3& a, const T& s) { return {a.x * s, a.y * s, a.z * s}; }
  friend LaneVec3 operator*(const T& s, const LaneVec3& a) { return {a.x * s, a.y * s, a.z * s}; }
  friend T dot(const LaneVec3& a, const LaneVec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
  friend LaneVec3 cross(const LaneVec3& a, const LaneVec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
  }
  friend T norm2(const LaneVec3& a) { return dot(a, a); }
};

// The vector and mask types of a lane type: Vec3 and bool for one contact.
template <class T> struct LaneTypes {
  using Vec = LaneVec3<T>;
  using Mask = typename T::batch_bool_type;
};
template <> struct LaneTypes<double> {
  using Vec = Vec3;
  using Mask = bool;
};
template <class T> using LaneVec = typename LaneTypes<T>::Vec;
template <class T> using LaneMask = typename LaneTypes<T>::Mask;

// select(m, a, b): a where m holds, b elsewhere.
inline double select(bool m, double a, double b) {
  return m ? a : b;
}
inline Vec3 select(bool m, const Vec3& a, const Vec3& b) {
  return m ? a : b;
}
template <class T>
LaneVec3<T> select(const typename T::batch_bool_type& m, const LaneVec3<T>& a,
                   const LaneVec3<T>& b) {
  return {xsimd::select(m, a.x, b.x), xsimd::select(m, a.y, b.y), xsimd::select(m, a.z, b.z)};
}
using xsimd::select;

// Whether the mask holds in any lane (for one contact: the mask itself).
inline bool any_lane(bool m) {
  return m;
}
template <class B> bool any_lane(const xsimd::batch_bool<double, B>& m) {
  return xsimd::any(m);
}

// The lanes where m holds, as bits: lane l is bit l.
template <class B> std::uint64_t lane_bits(const xsimd::batch_bool<double, B>& m) {
  using Mask = xsimd::batch_bool<double, B>;
  if constexpr (std::is_base_of_v<xsimd::avx512f, B>) { // the mask register itself
    return static_cast<typename Mask::register_type>(m);
  } else {
    alignas(64) bool lane[Mask::size];
    m.store_aligned(lane);
    std::uint64_t bits = 0;
    for (std::size_t l = 0; l < Mask::size; ++l) bits |= std::uint64_t{lane[l]} << l;
    return bits;
  }
}

inline double lane_sqrt(double a) {
  return std::sqrt(a);
}
template <class B> xsimd::batch<double, B> lane_sqrt(const xsimd::batch<double, B>& a) {
  return xsimd::sqrt(a);
}

// std::max(a, b) and std::min(a, b), lane by lane, with their exact rules.
template <class T> T lane_max(const T& a, const T& b) {
  return select(a < b, b, a);
}
template <class T> T lane_min(const T& a, const T& b) {
  return select(b < a, b, a);
}

} // namespace centridem
