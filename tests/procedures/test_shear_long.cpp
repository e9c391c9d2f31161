// Opt-in (ctest -L long): the paper's dry direct shear example
// (examples/paper/shear_dry.toml, ~13,300 particles in 13.2 x 13.2 x 4.4 mm,
// 200 mm/min) at one pressure through the library, and all five pressures
// through `centridem shear --jobs 2` when the binary has the subcommand.
// See docs/shear.md for the measured run times (hours per pressure).
#include "core/world.hpp"
#include "io/shear_config.hpp"
#include "procedures/direct_shear.hpp"
#include "procedures/specimen.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

using namespace centridem;

namespace {
const std::string kDry = std::string(CENTRIDEM_SOURCE_DIR) + "/examples/paper/shear_dry.toml";
}

TEST(ShearPaperLong, DryExampleAt100kPa) {
  const ShearScenario sc = load_shear_scenario(kDry);
  WorldSettings ws;
  ws.local_damping = sc.local_damping;
  ws.threads = 0; // the OpenMP default
  World world(ws);
  build_specimen(sc.specimen, world);
  EXPECT_NEAR(static_cast<double>(world.particles().size()), 13284.0, 0.05 * 13284.0);
  world.set_local_damping(sc.local_damping);
  world.set_ball_ball_defaults(sc.ball_ball);
  world.set_body_field(BodyField::scaled_gravity(sc.g_level, 1.0));
  const double sigma = 100e3;
  const DirectShearResult r = run_direct_shear(world, sc.run_spec(sigma));
  const double phi_peak = std::atan(r.peak_shear_stress_Pa / sigma) * 180 / std::numbers::pi;
  const double phi_res = std::atan(r.residual_shear_stress_Pa / sigma) * 180 / std::numbers::pi;
  std::printf("dry 100 kPa: peak %.1f kPa (%.1f deg) at strain %.3f, residual %.1f kPa (%.1f "
              "deg), worst sigma deviation %.2f %%, lost %zu, %.0f s, %.3g particle-steps/s\n",
              r.peak_shear_stress_Pa / 1e3, phi_peak, r.peak_strain,
              r.residual_shear_stress_Pa / 1e3, phi_res, 100 * r.worst_normal_stress_deviation,
              r.particles_lost, r.wall_seconds, r.particle_steps_per_s);
  EXPECT_EQ(r.particles_lost, 0u);
  EXPECT_NEAR(r.consolidated_normal_stress_Pa, sigma, 0.01 * sigma);
  EXPECT_LT(r.worst_normal_stress_deviation, 0.05) << "servo at the paper's rate";
  // Dry sand with mu = 0.5 and mu_r = 0.16: a friction angle of a sand.
  EXPECT_GT(phi_peak, 25.0);
  EXPECT_LT(phi_peak, 55.0);
  EXPECT_LE(r.residual_shear_stress_Pa, r.peak_shear_stress_Pa);
}

TEST(ShearPaperLong, DryExampleAllPressuresThroughTheCli) {
  const std::string bin = CENTRIDEM_BINARY;
  if (std::system((bin + " shear --help > /dev/null 2>&1").c_str()) != 0)
    GTEST_SKIP() << "this centridem has no `shear` subcommand";
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / "centridem_shear_dry_long";
  std::filesystem::remove_all(out);
  const std::string cmd = bin + " shear " + kDry + " --jobs 2 --out " + out.string();
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  for (const char* f : {"summary.json", "shear_curves.png", "mohr_coulomb.png", "scenario.toml",
                        "shear_40kPa.csv", "shear_120kPa.csv"})
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
  std::ifstream in(out / "summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  ASSERT_EQ(s["runs"].size(), 5u);
  const double phi = s["mohr_coulomb"]["peak"]["friction_angle_deg"].get<double>();
  std::printf("dry Mohr-Coulomb peak: c = %.2f kPa, phi = %.1f deg\n",
              s["mohr_coulomb"]["peak"]["cohesion_Pa"].get<double>() / 1e3, phi);
  EXPECT_GT(phi, 20.0);
  EXPECT_LT(phi, 55.0);
  for (const auto& r : s["runs"]) EXPECT_EQ(r["particles_lost"].get<long>(), 0);
}
