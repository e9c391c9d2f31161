// The moisture grading of the attraction F0 at the cut (procedures/slope_trial.hpp,
// grade_attraction_by_height; [moisture] in docs/slope.md): a vertical chain of touching balls,
// its contacts at known heights, graded in 4 bands over a height H with F0 x 1.5 at the bottom
// and x 0.5 at the top. Closed form: the contact whose mean centre height z lies in band
// b = floor(4 z / H) (the end bands extended below 0 and above H) carries
// F0 x (1.5 - (b + 0.5) / 4), that is 1.375, 1.125, 0.875 and 0.625 F0; nothing else changes.
#include "engine/world.hpp"
#include "io/slope_config.hpp"
#include "procedures/paper_material.hpp"
#include "procedures/slope_trial.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>

namespace centridem {
namespace {

TEST(Moisture, AttractionIsGradedByTheHeightOfEachContact) {
  WorldSettings s;
  s.threads = 1;
  World w(s);
  const ContactProperties base = paper::ball_ball();
  ASSERT_GT(base.attraction_force_N, 0.0);
  w.set_ball_ball_defaults(base);
  const double R = 1e-3, step = 1.99e-3; // overlap 0.01 mm: every neighbour in contact
  for (int k = 0; k < 10; ++k) w.add_particle({0, 0, R + k * step}, R, 2650, 0, k);
  w.cycle(1);
  const double H = 16e-3; // the highest contacts (z = 17.9 mm) lie above H: the top band
  MoistureSpec m;
  m.enabled = true;
  m.bottom_factor = 1.5;
  m.top_factor = 0.5;
  m.bands = 4;
  const std::size_t changed = grade_attraction_by_height(w, base, m, H);
  const auto contacts = w.ball_ball_contacts();
  ASSERT_EQ(contacts.size(), 9u);
  EXPECT_EQ(changed, 9u);
  const auto& P = w.particles();
  int per_band[4] = {0, 0, 0, 0};
  for (const ContactView& c : contacts) {
    const double z = 0.5 * (P.position[c.i].z + P.position[c.j].z);
    const int b = std::clamp(static_cast<int>(std::floor(4 * z / H)), 0, 3);
    ++per_band[b];
    const double expected = base.attraction_force_N * (1.5 - (b + 0.5) / 4);
    const ContactProperties& got = w.property_set(c.properties);
    EXPECT_NEAR(got.attraction_force_N, expected, 1e-15) << "contact at z = " << z;
    // Only F0 is graded.
    EXPECT_EQ(got.friction, base.friction);
    EXPECT_EQ(got.rolling_friction, base.rolling_friction);
    EXPECT_EQ(got.effective_modulus_Pa, base.effective_modulus_Pa);
  }
  // Not vacuous: every band holds contacts.
  for (int b = 0; b < 4; ++b) EXPECT_GT(per_band[b], 0) << "band " << b;
}

} // namespace
} // namespace centridem
