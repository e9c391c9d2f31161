// Acceptance 10: contact history survives a neighbour rebuild in which the
// pair's order (end 1 / end 2) swaps. The stored shear force and rolling
// moment act on end 2 (contact_law.hpp), so when the ends swap they must
// change sign (Newton 3); the force and moment each particle feels must be
// the same before and after. With both balls frozen (fixed, no velocity, no
// spin) the contact law adds no increment, so the forces are exactly
// constant: equal to 1e-12 relative. Source: contact_law.hpp sign
// conventions; PFC keeps contact history through re-sorting.
#include "physics_test_util.hpp"

#include <gtest/gtest.h>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double R = 1e-3, rho = 2650, E = 1e8;

struct Snapshot {
  std::int64_t first_end = 0; // id of end 1 (i) of the contact
  Vec3 force_on_A, moment_on_A, moment_on_B;
};

// Ball B (id 1, added first) sits on ball A (id 2); the pair is sheared (B
// moves along x) and bent (B spins about y), then frozen. Third balls (ids
// >= 3, far from touching) are added below A, which moves the cell grid's
// origin until A sorts before B: the pair's ends swap. Force on A and the
// moments on A and B (shear lever arms + rolling moment) must not change.
TEST(PhysicsContactHistory, PairOrderSwapKeepsShearAndRollingHistory) {
  WorldSettings s;
  s.threads = 1;
  s.timestep_s = 1e-7;
  World w(s);
  w.set_ball_ball_defaults(props(ContactModel::rrlinear, E, 1.0, 1.0));
  const double overlap = 1e-3 * R;
  w.add_particle({0, 0, 2 * R - overlap}, R, rho, 0, 1); // B, above
  w.add_particle({0, 0, 0}, R, rho, 0, 2);               // A, below
  for (std::size_t i = 0; i < 2; ++i) w.particles_mut().flags[i] = fix_translation | fix_rotation;
  w.particles_mut().velocity[idx(w, 1)] = {0.01, 0.005, 0};
  w.particles_mut().spin[idx(w, 1)] = {2.0, 5.0, 0};
  w.cycle(300);
  for (std::size_t i = 0; i < 2; ++i) {
    w.particles_mut().velocity[i] = {};
    w.particles_mut().spin[i] = {};
  }

  auto snap = [&] {
    Snapshot out;
    const auto c = w.ball_ball_contacts();
    EXPECT_EQ(c.size(), 1u);
    if (c.size() != 1u) return out;
    out.first_end = w.particles().id[c[0].i];
    out.force_on_A = w.particles().id[c[0].j] == 2 ? c[0].force_on_j : -c[0].force_on_j;
    out.moment_on_A = w.particles().moment[idx(w, 2)];
    out.moment_on_B = w.particles().moment[idx(w, 1)];
    return out;
  };
  w.cycle(1);
  const Snapshot before = snap();
  ASSERT_EQ(before.first_end, 1) << "setup: B should be end 1 before the swap";
  // Not vacuous: a shear force and a rolling moment are stored.
  const double fn = norm(before.force_on_A);
  const double shear =
      norm(before.force_on_A - dot(before.force_on_A, Vec3{0, 0, 1}) * Vec3{0, 0, 1});
  ASSERT_GT(shear, 0.05 * fn);
  // Rolling moment on B: its moment minus the shear lever arm (B is above,
  // its contact arm points down, length R - overlap/2).
  const Vec3 arm_B{0, 0, -(R - 0.5 * overlap)};
  const Vec3 rolling_B = before.moment_on_B - cross(arm_B, -before.force_on_A);
  ASSERT_GT(norm(rolling_B), 0.01 * norm(before.moment_on_B));

  // Move the grid origin below A in small steps until the pair swaps.
  bool swapped = false;
  std::int64_t next_id = 3;
  for (int k = 1; k <= 60 && !swapped; ++k) {
    const double depth = 2.05 * R + 0.05 * R * k; // never touching A
    w.add_particle({0, 0, -depth}, R, rho, 0, next_id);
    w.particles_mut().flags[idx(w, next_id)] = fix_translation | fix_rotation;
    ++next_id;
    const long rebuilds = w.neighbour_rebuilds();
    w.request_rebuild();
    w.cycle(1);
    EXPECT_GT(w.neighbour_rebuilds(), rebuilds);
    const Snapshot after = snap();
    swapped = after.first_end == 2;
    const double f = norm(before.force_on_A), m = norm(before.moment_on_A);
    EXPECT_LT(rel(after.force_on_A, before.force_on_A, f), 1e-12) << "attempt " << k;
    EXPECT_LT(rel(after.moment_on_A, before.moment_on_A, m), 1e-12) << "attempt " << k;
    EXPECT_LT(rel(after.moment_on_B, before.moment_on_B, m), 1e-12) << "attempt " << k;
  }
  EXPECT_TRUE(swapped) << "the pair never swapped ends: the test did not test anything";
}

} // namespace
} // namespace centridem
