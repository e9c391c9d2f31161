// The limit-equilibrium estimate of a benched slope (procedures/slope_stability;
// docs/slope.md "Limit equilibrium"; issue 16): the section is the slope's
// outline, and the scaling is the centrifuge's: for a c-phi soil the factor of
// safety depends on c / (gamma H) and phi only, so the critical g is
// proportional to c, inversely proportional to the bulk density, and the same
// at any size reduction factor s (H goes with s, the DEM's gamma with n / s).
#include "base/errors.hpp"
#include "procedures/foundation.hpp"
#include "procedures/slope_config.hpp"
#include "procedures/slope_stability.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <iterator>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

using namespace centridem;

namespace {

SlopeScenario lower_bench(double s, double c_Pa) {
  SlopeScenario sc = load_slope_scenario(std::string(CENTRIDEM_SOURCE_DIR) +
                                         "/examples/paper/slope_lower_bench.toml");
  sc.slope.size_reduction_factor = s;
  sc.limit_equilibrium.enabled = true;
  sc.limit_equilibrium.cohesion_Pa = c_Pa;
  sc.limit_equilibrium.friction_angle_deg = 32.4;
  return sc;
}

double critical_g(double s, double c_Pa, double rho) {
  const SlopeScenario sc = lower_bench(s, c_Pa);
  const SlopeLimitEquilibrium le = slope_limit_equilibrium(sc, SlopeGeometry(sc.slope), rho);
  EXPECT_TRUE(le.critical.bracketed);
  EXPECT_NEAR(le.critical.at_critical.factor_of_safety, 1.0, 1e-3);
  return le.critical.g_level;
}

} // namespace

TEST(SlopeStability, SectionIsTheSlopesOutlineOnTheChamberFloor) {
  const SlopeScenario sc = lower_bench(0.035, 5e3);
  const SlopeGeometry g(sc.slope);
  const LeSection section = slope_section(g);
  ASSERT_EQ(section.surface.size(), g.outline().size());
  EXPECT_DOUBLE_EQ(section.surface.front().second, g.height()); // the crest at the back wall
  EXPECT_DOUBLE_EQ(section.surface.back().first, g.length());
  EXPECT_DOUBLE_EQ(section.surface.back().second, g.toe_height());
  EXPECT_EQ(section.floor_z_m, 0.0);
}

TEST(SlopeStability, CriticalGScalesWithCohesionAndDensityAndNotWithSize) {
  const double rho = 1600;
  const double n1 = critical_g(0.035, 5e3, rho);
  const double n2 = critical_g(0.035, 10e3, rho);
  const double n3 = critical_g(0.063, 5e3, rho);
  const double n4 = critical_g(0.035, 5e3, 2 * rho);
  std::printf("critical g: c 5 kPa %.3f, c 10 kPa %.3f, s 0.063 %.3f, twice the density %.3f\n", n1,
              n2, n3, n4);
  EXPECT_NEAR(n2 / n1, 2.0, 0.01);  // proportional to c (phi fixed)
  EXPECT_NEAR(n3 / n1, 1.0, 0.005); // the model's stresses at n g, whatever s
  EXPECT_NEAR(n4 / n1, 0.5, 0.005); // inversely proportional to the unit weight
  EXPECT_GT(n1, 1.0);
}

TEST(SlopeStability, BulkDensityFromThePreparedFoundationOrTheKey) {
  SlopeScenario sc = lower_bench(0.035, 5e3);
  FoundationResult f;
  f.prepared = true;
  f.layer_porosity = {0.38, 0.40, 0.42};
  EXPECT_NEAR(limit_equilibrium_bulk_density(sc, &f), 2633.0 * 0.6, 1e-9);
  sc.limit_equilibrium.bulk_density_kg_m3 = 1700;
  EXPECT_DOUBLE_EQ(limit_equilibrium_bulk_density(sc, &f), 1700);
  sc.limit_equilibrium.bulk_density_kg_m3 = 0;
  EXPECT_THROW(limit_equilibrium_bulk_density(sc, nullptr), InputError);
}

// `--search-auto` needs the soil's strength: without [limit_equilibrium] it
// is refused before any work, exit 2, naming the flag and the table.
TEST(SlopeStability, SearchAutoWithoutTheStrengthIsRefused) {
  const std::string out = (std::filesystem::temp_directory_path() /
                           ("centridem_search_auto_" + std::to_string(::getpid())))
                              .string();
  const std::string log = out + ".log";
  const std::string cmd = std::string("'") + CENTRIDEM_BINARY + "' slope '" + CENTRIDEM_SOURCE_DIR +
                          "/examples/demo_slope.toml'" + " --search-auto --out '" + out + "' > '" +
                          log + "' 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("--search-auto"), std::string::npos) << text;
  EXPECT_NE(text.find("[limit_equilibrium]"), std::string::npos) << text;
  std::filesystem::remove_all(out);
  std::filesystem::remove(log);
}
