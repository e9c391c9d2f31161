// Scenario files: parsing of a valid file, and one test per class of bad
// input, each checking that the message names the full key and what is
// allowed.
#include "base/errors.hpp"
#include "io/scenario.hpp"
#include "procedures/staged_run.hpp"

#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <functional>
#include <gtest/gtest.h>
#include <initializer_list>
#include <sstream>
#include <string>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace centridem;

namespace {

// A fresh folder per test, holding a small particle file.
class ScenarioTest : public ::testing::Test {
protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / fmt::format("centridem_scenario_{}_{}_{}", getpid(),
                                                   info->test_suite_name(), info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    write("grains.xyzr", "# x y z r\n0.001 0.001 0.001 0.0005\n0.002 0.001 0.001 0.0004\n"
                         "0.001 0.002 0.001 0.0005\n");
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  Scenario parse(const std::string& text) { return load_scenario(write("scenario.toml", text)); }
  fs::path dir_;
};

// A valid scenario; tests replace parts of it.
const std::string kValid = R"(
description = "a small test"

[simulation]
timestep_s = "auto"
local_damping = 0.7
threads = 1
progress_interval_s = 5

[particles]
file = "grains.xyzr"
density_kg_m3 = 2633

[contact.ball_ball]
model = "arrlinear"
effective_modulus_Pa = 300e6
stiffness_ratio = 1.5
friction = 0.5
rolling_friction = 0.16
attraction_force_N = 1.2e-4

[gravity]
g_level = 40
size_reduction_factor = 0.063

[[walls]]
name = "floor"
type = "plane"
point_m = [0, 0, 0]
normal = [0, 0, 2]
[walls.contact]
model = "linear"
effective_modulus_Pa = 1e9
friction = 0.2

[[walls]]
name = "lid"
type = "rectangle"
centre_m = [0.0015, 0.0015, 0.004]
normal = [0, 0, -1]
u_direction = [1, 0, 0]
size_m = [0.01, 0.01]
velocity_m_per_s = [0, 0, -0.01]
[walls.contact]
model = "linear"
normal_stiffness_N_per_m = 1e5
shear_stiffness_N_per_m = 5e4

[[stages]]
name = "settle"
until_equilibrium = { ratio = 1e-3, max_steps = 5000 }
frames_every = 100

[[stages]]
name = "shear"
contact.ball_ball = { attraction_force_N = 0 }
modify_contacts = { region = { lo = [0, 0, 0], hi = [1, 1, 1] }, set = { rolling_friction = 0 } }
walls = { lid = { velocity_m_per_s = [0, 0, 0], contact = { friction = 0.3 } } }
steps = 1e3

[[stages]]
name = "excavate"
remove_walls = ["lid"]
remove_particles = { region = { lo = [0, 0, 0.0015], hi = [1, 1, 1] } }
reset_displacements = true
local_damping = 0.5
gravity = { acceleration_m_per_s2 = [0, 0, -9.81] }
time_s = 0.01
measure_every = 0
)";

// Replaces the first occurrence of `from` in kValid.
std::string with(const std::string& from, const std::string& to) {
  std::string s = kValid;
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

// Runs f, expects an InputError whose message holds every piece.
void expect_error(const std::function<void()>& f, std::initializer_list<std::string> pieces) {
  try {
    f();
    ADD_FAILURE() << "no InputError thrown";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    for (const std::string& p : pieces)
      EXPECT_NE(msg.find(p), std::string::npos) << "message lacks \"" << p << "\":\n  " << msg;
  }
}

} // namespace

TEST_F(ScenarioTest, ValidFileParsesWithEveryDefaultResolved) {
  const Scenario s = parse(kValid);
  EXPECT_EQ(s.description, "a small test");
  EXPECT_EQ(s.simulation.world.timestep_s, 0.0);
  EXPECT_EQ(s.simulation.world.local_damping, 0.7);
  EXPECT_EQ(s.simulation.world.timestep_safety_factor, 0.8); // default
  EXPECT_EQ(s.simulation.world.threads, 1);
  EXPECT_EQ(s.simulation.output_dir, "runs/scenario");
  EXPECT_EQ(s.simulation.progress_interval_s, 5.0);
  ASSERT_EQ(s.particles.records.size(), 3u);
  EXPECT_EQ(s.particles.density_kg_m3, 2633.0);
  EXPECT_EQ(s.particles.records[1].radius, 0.0004);
  EXPECT_EQ(s.ball_ball.model, ContactModel::arrlinear);
  EXPECT_EQ(s.ball_ball.attraction_force_N, 1.2e-4);
  EXPECT_EQ(s.ball_ball.attraction_range_m, 0.0);
  // n g / s
  EXPECT_NEAR(s.gravity.field().gravity_m_s2.z, -40 * standard_gravity_m_s2 / 0.063, 1e-9);

  ASSERT_EQ(s.walls.size(), 2u);
  EXPECT_EQ(s.walls[0].normal, (Vec3{0, 0, 1})); // normalised
  EXPECT_EQ(s.walls[0].contact.friction, 0.2);
  EXPECT_EQ(s.walls[1].shape, WallShape::rectangle);
  EXPECT_EQ(s.walls[1].contact.stiffness_method, StiffnessMethod::direct);
  EXPECT_EQ(s.walls[1].velocity, (Vec3{0, 0, -0.01}));

  ASSERT_EQ(s.stages.size(), 3u);
  EXPECT_EQ(s.stages[0].end, StageEnd::equilibrium);
  EXPECT_EQ(s.stages[0].equilibrium_ratio, 1e-3);
  EXPECT_EQ(s.stages[0].equilibrium_max_steps, 5000);
  EXPECT_EQ(s.stages[0].equilibrium_check_interval, 100); // default
  EXPECT_EQ(s.stages[0].frames_every, 100);
  EXPECT_EQ(s.stages[0].measure_every, 1000); // default

  // A partial contact table changes only the keys it names.
  const StageSpec& shear = s.stages[1];
  EXPECT_EQ(shear.end, StageEnd::steps);
  EXPECT_EQ(shear.steps, 1000); // 1e3, a float, accepted as a whole number
  ASSERT_TRUE(shear.ball_ball);
  EXPECT_EQ(shear.ball_ball->attraction_force_N, 0.0);
  EXPECT_EQ(shear.ball_ball->rolling_friction, 0.16);
  EXPECT_EQ(shear.ball_ball->effective_modulus_Pa, 300e6);
  ASSERT_TRUE(shear.modify_contacts);
  EXPECT_TRUE(shear.modify_contacts->region);
  EXPECT_EQ(shear.modify_contacts->set.rolling_friction, 0.0);
  EXPECT_FALSE(shear.modify_contacts->set.friction);
  ASSERT_EQ(shear.walls.size(), 1u);
  ASSERT_TRUE(shear.walls[0].contact);
  EXPECT_EQ(shear.walls[0].contact->friction, 0.3);
  EXPECT_EQ(shear.walls[0].contact->normal_stiffness_N_per_m, 1e5); // kept

  const StageSpec& ex = s.stages[2];
  EXPECT_EQ(ex.remove_walls, std::vector<std::string>{"lid"});
  ASSERT_TRUE(ex.remove_particles);
  EXPECT_FALSE(ex.remove_particles->outside);
  EXPECT_TRUE(ex.reset_displacements);
  EXPECT_EQ(ex.local_damping, 0.5);
  ASSERT_TRUE(ex.gravity);
  EXPECT_EQ(ex.gravity->field().gravity_m_s2, (Vec3{0, 0, -9.81}));
  EXPECT_EQ(ex.end, StageEnd::time);
  EXPECT_EQ(ex.measure_every, 0);
}

TEST_F(ScenarioTest, ResolvedScenarioReadsBackTheSame) {
  const Scenario s = parse(kValid);
  const std::string resolved = resolved_toml(s);
  EXPECT_NE(resolved.find("timestep_safety_factor = 0.8"), std::string::npos);
  EXPECT_NE(resolved.find("check_interval = 100"), std::string::npos);
  const Scenario again = parse_scenario(resolved, "resolved.toml", dir_.string());
  EXPECT_EQ(again.ball_ball, s.ball_ball);
  ASSERT_EQ(again.stages.size(), s.stages.size());
  for (std::size_t k = 0; k < s.stages.size(); ++k) {
    EXPECT_EQ(again.stages[k].ball_ball, s.stages[k].ball_ball);
    EXPECT_EQ(again.stages[k].modify_contacts.has_value(), s.stages[k].modify_contacts.has_value());
  }
  // Compare without the comments ("named here" lists what each file named).
  auto body = [](const std::string& t) {
    std::istringstream in(t.substr(t.find("description")));
    std::string out, line;
    while (std::getline(in, line)) out += line.substr(0, line.find("  #")) + "\n";
    return out;
  };
  EXPECT_EQ(body(resolved_toml(again)), body(resolved));
}

TEST_F(ScenarioTest, NegativeRadiusInParticleFile) {
  write("grains.xyzr", "0 0 0 0.001\n0.01 0 0 -0.002\n");
  expect_error([&] { parse(kValid); },
               {"particles.file", "grains.xyzr:2", "column 4 (r)", "-0.002", "must be > 0"});
}

TEST_F(ScenarioTest, ZeroDensity) {
  expect_error([&] { parse(with("density_kg_m3 = 2633", "density_kg_m3 = 0")); },
               {"particles.density_kg_m3 = 0", "> 0 [kg/m^3]", "scenario.toml:12:"});
}

TEST_F(ScenarioTest, UnknownContactModel) {
  expect_error([&] { parse(with("model = \"arrlinear\"", "model = \"arlinear\"")); },
               {"contact.ball_ball.model = \"arlinear\"", "did you mean \"arrlinear\"",
                "\"linear\", \"rrlinear\" or \"arrlinear\""});
}

TEST_F(ScenarioTest, TimestepAboveTheCriticalOne) {
  Scenario s = parse(with("timestep_s = \"auto\"", "timestep_s = 1e-3"));
  s.simulation.output_dir = (dir_ / "run").string();
  RunOptions o;
  o.out = o.err = nullptr;
  expect_error([&] { run_scenario(s, o); },
               {"simulation.timestep_s = 0.001", "above the critical timestep", "\"auto\""});
  EXPECT_FALSE(fs::exists(dir_ / "run")); // found before any output
}

TEST_F(ScenarioTest, UnknownKeyWithSuggestion) {
  expect_error([&] { parse(with("{ attraction_force_N = 0 }", "{ atraction_force_N = 0 }")); },
               {"stages[1].contact.ball_ball.atraction_force_N", "unknown key",
                "did you mean \"attraction_force_N\"", "allowed keys: model,"});
  expect_error([&] { parse(with("density_kg_m3 = 2633", "density = 2633")); },
               {"particles.density", "did you mean \"density_kg_m3\""});
  // A stage key written after a sub-table header lands in that sub-table.
  expect_error(
      [&] {
        parse(with("[walls.contact]\nmodel = \"linear\"",
                   "[walls.contact]\nmodel = \"linear\"\nsteps = 3"));
      },
      {"walls[0].contact.steps", "is a key of [[stages]]"});
}

TEST_F(ScenarioTest, WrongType) {
  expect_error([&] { parse(with("threads = 1", "threads = \"two\"")); },
               {"simulation.threads = \"two\"", "expected a whole number", ">= 0"});
  expect_error([&] { parse(with("normal = [0, 0, 2]", "normal = [0, 0]")); },
               {"walls[0].normal = [0, 0]", "array of 3 numbers"});
  expect_error([&] { parse(with("reset_displacements = true", "reset_displacements = 1")); },
               {"stages[2].reset_displacements = 1", "true or false"});
  expect_error([&] { parse(with("steps = 1e3", "steps = 10.5")); },
               {"stages[1].steps = 10.5", "whole number"});
}

TEST_F(ScenarioTest, MissingParticleFile) {
  expect_error([&] { parse(with("file = \"grains.xyzr\"", "file = \"nothere.xyzr\"")); },
               {"particles.file = \"nothere.xyzr\"", "file not found", "nothere.xyzr",
                "relative to the scenario file"});
}

TEST_F(ScenarioTest, MissingScenarioFile) {
  expect_error([&] { load_scenario((dir_ / "absent.toml").string()); },
               {"absent.toml", "cannot be opened"});
}

TEST_F(ScenarioTest, MissingRequiredKeys) {
  expect_error([&] { parse(with("density_kg_m3 = 2633\n", "")); },
               {"particles.density_kg_m3 = (missing)", "required", "> 0 [kg/m^3]"});
  expect_error(
      [&] { parse(with("model = \"arrlinear\"\n", "")); },
      {"contact.ball_ball.model = (missing)", "\"linear\", \"rrlinear\" or \"arrlinear\""});
  expect_error([&] { parse(with("effective_modulus_Pa = 300e6\n", "")); },
               {"contact.ball_ball.effective_modulus_Pa = (missing)", "E* > 0 [Pa]"});
  expect_error([&] { parse(with("time_s = 0.01\n", "")); },
               {"stages[2].steps = (missing)", "exactly one of steps"});
  expect_error([&] { parse(with("shear_stiffness_N_per_m = 5e4\n", "")); },
               {"walls[1].contact.shear_stiffness_N_per_m = (missing)"});
}

TEST_F(ScenarioTest, OutOfRangeValues) {
  expect_error([&] { parse(with("friction = 0.5", "friction = -0.5")); },
               {"contact.ball_ball.friction = -0.5", ">= 0"});
  expect_error([&] { parse(with("local_damping = 0.7", "local_damping = 1.2")); },
               {"simulation.local_damping = 1.2", "[0, 1)"});
  expect_error([&] { parse(with("ratio = 1e-3", "ratio = 0")); },
               {"stages[0].until_equilibrium.ratio = 0", "> 0"});
  expect_error([&] { parse(with("size_m = [0.01, 0.01]", "size_m = [0.01, 0]")); },
               {"walls[1].size_m", "> 0 [m]"});
  expect_error([&] { parse(with("timestep_s = \"auto\"", "timestep_s = \"fast\"")); },
               {"simulation.timestep_s = \"fast\"", "\"auto\""});
  // A model that lacks the property given.
  expect_error([&] { parse(with("model = \"arrlinear\"", "model = \"linear\"")); },
               {"contact.ball_ball.rolling_friction = 0.16", "no rolling resistance"});
}

TEST_F(ScenarioTest, StageReferencesAreChecked) {
  expect_error([&] { parse(with("remove_walls = [\"lid\"]", "remove_walls = [\"lidd\"]")); },
               {"stages[2].remove_walls[0] = \"lidd\"", "did you mean \"lid\"", "known walls"});
  expect_error([&] { parse(with("time_s = 0.01", "time_s = 0.01\nsteps = 4")); },
               {"stages[2].time_s", "exactly one of"});
  expect_error(
      [&] {
        parse(with("remove_walls = [\"lid\"]", "remove_walls = [\"lid\"]\nwalls = { lid = {} }"));
      },
      {"stages[2].walls.lid", "no such wall at this stage"});
  expect_error([&] { parse(with("name = \"shear\"", "name = \"settle\"")); },
               {"stages[1].name = \"settle\"", "unique"});
  expect_error([&] { parse(with("name = \"shear\"", "name = \"a b\"")); },
               {"stages[1].name = \"a b\"", "letters, digits"});
}

TEST_F(ScenarioTest, TomlSyntaxErrorNamesLineAndColumn) {
  expect_error([&] { parse(with("friction = 0.5", "friction = = 0.5")); },
               {"scenario.toml:18:", "TOML syntax error"});
}

TEST_F(ScenarioTest, SpecimenTableIsCheckedButNotUsed) {
  const std::string specimen = "\n[specimen]\nfile = \"grains.xyzr\"\ndensity_kg_m3 = 2633\n";
  const Scenario s = parse(kValid + specimen);
  EXPECT_TRUE(s.has_specimen);
  EXPECT_NE(resolved_toml(s).find("[specimen] table"), std::string::npos);
  expect_error([&] { parse(kValid + "\n[specimen]\nfile = \"grains.xyzr\"\n"); },
               {"specimen.density_kg_m3 = (missing)"});
  const std::string block = "[particles]\nfile = \"grains.xyzr\"\ndensity_kg_m3 = 2633\n";
  std::string no_particles = kValid + specimen;
  no_particles.erase(no_particles.find(block), block.size());
  expect_error([&] { parse(no_particles); }, {"particles = (missing)", "centridem generate"});
}

TEST(ScenarioHelpers, DidYouMean) {
  const std::vector<std::string_view> keys = {"friction", "rolling_friction", "density_kg_m3"};
  EXPECT_EQ(did_you_mean("frction", keys), "friction");
  EXPECT_EQ(did_you_mean("density", keys), "density_kg_m3");
  EXPECT_EQ(did_you_mean("rolling_fric", keys), "rolling_friction");
  EXPECT_EQ(did_you_mean("frictoin", keys), "friction"); // a swap is one edit
  EXPECT_EQ(did_you_mean("colour", keys), "");
}
