// `centridem generate` (app/cmd_generate): a slope scenario gives its
// foundation with a porosity profile against height (issue 16: one
// preparation that generate, shear and slope read alike); --set changes a
// value and a bad one is refused with its key, exit 2; --scale is refused
// where it has no meaning.
#include "cli_test_util.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

// A small slope (s = 0.03: a 9 x 3 x 5.4 mm chamber, about 1,100 grains of
// 0.4-0.6 mm) without [preparation]: generate builds it as generated.
const char* kSlope = R"(
[specimen]
gradation = { bins = [{ d_min_m = 0.4e-3, d_max_m = 0.6e-3, volume_fraction = 1.0 }] }
porosity = 0.50
density_kg_m3 = 2633.0
seed = 5
brick = { size_m = [3e-3, 3e-3, 3e-3] }

[contact.ball_ball]
model = "arrlinear"
effective_modulus_Pa = 300e6
stiffness_ratio = 1.5
friction = 0.5
rolling_friction = 0.16
attraction_force_N = 1.2e-4

[slope]
size_reduction_factor = 0.03
benches = [{ height_m = 0.075, width_m = 0.03 }, { height_m = 0.075 }]
breadth_m = 0.10
[campaign]
g_levels = [50]
)";

using centridem::testutil::CliRun;

// `centridem generate ARGS` (ARGS split at spaces; quoted paths hold none).
centridem::testutil::CliRun generate(const std::string& args, const fs::path& dir) {
  std::vector<std::string> all = {"generate"};
  std::istringstream in(args);
  for (std::string w; in >> w;) {
    if (w.size() >= 2 && w.front() == '\'' && w.back() == '\'') w = w.substr(1, w.size() - 2);
    all.push_back(w);
  }
  return centridem::testutil::run_centridem(all, dir / "log.txt");
}

} // namespace

TEST(GenerateCommand, SlopeScenarioWritesItsFoundationWithAPorosityProfile) {
  const fs::path dir =
      fs::temp_directory_path() / ("centridem_generate_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  { std::ofstream(dir / "slope.toml") << kSlope; }
  const fs::path out = dir / "out";
  const CliRun r = generate("'" + (dir / "slope.toml").string() + "' --threads 1 --out '" +
                                out.string() + "' --cache '" + (dir / "cache").string() + "'",
                            dir);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("porosity against height"), std::string::npos) << r.output;
  for (const char* f : {"foundation.vtu", "foundation.xyzr", "foundation.json", "scenario.toml"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  std::ifstream in(out / "foundation.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  const auto& p = j.at("porosity_profile");
  const auto n = p.at("porosity").size();
  EXPECT_GE(n, 3u);
  EXPECT_EQ(p.at("z_bottom_m").size(), n);
  // Plumbing, not the measurement (that is the cubic-lattice test in
  // test_foundation.cpp): porosities of a granular packing. Generated at 0.50
  // ignoring overlaps and pushed off the walls, the interior is at 0.43-0.45.
  for (const auto& v : p.at("porosity")) {
    EXPECT_GT(v.get<double>(), 0.30);
    EXPECT_LT(v.get<double>(), 0.60);
  }
  std::size_t lines = 0;
  {
    std::ifstream x(out / "foundation.xyzr");
    for (std::string l; std::getline(x, l);)
      if (!l.empty() && l[0] != '#') ++lines;
  }
  EXPECT_EQ(lines, j.at("particles").get<std::size_t>());
  EXPECT_DOUBLE_EQ(j.at("size_reduction_factor").get<double>(), 0.03);

  // --scale as in `slope`: the DEM box shrinks with s (2/3 here), and with it the grain count.
  const CliRun scaled =
      generate("'" + (dir / "slope.toml").string() +
                   "' --threads 1 --scale 0.02 "
                   "--out '" +
                   (dir / "out2").string() + "' --cache '" + (dir / "cache").string() + "'",
               dir);
  ASSERT_EQ(scaled.code, 0) << scaled.output;
  std::ifstream in2(dir / "out2" / "foundation.json");
  const nlohmann::json j2 = nlohmann::json::parse(in2);
  EXPECT_DOUBLE_EQ(j2.at("size_reduction_factor").get<double>(), 0.02);
  EXPECT_NEAR(j2.at("design_height_m").get<double>(),
              j.at("design_height_m").get<double>() * 0.02 / 0.03, 1e-12);
  EXPECT_LT(j2.at("particles").get<std::size_t>(), j.at("particles").get<std::size_t>());
  fs::remove_all(dir);
}

TEST(GenerateCommand, SetChangesAValueAndABadOneIsRefusedWithItsKey) {
  const fs::path dir =
      fs::temp_directory_path() / ("centridem_generate_set_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  { std::ofstream(dir / "slope.toml") << kSlope; }
  const std::string scenario = "'" + (dir / "slope.toml").string() + "'";
  const CliRun bad = generate(
      scenario + " --set specimen.porosity=1.5 --out '" + (dir / "bad").string() + "'", dir);
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_NE(bad.output.find("specimen.porosity"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("1.5"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(dir / "bad" / "foundation.json"));

  const CliRun ok =
      generate(scenario + " --threads 1 --set slope.size_reduction_factor=0.02 --out '" +
                   (dir / "ok").string() + "' --cache '" + (dir / "cache").string() + "'",
               dir);
  ASSERT_EQ(ok.code, 0) << ok.output;
  std::ifstream in(dir / "ok" / "foundation.json");
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(in).at("size_reduction_factor").get<double>(), 0.02);

  // A plain specimen scenario: --scale has no meaning there.
  {
    std::ofstream(dir / "specimen.toml")
        << std::string(kSlope).substr(0, std::string(kSlope).find("[contact"));
  }
  const CliRun scale = generate("'" + (dir / "specimen.toml").string() + "' --scale 0.5 --out '" +
                                    (dir / "sp").string() + "'",
                                dir);
  EXPECT_EQ(scale.code, 2) << scale.output;
  EXPECT_NE(scale.output.find("--scale"), std::string::npos) << scale.output;
  fs::remove_all(dir);
}
