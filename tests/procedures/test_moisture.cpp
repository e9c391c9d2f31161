// Moisture-graded adhesion (physics/moisture.hpp, procedures/moisture.hpp; [moisture] in
// docs/slope.md).
//
// 1. The older linear reading (top_factor / bottom_factor): a vertical chain of touching balls,
// its contacts at known heights, graded in 4 bands over a height H with F0 x 1.5 at the bottom
// and x 0.5 at the top. Closed form: the contact whose mean centre height z lies in band
// b = floor(4 z / H) (the end bands extended below 0 and above H) carries
// F0 x (1.5 - (b + 0.5) / 4), that is 1.375, 1.125, 0.875 and 0.625 F0; nothing else changes.
#include "engine/world.hpp"
#include "io/checkpoint.hpp"
#include "procedures/moisture.hpp"
#include "procedures/paper_material.hpp"
#include "procedures/slope_config.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <gtest/gtest.h>
#include <unistd.h>

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
  m.adhesion = MoistureSpec::Adhesion::linear_factor;
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

// 2. The water content and the law of F0 against it, by hand: the default
// profile is the centrifuge test's 9.2 / 7.3 / 5.5 % at floor / middle / crest,
// linear between (so 8.25 % at a quarter height, 6.4 % at three quarters) and
// constant beyond; "proportional" divides by the shear box's 6 %, "constant"
// is 1, "table" interpolates its points.
TEST(Moisture, WaterContentProfileAndTheLawsOfAdhesionAgainstIt) {
  MoistureSpec m;
  EXPECT_DOUBLE_EQ(water_content_percent(m, 0.0), 9.2);
  EXPECT_NEAR(water_content_percent(m, 0.25), 8.25, 1e-12);
  EXPECT_DOUBLE_EQ(water_content_percent(m, 0.5), 7.3);
  EXPECT_NEAR(water_content_percent(m, 0.75), 6.4, 1e-12);
  EXPECT_DOUBLE_EQ(water_content_percent(m, 1.0), 5.5);
  EXPECT_DOUBLE_EQ(water_content_percent(m, -0.3), 9.2);
  EXPECT_DOUBLE_EQ(water_content_percent(m, 1.7), 5.5);
  EXPECT_EQ(m.adhesion, MoistureSpec::Adhesion::proportional) << "the documented default";
  EXPECT_NEAR(attraction_factor(m, 0.25), 8.25 / 6.0, 1e-12);
  EXPECT_NEAR(attraction_factor(m, 1.0), 5.5 / 6.0, 1e-12);
  m.adhesion = MoistureSpec::Adhesion::constant;
  EXPECT_EQ(attraction_factor(m, 0.25), 1.0);
  m.adhesion = MoistureSpec::Adhesion::table;
  m.table = {{5.0, 0.5}, {7.0, 1.0}, {9.0, 2.0}};
  EXPECT_NEAR(attraction_factor(m, 0.75), 0.5 + 0.25 * 1.4, 1e-12); // w = 6.4 %
  EXPECT_NEAR(attraction_factor(m, 0.25), 1.0 + 0.5 * 1.25, 1e-12); // w = 8.25 %
  EXPECT_DOUBLE_EQ(attraction_factor(m, 0.0), 2.0);                 // w = 9.2 %: past the end
  // Bands take the factor at their middle: 4 bands at 1/8, 3/8, 5/8, 7/8.
  m.adhesion = MoistureSpec::Adhesion::proportional;
  m.bands = 4;
  const std::vector<double> f = band_attraction_factors(m);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_NEAR(f[0], (9.2 - 1.9 / 4) / 6, 1e-12);
  EXPECT_NEAR(f[3], (7.3 - 1.8 * 3 / 4) / 6, 1e-12);
}

// 3. Contacts made at different heights carry the F0 of their height, and a
// contact made after the cut takes the F0 of where it is made, also in a World
// read back from a checkpoint. The cut: a chain of touching balls graded as it
// stands (proportional law, default profile, 4 bands over H), then the
// after-cut defaults (mu_r = 0) graded for new contacts. Then pairs of
// overlapping balls are added far from the chain at three heights: in the
// lowest band, the highest, and above the model (the highest band extends up);
// each contact born at the next step must carry F0 x factor(band) and the
// after-cut rolling friction. A fresh set_ball_ball_defaults removes the grading.
TEST(Moisture, ContactsMadeAfterTheCutTakeTheF0OfTheirHeight) {
  WorldSettings s;
  s.threads = 1;
  World w(s);
  const ContactProperties soil = paper::ball_ball();
  ContactProperties after_cut = soil;
  after_cut.rolling_friction = 0.0;
  w.set_ball_ball_defaults(soil);
  w.set_fixed_timestep(1e-9);
  const double R = 1e-3, step = 1.99e-3, H = 16e-3;
  for (int k = 0; k < 8; ++k) w.add_particle({0, 0, R + k * step}, R, 2650, 0, k);
  w.cycle(1);
  MoistureSpec m;
  m.enabled = true;
  m.bands = 4;
  const std::vector<double> factor = band_attraction_factors(m);
  EXPECT_EQ(grade_attraction_by_height(w, soil, m, H), 7u);
  w.set_ball_ball_defaults(after_cut);
  grade_new_contacts_by_height(w, after_cut, m, H);

  auto band_of = [&](double z) {
    return std::clamp(static_cast<int>(std::floor(4 * z / H)), 0, 3);
  };
  std::int64_t next_id = 100;
  auto add_pair = [&](World& world, double x, double z) {
    world.add_particle({x, 0, z}, R, 2650, 0, next_id++);
    world.add_particle({x + 2 * R - 1e-5, 0, z}, R, 2650, 0, next_id++);
  };
  // Every contact's F0 against its band; the new ones (not on the chain's
  // axis x = 0) also carry the after-cut rule. Returns how many new ones.
  auto check = [&](const World& world, const std::string& when) {
    const auto& P = world.particles();
    int fresh = 0;
    for (const ContactView& c : world.ball_ball_contacts()) {
      const double z = 0.5 * (P.position[c.i].z + P.position[c.j].z);
      const ContactProperties& got = world.property_set(c.properties);
      EXPECT_NEAR(got.attraction_force_N, soil.attraction_force_N * factor[band_of(z)], 1e-15)
          << when << ": contact at z = " << z;
      if (P.position[c.i].x > 1e-3) {
        ++fresh;
        EXPECT_EQ(got.rolling_friction, 0.0) << when << ": the after-cut rule";
      } else {
        EXPECT_EQ(got.rolling_friction, soil.rolling_friction) << when << ": made before the cut";
      }
    }
    return fresh;
  };
  add_pair(w, 0.01, 1.5e-3); // band 0: F0 x 1.454
  add_pair(w, 0.02, 15e-3);  // band 3: F0 x 0.992
  add_pair(w, 0.03, 40e-3);  // above the model: band 3
  w.cycle(1);
  EXPECT_EQ(check(w, "after the cut"), 3);
  EXPECT_GT(factor[0], 1.4 * factor[3]) << "not vacuous: the bands differ";

  // The grading survives a checkpoint.
  const std::string path =
      (std::filesystem::temp_directory_path() / ("moisture_" + std::to_string(::getpid()) + ".bin"))
          .string();
  write_checkpoint(w, path, "");
  World back;
  read_checkpoint(back, path);
  std::filesystem::remove(path);
  add_pair(back, 0.04, 5e-3); // band 1
  back.cycle(1);
  EXPECT_EQ(check(back, "read back"), 4);

  // set_ball_ball_defaults ends the grading: a new contact copies the defaults.
  back.set_ball_ball_defaults(soil);
  add_pair(back, 0.05, 1.5e-3);
  back.cycle(1);
  bool found = false;
  for (const ContactView& c : back.ball_ball_contacts())
    if (back.particles().position[c.i].x > 0.045) {
      found = true;
      EXPECT_EQ(back.property_set(c.properties).attraction_force_N, soil.attraction_force_N);
    }
  EXPECT_TRUE(found);
}

} // namespace
} // namespace centridem
