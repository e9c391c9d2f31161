// The [specimen] table: every key checked (type, range, unknown with
// did-you-mean, required), paths relative to the scenario, the examples.
#include "base/errors.hpp"
#include "io/specimen_config.hpp"
#include "procedures/gsd.hpp"

#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <string>

using namespace centridem;

namespace {

const std::string kExamples = std::string(CENTRIDEM_SOURCE_DIR) + "/examples";

template <class F> void expect_input_error(F&& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    for (const std::string& p : parts)
      EXPECT_NE(msg.find(p), std::string::npos) << "message: " << msg << "\n  lacks: " << p;
  }
}

const char* kBins = R"(
[specimen]
gradation = { bins = [ { d_min_m = 0.25e-3, d_max_m = 0.5e-3, volume_fraction = 0.6 },
                       { d_min_m = 0.5e-3, d_max_m = 1.0e-3, volume_fraction = 0.4 } ] }
porosity = 0.4
density_kg_m3 = 2650
seed = 42
brick = { size_m = [4e-3, 4e-3, 4e-3] }
region = { lo_m = [0, 0, 0], hi_m = [8e-3, 8e-3, 4e-3] }
periodic = [true, false, false]
relax = { ratio = 1e-4, max_steps = 1000, contact = { model = "rrlinear", effective_modulus_Pa = 1e8, friction = 0.5, rolling_friction = 0.1 } }

[stages]   # other tables belong to the scenario parser
)";

SpecimenSpec parse(const std::string& text) {
  return parse_specimen(text, "s.toml", ".");
}

std::string with(const std::string& from, const std::string& to) {
  std::string s = kBins;
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

} // namespace

TEST(SpecimenConfig, ReadsEveryKey) {
  const SpecimenSpec s = parse(kBins);
  EXPECT_EQ(s.source, SpecimenSpec::Source::distribute);
  ASSERT_EQ(s.bins.size(), 2u);
  EXPECT_DOUBLE_EQ(s.bins[1].volume_fraction, 0.4);
  EXPECT_DOUBLE_EQ(s.porosity, 0.4);
  EXPECT_DOUBLE_EQ(s.density_kg_m3, 2650);
  EXPECT_EQ(s.seed, 42u);
  EXPECT_DOUBLE_EQ(s.brick_size_m.y, 4e-3);
  ASSERT_TRUE(s.region.has_value());
  EXPECT_DOUBLE_EQ(s.region->hi.x, 8e-3);
  EXPECT_TRUE(s.periodic[0]);
  EXPECT_FALSE(s.periodic[1]);
  EXPECT_DOUBLE_EQ(s.relax.ratio, 1e-4);
  EXPECT_EQ(s.relax.max_steps, 1000);
  ASSERT_TRUE(s.relax.contact.has_value());
  EXPECT_EQ(s.relax.contact->model, ContactModel::rrlinear);
  EXPECT_DOUBLE_EQ(s.relax.contact->friction, 0.5);
  EXPECT_EQ(resolve_gradation(s).size(), 2u);
  // The resolved table reads back to the same specimen.
  const SpecimenSpec again = parse(resolved_specimen_toml(s));
  EXPECT_EQ(again.bins, s.bins);
  EXPECT_EQ(again.seed, s.seed);
  EXPECT_EQ(again.relax.contact, s.relax.contact);
  EXPECT_DOUBLE_EQ(again.relax.max_overlap_ratio, s.relax.max_overlap_ratio);
}

TEST(SpecimenConfig, BadKeysNameTheDottedKey) {
  expect_input_error([] { parse(with("porosity = 0.4", "porosty = 0.4")); },
                     {"specimen.porosty", "unknown key", "did you mean \"porosity\""});
  expect_input_error([] { parse(with("porosity = 0.4", "porosity = \"0.4\"")); },
                     {"specimen.porosity", "expected a number"});
  expect_input_error([] { parse(with("porosity = 0.4", "porosity = 1.2")); },
                     {"specimen.porosity = 1.2", "in (0, 1)", "s.toml:"});
  expect_input_error([] { parse(with("seed = 42", "seed = -1")); }, {"specimen.seed", ">= 0"});
  expect_input_error([] { parse(with("seed = 42", "seed = 1.5")); },
                     {"specimen.seed", "expected an integer"});
  expect_input_error([] { parse(with("ratio = 1e-4", "ration = 1e-4")); },
                     {"specimen.relax.ration", "did you mean \"ratio\""});
  expect_input_error([] { parse(with("friction = 0.5", "friction = -0.5")); },
                     {"specimen.relax.contact.friction", ">= 0"});
  expect_input_error([] { parse(with("brick = { size_m = [4e-3, 4e-3, 4e-3] }", "")); },
                     {"specimen.brick", "(missing)", "size_m"});
  expect_input_error([] { parse(with("[4e-3, 4e-3, 4e-3]", "[4e-3, 4e-3]")); },
                     {"specimen.brick.size_m", "3 numbers"});
  expect_input_error([] { parse(with("hi_m = [8e-3, 8e-3, 4e-3]", "hi_m = [8e-3, 8e-3, 0]")); },
                     {"specimen.region.hi_m", "must exceed lo_m along z"});
  expect_input_error([] { parse(with("volume_fraction = 0.6", "volume_fractoin = 0.6")); },
                     {"specimen.gradation.bins[0].volume_fractoin", "did you mean"});
  expect_input_error([] { parse(with("density_kg_m3 = 2650", "")); },
                     {"specimen.density_kg_m3", "(missing)"});
  expect_input_error([] { parse(with("periodic = [true, false, false]", "periodic = [1, 0, 0]")); },
                     {"specimen.periodic[0]", "true or false"});
  expect_input_error(
      [] {
        parse(with("contact = { model = \"rrlinear\", effective_modulus_Pa = 1e8, friction = 0.5, "
                   "rolling_friction = 0.1 }",
                   "contact = \"scenario\""));
      },
      {"specimen.relax.contact", "[contact.ball_ball]"});
  expect_input_error([] { parse("[specimen]\nfile = \"nope.xyzr\"\ndensity_kg_m3 = 1\n"); },
                     {"specimen.file", "file not found"});
  expect_input_error([] { parse("[other]\n"); }, {"specimen", "(missing)"});
  expect_input_error([] { parse("[specimen\n"); }, {"s.toml:1", "TOML syntax error"});
}

// The sieve table and a particle file are found relative to the scenario.
TEST(SpecimenConfig, PathsAreRelativeToTheScenario) {
  const auto dir = std::filesystem::temp_directory_path() / "centridem_specimen_config";
  std::filesystem::create_directories(dir / "data");
  {
    std::ofstream(dir / "data" / "gsd.csv") << "sieve_mm,percent_passing\n0.5,0\n1.0,100\n";
    std::ofstream(dir / "p.xyzr") << "0 0 0 1e-3\n";
    std::ofstream(dir / "a.toml")
        << "[specimen]\ngradation = { sieve_csv = \"data/gsd.csv\" }\nporosity = 0.5\n"
           "density_kg_m3 = 2633\nbrick = { size_m = [5e-3, 5e-3, 5e-3] }\n"
           "region = { lo_m = [0, 0, 0], hi_m = [5e-3, 5e-3, 5e-3] }\n"
           "[contact.ball_ball]\nmodel = \"linear\"\neffective_modulus_Pa = 1e8\n"
           "[specimen.relax]\ncontact = \"scenario\"\n";
    std::ofstream(dir / "b.toml") << "[specimen]\nfile = \"p.xyzr\"\ndensity_kg_m3 = 2633\n";
    std::ofstream(dir / "c.toml") << "[specimen]\nfile = \"p.xyzr\"\ndensity_kg_m3 = 2633\n"
                                     "porosity = 0.4\n";
  }
  const SpecimenSpec a = load_specimen((dir / "a.toml").string());
  ASSERT_TRUE(a.sieve.has_value());
  EXPECT_EQ(a.sieve->rows.size(), 2u);
  EXPECT_EQ(a.relax.contact_source, "scenario");
  EXPECT_EQ(a.relax.contact->model, ContactModel::linear);
  const SpecimenSpec b = load_specimen((dir / "b.toml").string());
  EXPECT_EQ(b.source, SpecimenSpec::Source::file);
  EXPECT_TRUE(std::filesystem::exists(b.file_path));
  expect_input_error([&] { load_specimen((dir / "c.toml").string()); },
                     {"specimen.porosity", "not used with specimen.file"});
  std::filesystem::remove_all(dir);
}

// The example specimens read, and give the paper's truncated gradation.
TEST(SpecimenConfig, ExamplesRead) {
  for (const char* name : {"paper_shear_box.toml", "paper_foundation.toml"}) {
    const SpecimenSpec s = load_specimen(kExamples + "/specimens/" + name);
    const std::vector<GradationBin> bins = resolve_gradation(s);
    ASSERT_EQ(bins.size(), 4u) << name;
    EXPECT_NEAR(bins[0].volume_fraction, 0.72, 1e-12);
    EXPECT_NEAR(bins[3].volume_fraction, 0.03, 1e-12);
    EXPECT_DOUBLE_EQ(s.porosity, 0.52);
    EXPECT_DOUBLE_EQ(s.density_kg_m3, 2633.0);
    EXPECT_EQ(s.relax.contact_source, "scenario");
  }
}
