// The contact law in SIMD lanes (contact_law<ContactLanes>, physics/lanes.hpp)
// gives every lane exactly the bits the scalar law (contact_law<double>) gives
// that contact alone: the engine computes ball-ball contacts in batches, and
// its results must not depend on which contacts share a batch (nor on the
// thread count). Checked over every branch of the law: the three models, both
// stiffness methods, the four dashpot modes, attraction inside and beyond its
// range (D0 > 0 and D0 = 0), limits on the net force, sticking and sliding,
// rolling below and at its limit, histories that are zero, along the normal,
// or turned by a large angle, and an overlap of exactly -0.
#include "physics/contact_law.hpp"
#include "physics/lanes.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace centridem {
namespace {

constexpr std::size_t W = ContactLanes::size;

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// Property sets covering the law's branches on its properties.
std::vector<ContactProperties> property_sets() {
  std::vector<ContactProperties> out;
  for (ContactModel model : {ContactModel::linear, ContactModel::rrlinear, ContactModel::arrlinear})
    for (StiffnessMethod method : {StiffnessMethod::deformability, StiffnessMethod::direct})
      for (int dashpots = 0; dashpots <= 4; ++dashpots) // 4: none
        for (int attraction = 0; attraction <= 2; ++attraction)
          for (bool net : {false, true}) {
            ContactProperties p;
            p.model = model;
            p.stiffness_method = method;
            p.effective_modulus_Pa = 3e8;
            p.stiffness_ratio = 1.5;
            p.normal_stiffness_N_per_m = 5e4;
            p.shear_stiffness_N_per_m = 5e4 / 1.5;
            p.friction = 0.5;
            p.rolling_friction = model == ContactModel::linear ? 0.0 : 0.16;
            if (dashpots < 4) {
              p.dashpot_normal_ratio = 0.3, p.dashpot_shear_ratio = 0.2, p.dashpot_mode = dashpots;
            }
            if (attraction > 0 && model == ContactModel::arrlinear) {
              p.attraction_force_N = 1.2e-4;
              p.attraction_range_m = attraction == 1 ? 5e-6 : 0.0;
            }
            p.limits_use_net_force = net;
            out.push_back(p);
          }
  return out;
}

struct Case {
  ContactGeometry g;
  ContactState s;
};

// W contacts, random, each also of one of eight kinds in turn (the counter
// runs across calls, so batches of 2 lanes see every kind as batches of 8 do).
std::array<Case, W> cases(std::mt19937_64& rng, std::size_t& counter) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto unit = [&] {
    Vec3 v{u(rng), u(rng), u(rng)};
    return v * (1.0 / norm(v));
  };
  auto vec = [&](double scale) { return Vec3{u(rng), u(rng), u(rng)} * scale; };
  std::array<Case, W> out{};
  for (std::size_t l = 0; l < W; ++l) {
    const Vec3 n = unit();
    const double R1 = 1e-4 * (1.5 + u(rng)), R2 = 1e-4 * (1.5 + u(rng));
    const double m1 = 2633 * 4.19 * R1 * R1 * R1, m2 = 2633 * 4.19 * R2 * R2 * R2;
    ContactGeometry g{
        n,       1e-6 * (1.2 + u(rng)), vec(1e-2),          vec(50.0), std::min(R1, R2),
        R1 + R2, R1 * R2 / (R1 + R2),   m1 * m2 / (m1 + m2)};
    // Stored history: in the plane, slightly off it, or (below) special;
    // its size is up to about twice the Coulomb limit, so some lanes slide.
    const Vec3 t = cross(n, unit());
    ContactState s{t * (3e-2 * u(rng)) + n * (1e-5 * u(rng)),
                   cross(n, unit()) * (2e-6 * u(rng)) + n * (1e-9 * u(rng))};
    switch (counter++ % 8) {
    case 0:
      s = ContactState{};
      break; // fresh contact
    case 1:
      s.shear_force = n * 1e-2;
      break; // history along the normal
    case 2:
      s.shear_force = s.shear_force + n * 1e-2;
      break; // large turn (exact rescale)
    case 3:
      g.overlap_m = -2e-6;
      break; // gap inside D0 = 5 um
    case 4:
      g.overlap_m = -8e-6;
      break; // gap beyond D0
    case 5:
      g.overlap_m = -0.0;
      break; // touching exactly
    case 6:
      s.rolling_moment = cross(n, unit()) * 1e-3;
      break; // rolling at its limit
    default:
      break;
    }
    out[l] = {g, s};
  }
  return out;
}

TEST(ContactLanes, EveryLaneGivesTheScalarLawsBits) {
  std::mt19937_64 rng(20261203);
  const std::vector<ContactProperties> sets = property_sets();
  const double dt = 1e-7;
  std::size_t compared = 0, sliding = 0;
  for (const ContactProperties& p : sets) {
    std::size_t counter = 0;
    for (std::size_t round = 0; round < 32 / W; ++round) {
      const std::array<Case, W> c = cases(rng, counter);
      // Scalar, one contact at a time.
      std::array<ContactResult, W> scalar{};
      std::array<ContactState, W> scalar_state{};
      for (std::size_t l = 0; l < W; ++l) {
        scalar_state[l] = c[l].s;
        scalar[l] = contact_law(p, c[l].g, scalar_state[l], dt);
      }
      // The same W contacts in one batch.
      alignas(64) double in[22][W];
      for (std::size_t l = 0; l < W; ++l) {
        const ContactGeometry& g = c[l].g;
        const double v[22] = {g.normal.x,
                              g.normal.y,
                              g.normal.z,
                              g.overlap_m,
                              g.relative_velocity.x,
                              g.relative_velocity.y,
                              g.relative_velocity.z,
                              g.relative_spin.x,
                              g.relative_spin.y,
                              g.relative_spin.z,
                              g.contact_radius_m,
                              g.contact_length_m,
                              g.rolling_radius_m,
                              g.effective_mass_kg,
                              c[l].s.shear_force.x,
                              c[l].s.shear_force.y,
                              c[l].s.shear_force.z,
                              c[l].s.rolling_moment.x,
                              c[l].s.rolling_moment.y,
                              c[l].s.rolling_moment.z,
                              0,
                              0};
        for (int q = 0; q < 22; ++q) in[q][l] = v[q];
      }
      auto L = [&](int q) { return ContactLanes::load_aligned(in[q]); };
      using LV = LaneVec<ContactLanes>;
      const ContactGeometryT<ContactLanes> g{LV{L(0), L(1), L(2)},
                                             L(3),
                                             LV{L(4), L(5), L(6)},
                                             LV{L(7), L(8), L(9)},
                                             L(10),
                                             L(11),
                                             L(12),
                                             L(13)};
      ContactStateT<ContactLanes> st{LV{L(14), L(15), L(16)}, LV{L(17), L(18), L(19)}};
      const ContactResultT<ContactLanes> res = contact_law(p, g, st, dt);
      alignas(64) double out[16][W];
      const ContactLanes outs[16] = {
          res.force.x,         res.force.y,       res.force.z,         res.moment.x,
          res.moment.y,        res.moment.z,      res.normal_force_N,  st.shear_force.x,
          st.shear_force.y,    st.shear_force.z,  st.rolling_moment.x, st.rolling_moment.y,
          st.rolling_moment.z, ContactLanes(0.0), ContactLanes(0.0),   ContactLanes(0.0)};
      for (int q = 0; q < 16; ++q) outs[q].store_aligned(out[q]);
      alignas(64) bool slides[W];
      res.sliding.store_aligned(slides);
      for (std::size_t l = 0; l < W; ++l) {
        const ContactResult& r = scalar[l];
        const ContactState& s = scalar_state[l];
        const double want[13] = {r.force.x,         r.force.y,          r.force.z,
                                 r.moment.x,        r.moment.y,         r.moment.z,
                                 r.normal_force_N,  s.shear_force.x,    s.shear_force.y,
                                 s.shear_force.z,   s.rolling_moment.x, s.rolling_moment.y,
                                 s.rolling_moment.z};
        for (int q = 0; q < 13; ++q)
          ASSERT_TRUE(same_bits(out[q][l], want[q]))
              << "output " << q << ", lane " << l << " of " << W << ": batch " << out[q][l]
              << ", scalar " << want[q] << " (model " << to_string(p.model) << ", dashpot mode "
              << p.dashpot_mode << ", F0 " << p.attraction_force_N << ", D0 "
              << p.attraction_range_m << ")";
        ASSERT_EQ(slides[l], r.sliding) << "lane " << l;
        ++compared;
        sliding += r.sliding ? 1 : 0;
      }
    }
  }
  // The cases reached both sides of the Coulomb limit.
  EXPECT_GT(sliding, compared / 10);
  EXPECT_LT(sliding, compared - compared / 10);
}

} // namespace
} // namespace centridem

namespace centridem {
// lane_bits (the neighbour search's SIMD distance test reads its mask as bits):
// for every pattern of true lanes of a comparison, bit l is set exactly when
// lane l holds.
TEST(ContactLanes, LaneBitsAreTheLanesThatHold) {
  constexpr std::size_t L = ContactLanes::size;
  alignas(64) double a[L], b[L];
  for (std::uint64_t pattern = 0; pattern < (std::uint64_t{1} << L); ++pattern) {
    for (std::size_t l = 0; l < L; ++l) {
      a[l] = static_cast<double>(l);
      b[l] = (pattern >> l & 1) ? a[l] + 1.0 : a[l] - 1.0;
    }
    EXPECT_EQ(lane_bits(ContactLanes::load_aligned(a) < ContactLanes::load_aligned(b)), pattern);
  }
}
} // namespace centridem
