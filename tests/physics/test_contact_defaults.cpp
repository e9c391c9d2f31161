// Acceptance 8: contact defaults by stage (PFC's contact model assignment
// table; DESIGN.md "Physics"): a new contact copies the current ball-ball
// defaults, an existing one keeps the properties it was born with, across
// later changes of the defaults and across neighbour rebuilds. The physics
// follows the stored set: an adhesive pair at rest has overlap F0/kn with
// its own F0 (see test_adhesion.cpp for the derivation).
#include "physics_test_util.hpp"
#include "procedures/paper_material.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace centridem {
namespace {
using namespace phys_test;

constexpr double R = 1e-3, rho = 2633;

// Pair A (ids 1, 2) touches under defaults D1 (F0 = 1e-3 N, mu_r = 0.16);
// then the defaults become D2 (F0 = 4e-3 N, mu_r = 0.05) and pair B (ids 3,
// 4) is created. A keeps F0, mu_r of D1, B gets D2, exactly, before and
// after a forced rebuild; at rest (damping 0.7) each pair's overlap is its
// own F0/kn within 1 %.
TEST(PhysicsContactDefaults, ExistingContactsKeepTheirPropertiesNewOnesGetTheNewDefaults) {
  WorldSettings s;
  s.threads = 1;
  s.local_damping = 0.7;
  World w(s);
  ContactProperties d1 = paper::ball_ball(1e-3);
  d1.rolling_friction = 0.16;
  ContactProperties d2 = d1;
  d2.attraction_force_N = 4e-3;
  d2.rolling_friction = 0.05;
  const double kn = kn_ball_ball(d1.effective_modulus_Pa, R, R);
  w.set_ball_ball_defaults(d1);
  w.add_particle({0, 0, 0}, R, rho, 0, 1);
  w.add_particle({2 * R - 1e-9, 0, 0}, R, rho, 0, 2);
  w.cycle(100);
  ASSERT_EQ(w.ball_ball_contacts().size(), 1u);

  w.set_ball_ball_defaults(d2);
  w.add_particle({0, 10 * R, 0}, R, rho, 0, 3);
  w.add_particle({2 * R - 1e-9, 10 * R, 0}, R, rho, 0, 4);

  auto check = [&](const char* when) {
    const auto contacts = w.ball_ball_contacts();
    ASSERT_EQ(contacts.size(), 2u) << when;
    for (const ContactView& c : contacts) {
      const std::int64_t a = w.particles().id[c.i], b = w.particles().id[c.j];
      const ContactProperties& p = w.property_set(c.properties);
      const ContactProperties& expected = std::min(a, b) == 1 ? d1 : d2;
      EXPECT_EQ(p.attraction_force_N, expected.attraction_force_N) << when << " pair " << a;
      EXPECT_EQ(p.rolling_friction, expected.rolling_friction) << when << " pair " << a;
      EXPECT_TRUE(p == expected) << when << " pair " << a;
      EXPECT_NEAR(c.overlap_m / (expected.attraction_force_N / kn), 1.0, 0.01)
          << when << " pair " << a;
    }
  };
  w.cycle(20000);
  check("after the change of defaults");
  w.request_rebuild();
  w.cycle(10);
  check("after a rebuild");
  EXPECT_TRUE(w.ball_ball_defaults() == d2);
}

} // namespace
} // namespace centridem
