// The [shear] scenario parser (`centridem shear`, docs/shear.md): a valid
// scenario resolves every default, the examples parse, and every class of bad
// key is rejected with an InputError naming the dotted key.
#include "base/errors.hpp"
#include "procedures/shear_config.hpp"

#include <gtest/gtest.h>
#include <string>

using namespace centridem;

namespace {

const std::string kSpecimen = R"(
[specimen]
gradation = { bins = [{ d_min_m = 0.4e-3, d_max_m = 0.6e-3, volume_fraction = 1.0 }] }
porosity = 0.40
density_kg_m3 = 2633.0
seed = 11
brick = { size_m = [3e-3, 3e-3, 3e-3] }
region = { lo_m = [0.0, 0.0, 0.0], hi_m = [6e-3, 6e-3, 3e-3] }
)";

const std::string kContact = R"(
[contact.ball_ball]
model = "arrlinear"
effective_modulus_Pa = 300e6
stiffness_ratio = 1.5
friction = 0.5
rolling_friction = 0.16
attraction_force_N = 1.2e-4
)";

std::string scenario(const std::string& shear_body, const std::string& extra_top = "") {
  return extra_top + kSpecimen + kContact + "\n[shear]\n" + shear_body;
}

ShearScenario parse(const std::string& text) {
  return parse_shear_scenario(text, "test.toml", ".");
}

// The InputError's message, or "" when parsing succeeds.
std::string error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

#define EXPECT_ERROR(text, key_substring)                                                          \
  do {                                                                                             \
    const std::string msg = error_of(text);                                                        \
    EXPECT_NE(msg, "") << "accepted";                                                              \
    EXPECT_NE(msg.find(key_substring), std::string::npos) << msg;                                  \
  } while (0)

} // namespace

TEST(ShearConfig, MinimalScenarioResolvesDefaults) {
  const ShearScenario s = parse(scenario("normal_stresses_Pa = [40e3, 80e3]\n"));
  ASSERT_EQ(s.normal_stresses_Pa.size(), 2u);
  EXPECT_DOUBLE_EQ(s.normal_stresses_Pa[1], 80e3);
  // The box is the specimen's region.
  EXPECT_DOUBLE_EQ(s.test.box.length_m, 6e-3);
  EXPECT_DOUBLE_EQ(s.test.box.width_m, 6e-3);
  EXPECT_DOUBLE_EQ(s.test.box.height_m, 3e-3);
  EXPECT_NEAR(s.test.shear_rate_m_per_s, 0.2e-3 / 60 * 1000, 1e-15);
  EXPECT_DOUBLE_EQ(s.test.max_shear_displacement_m, 0.2 * 3e-3); // 20 % of the height
  EXPECT_EQ(s.test.strain, StrainDefinition::height);
  EXPECT_EQ(s.test.ball_wall.model, ContactModel::linear);
  EXPECT_DOUBLE_EQ(s.test.ball_wall.effective_modulus_Pa, 1e9);
  EXPECT_DOUBLE_EQ(s.test.ball_wall.friction, 0.0);
  EXPECT_DOUBLE_EQ(s.local_damping, 0.7);
  EXPECT_DOUBLE_EQ(s.g_level, 1.0);
  EXPECT_EQ(s.threads, 1);
  EXPECT_TRUE(s.during_shear.empty());
  EXPECT_FALSE(s.run_spec(40e3).ball_ball_during_shear.has_value());
  EXPECT_EQ(s.ball_ball.model, ContactModel::arrlinear);
  EXPECT_DOUBLE_EQ(s.ball_ball.attraction_force_N, 1.2e-4);
}

TEST(ShearConfig, EveryKeyIsRead) {
  const ShearScenario s = parse(scenario(R"(
box = { length_m = 6e-3, width_m = 6e-3, height_m = 3e-3, plate_length_m = 1e-3 }
normal_stresses_Pa = [50e3, 100000, 150e3]
shear_rate_m_per_s = 0.02
max_shear_displacement_m = 0.6e-3
strain = "length"
ball_wall = { friction = 0.2 }
during_shear = { attraction_force_N = 0 }
servo_gain_factor = 0.3
servo_max_speed_m_per_s = 0.01
servo_integral_time_s = 3e-4
consolidation_ratio = 2e-3
consolidation_stress_tolerance = 0.02
consolidation_max_steps = 1000
unload_reload_fraction = 0.8
record_interval_steps = 250
local_damping = 0.5
g_level = 2
threads = 2
)",
                                         "description = \"d\"\n"));
  EXPECT_EQ(s.description, "d");
  EXPECT_DOUBLE_EQ(s.normal_stresses_Pa[1], 100e3);
  EXPECT_DOUBLE_EQ(s.test.box.plate_length_m, 1e-3);
  EXPECT_DOUBLE_EQ(s.test.shear_rate_m_per_s, 0.02);
  EXPECT_DOUBLE_EQ(s.test.max_shear_displacement_m, 0.6e-3);
  EXPECT_EQ(s.test.strain, StrainDefinition::length);
  EXPECT_DOUBLE_EQ(s.test.ball_wall.friction, 0.2);
  EXPECT_DOUBLE_EQ(s.test.ball_wall.effective_modulus_Pa, 1e9); // the rest from the default
  EXPECT_DOUBLE_EQ(s.test.servo_gain_factor, 0.3);
  EXPECT_DOUBLE_EQ(s.test.servo_max_speed_m_per_s, 0.01);
  EXPECT_DOUBLE_EQ(s.test.servo_integral_time_s, 3e-4);
  EXPECT_DOUBLE_EQ(s.test.consolidation_ratio, 2e-3);
  EXPECT_DOUBLE_EQ(s.test.consolidation_stress_tolerance, 0.02);
  EXPECT_EQ(s.test.consolidation_max_steps, 1000);
  EXPECT_DOUBLE_EQ(s.test.unload_reload_fraction, 0.8);
  EXPECT_EQ(s.test.record_interval_steps, 250);
  EXPECT_DOUBLE_EQ(s.local_damping, 0.5);
  EXPECT_DOUBLE_EQ(s.g_level, 2.0);
  EXPECT_EQ(s.threads, 2);
  // during_shear patches the ball-ball defaults: F0 off, everything else kept.
  const DirectShearSpec r = s.run_spec(100e3);
  EXPECT_DOUBLE_EQ(r.normal_stress_Pa, 100e3);
  ASSERT_TRUE(r.ball_ball_during_shear.has_value());
  EXPECT_DOUBLE_EQ(r.ball_ball_during_shear->attraction_force_N, 0.0);
  EXPECT_DOUBLE_EQ(r.ball_ball_during_shear->friction, 0.5);
  EXPECT_EQ(r.ball_ball_during_shear->model, ContactModel::arrlinear);
  EXPECT_FALSE(r.ball_ball_during_consolidation.has_value()); // no [preparation]
  EXPECT_DOUBLE_EQ(r.ball_ball.friction, 0.5);
}

TEST(ShearConfig, PreparationTableDrivesTheConsolidation) {
  const ShearScenario s = parse(scenario(R"(
normal_stresses_Pa = [50e3]
[preparation]
during_compaction = { friction = 0.1, rolling_friction = 0 }
ratio = 2e-3
max_steps = 1234
)"));
  ASSERT_TRUE(s.preparation.enabled);
  const DirectShearSpec r = s.run_spec(50e3);
  // The packing's properties; the material is kept for shearing.
  ASSERT_TRUE(r.ball_ball_during_consolidation.has_value());
  EXPECT_DOUBLE_EQ(r.ball_ball_during_consolidation->friction, 0.1);
  EXPECT_DOUBLE_EQ(r.ball_ball_during_consolidation->rolling_friction, 0.0);
  EXPECT_DOUBLE_EQ(r.ball_ball_during_consolidation->attraction_force_N,
                   s.ball_ball.attraction_force_N);
  EXPECT_DOUBLE_EQ(r.ball_ball.friction, 0.5);
  EXPECT_DOUBLE_EQ(r.consolidation_ratio, 2e-3);
  EXPECT_EQ(r.consolidation_max_steps, 1234);
  // The old key points to the new table; the [shear] ratio may not compete with it.
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nduring_consolidation = { friction = 0.1 }\n"),
               "[preparation]");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nconsolidation_ratio = 1e-3\n"
                        "[preparation]\nduring_compaction = { friction = 0.2 }\n"),
               "shear.consolidation_ratio");
}

TEST(ShearConfig, ResolvedTomlReadsBackTheSame) {
  const ShearScenario a = parse(scenario(R"(
normal_stresses_Pa = [50e3, 100e3]
strain = "length"
unload_reload_fraction = 0.75
during_shear = { attraction_force_N = 0.0, friction = 0.4 }
[preparation]
during_compaction = { friction = 0.05 }
)"));
  const ShearScenario b = parse(resolved_shear_toml(a));
  EXPECT_EQ(a.normal_stresses_Pa, b.normal_stresses_Pa);
  EXPECT_EQ(a.ball_ball, b.ball_ball);
  EXPECT_EQ(a.during_shear, b.during_shear);
  EXPECT_EQ(a.preparation, b.preparation);
  EXPECT_TRUE(b.preparation.enabled);
  EXPECT_EQ(a.test.ball_wall, b.test.ball_wall);
  EXPECT_EQ(a.test.strain, b.test.strain);
  EXPECT_DOUBLE_EQ(a.test.max_shear_displacement_m, b.test.max_shear_displacement_m);
  EXPECT_DOUBLE_EQ(a.test.shear_rate_m_per_s, b.test.shear_rate_m_per_s);
  EXPECT_DOUBLE_EQ(a.test.unload_reload_fraction, b.test.unload_reload_fraction);
  EXPECT_EQ(resolved_shear_toml(a), resolved_shear_toml(b));
}

TEST(ShearConfig, ExamplesParse) {
  const std::string root = CENTRIDEM_SOURCE_DIR;
  for (const char* f : {"/examples/shear_small.toml", "/examples/paper/shear_dry.toml",
                        "/examples/paper/shear_humid.toml"}) {
    SCOPED_TRACE(f);
    const ShearScenario s = load_shear_scenario(root + f);
    EXPECT_GE(s.normal_stresses_Pa.size(), 3u);
  }
  const ShearScenario dry = load_shear_scenario(root + "/examples/paper/shear_dry.toml");
  EXPECT_EQ(dry.normal_stresses_Pa, (std::vector<double>{40e3, 60e3, 80e3, 100e3, 120e3}));
  EXPECT_DOUBLE_EQ(dry.test.box.length_m, 13.2e-3);
  EXPECT_DOUBLE_EQ(dry.test.box.height_m, 4.4e-3);
  EXPECT_DOUBLE_EQ(dry.ball_ball.attraction_force_N, 0.0);
  EXPECT_NEAR(dry.test.shear_rate_m_per_s, 0.2e-3 / 60 * 1000, 1e-12);
  const ShearScenario humid = load_shear_scenario(root + "/examples/paper/shear_humid.toml");
  EXPECT_DOUBLE_EQ(humid.ball_ball.attraction_force_N, 1.2e-4);
  ASSERT_TRUE(humid.run_spec(40e3).ball_ball_during_shear.has_value());
  EXPECT_DOUBLE_EQ(humid.run_spec(40e3).ball_ball_during_shear->attraction_force_N, 0.0);
}

TEST(ShearConfig, UnknownKeysAreNamedWithASuggestion) {
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nshear_rate_m_per_sec = 0.1\n"),
               "shear.shear_rate_m_per_sec");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nshear_rate_m_per_sec = 0.1\n"),
               "did you mean \"shear_rate_m_per_s\"");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nbox = { lenght_m = 6e-3 }\n"),
               "shear.box.lenght_m");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nball_wall = { fricton = 0.1 }\n"),
               "shear.ball_wall.fricton");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nduring_shear = { atraction_force_N = 0 }\n"),
               "did you mean \"attraction_force_N\"");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\n", "sheer = 1\n"), "sheer");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\n", "stages = 1\n"), "unknown key");
}

TEST(ShearConfig, WrongTypesAndRangesAreRejected) {
  EXPECT_ERROR(scenario("normal_stresses_Pa = 40e3\n"), "shear.normal_stresses_Pa");
  EXPECT_ERROR(scenario("normal_stresses_Pa = []\n"), "shear.normal_stresses_Pa");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3, -1.0]\n"), "shear.normal_stresses_Pa[1]");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3, \"x\"]\n"), "shear.normal_stresses_Pa[1]");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3, 40e3]\n"), "each normal stress once");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nshear_rate_m_per_s = 0\n"),
               "shear.shear_rate_m_per_s");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nshear_rate_m_per_s = \"fast\"\n"),
               "expected a number");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nmax_shear_displacement_m = 7e-3\n"),
               "shear.max_shear_displacement_m");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nstrain = \"width\"\n"), "shear.strain");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nservo_gain_factor = 1.5\n"),
               "shear.servo_gain_factor");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nservo_integral_time_s = -1e-4\n"),
               "shear.servo_integral_time_s");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nservo_max_speed_m_per_s = -1\n"),
               "shear.servo_max_speed_m_per_s");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nconsolidation_ratio = 0\n"),
               "shear.consolidation_ratio");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nconsolidation_max_steps = 1.5\n"),
               "shear.consolidation_max_steps = 1.5: expected a whole number");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nunload_reload_fraction = 1.0\n"),
               "shear.unload_reload_fraction");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nrecord_interval_steps = 0\n"),
               "shear.record_interval_steps");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nlocal_damping = 1.0\n"),
               "shear.local_damping");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\ng_level = -1\n"), "shear.g_level");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nthreads = -2\n"), "shear.threads");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nball_wall = { friction = -0.1 }\n"),
               "shear.ball_wall.friction");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nball_wall = { model = \"hertz\" }\n"),
               "shear.ball_wall.model");
  EXPECT_ERROR(
      scenario("normal_stresses_Pa = [40e3]\nduring_shear = { attraction_force_N = -1 }\n"),
      "shear.during_shear.attraction_force_N");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nduring_shear = 0\n"), "shear.during_shear");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\n[preparation]\n"
                        "during_compaction = { friction = -0.1 }\n"),
               "preparation.during_compaction.friction");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\n[preparation]\n"
                        "during_compaction = { fiction = 0 }\n"),
               "did you mean \"friction\"");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\n[preparation]\nratio = 0.1\n"),
               "preparation.during_compaction");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\n[preparation]\n"
                        "during_compaction = { friction = 0.2 }\noverfill = 0.5\n"),
               "preparation.overfill");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nbox = { length_m = -1 }\n"),
               "shear.box.length_m");
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nbox = { plate_length_m = 1e-5 }\n"),
               "shear.box.plate_length_m");
}

TEST(ShearConfig, MissingTablesAndMismatchedBoxAreRejected) {
  EXPECT_ERROR(scenario(""), "shear.normal_stresses_Pa");
  EXPECT_ERROR(kSpecimen + kContact, "shear");
  EXPECT_ERROR(kSpecimen + "\n[shear]\nnormal_stresses_Pa = [40e3]\n", "contact.ball_ball");
  EXPECT_ERROR(kContact + "\n[shear]\nnormal_stresses_Pa = [40e3]\n", "specimen");
  EXPECT_ERROR(kSpecimen + "\n[contact.ball_ball]\nfriction = 0.5\n[shear]\n"
                           "normal_stresses_Pa = [40e3]\n",
               "contact.ball_ball.model");
  // The box must be the specimen's region.
  EXPECT_ERROR(scenario("normal_stresses_Pa = [40e3]\nbox = { length_m = 8e-3 }\n"),
               "specimen.region");
  std::string shifted = scenario("normal_stresses_Pa = [40e3]\nbox = { length_m = 6e-3 }\n");
  const std::string region = "lo_m = [0.0, 0.0, 0.0], hi_m = [6e-3, 6e-3, 3e-3]";
  shifted.replace(shifted.find(region), region.size(),
                  "lo_m = [1e-3, 0.0, 0.0], hi_m = [7e-3, 6e-3, 3e-3]");
  EXPECT_ERROR(shifted, "specimen.region");
  EXPECT_ERROR("[shear\n", "TOML syntax error");
}
