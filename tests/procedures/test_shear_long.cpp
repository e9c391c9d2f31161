// Opt-in (ctest -L long): the paper's dry direct shear example
// (examples/paper/shear_dry.toml, ~13,300 particles in 13.2 x 13.2 x 4.4 mm,
// 200 mm/min) at one pressure through the library, and the five pressures of
// the dry and the humid examples through `centridem shear --jobs 2`: the
// issue's acceptance (servo within 2 %, no particle lost, peaks rising with
// the normal stress, dry peak fit R^2 > 0.98, humid cohesion above dry).
// See docs/shear.md for the measured run times (hours per pressure).
#include "engine/world.hpp"
#include "io/csv.hpp"
#include "procedures/direct_shear.hpp"
#include "procedures/shear_config.hpp"
#include "procedures/specimen.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>
#include <string>

using namespace centridem;

namespace {
const std::string kDry = std::string(CENTRIDEM_SOURCE_DIR) + "/examples/paper/shear_dry.toml";
const std::string kHumid = std::string(CENTRIDEM_SOURCE_DIR) + "/examples/paper/shear_humid.toml";

// Mean shear stress over the part of a curve whose strain is in [lo, hi].
double mean_tau(const std::vector<std::pair<double, double>>& strain_tau, double lo, double hi) {
  double sum = 0;
  int n = 0;
  for (const auto& [e, t] : strain_tau)
    if (e >= lo && e <= hi) sum += t, ++n;
  EXPECT_GT(n, 0) << "no curve point in [" << lo << ", " << hi << "]";
  return n ? sum / n : 0.0;
}

// "Rises to a peak and softens or plateaus": the mean stress over the last
// 20 % of the strain is not above the mean over 40-60 % by more than 10 %. A
// loose specimen that hardens throughout (docs/results/shear.md section 2:
// 1.18-1.30 over its 20 % of strain, 1.14-1.37 over the first 15 %) fails this. The bound was 5 %
// until the paper runs measured how much this ratio scatters for one material: at 120 kPa,
// dry, 1.051 with seed 1 and 0.993 with seed 2, and 1.001 humid on the seed-1 packing; at 40-100
// kPa 0.92-0.98. A bound inside that scatter would fail a plateau by the luck of the packing; 1.10
// is above it and below the loose curves.
void expect_peak_then_level(const std::vector<std::pair<double, double>>& strain_tau,
                            double final_strain, const std::string& what) {
  const double middle = mean_tau(strain_tau, 0.4 * final_strain, 0.6 * final_strain);
  const double last = mean_tau(strain_tau, 0.8 * final_strain, final_strain);
  EXPECT_LE(last, 1.10 * middle) << what << ": still hardening";
}

// strain and shear stress of a curve CSV (columns as cmd_shear writes them:
// step,time_s,shear_displacement_m,shear_strain,shear_stress_Pa,...).
std::vector<std::pair<double, double>> read_curve(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line); // header
  std::vector<std::pair<double, double>> c;
  for (int n = 2; std::getline(in, line); ++n) {
    const auto f = split_commas(line);
    const std::string where = csv.string() + ":" + std::to_string(n);
    if (f.size() < 5) throw std::runtime_error(where + ": fewer than 5 columns");
    c.emplace_back(parse_finite_number(f[3], where), parse_finite_number(f[4], where));
  }
  return c;
}
} // namespace

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
  // Dry sand with mu = 0.5 and mu_r = 0.16, prepared medium-dense: a friction
  // angle of a sand, and a curve that levels off or softens.
  EXPECT_GT(phi_peak, 25.0);
  std::vector<std::pair<double, double>> curve;
  for (const ShearPoint& p : r.curve) curve.emplace_back(p.shear_strain, p.shear_stress_Pa);
  expect_peak_then_level(curve, r.curve.back().shear_strain, "dry 100 kPa");
  EXPECT_LT(phi_peak, 55.0);
  EXPECT_LE(r.residual_shear_stress_Pa, r.peak_shear_stress_Pa);
}

namespace {
// Runs `centridem shear SCENARIO --jobs 2` into a temporary folder and returns
// its summary.json (the acceptance items 1, 2 and 4).
std::filesystem::path out_dir(const std::string& name) {
  return std::filesystem::temp_directory_path() / name;
}

nlohmann::json run_paper_shear(const std::string& scenario, const std::string& name) {
  const std::string bin = CENTRIDEM_BINARY;
  const std::filesystem::path out = out_dir(name);
  std::filesystem::remove_all(out);
  const std::string cmd = bin + " shear " + scenario + " --jobs 2 --out " + out.string();
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  for (const char* f : {"summary.json", "shear_curves.png", "mohr_coulomb.png", "scenario.toml",
                        "shear_40kPa.csv", "shear_120kPa.csv"})
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
  std::ifstream in(out / "summary.json");
  return nlohmann::json::parse(in);
}

// Servo within 2 %, no particle lost, peaks rising with the normal stress,
// each curve levelling off or softening after its peak.
void expect_paper_quality(const nlohmann::json& s, const std::filesystem::path& dir,
                          double final_strain) {
  ASSERT_EQ(s["runs"].size(), 5u);
  double last_peak = 0;
  for (const auto& r : s["runs"]) {
    expect_peak_then_level(read_curve(dir / r["curve_csv"].get<std::string>()), final_strain,
                           r["curve_csv"].get<std::string>());
    EXPECT_LE(r["residual_shear_stress_Pa"].get<double>(), r["peak_shear_stress_Pa"].get<double>());
    EXPECT_EQ(r["particles_lost"].get<long>(), 0);
    EXPECT_LT(r["worst_normal_stress_deviation"].get<double>(), 0.02)
        << r["normal_stress_target_Pa"].get<double>() << " Pa";
    EXPECT_GT(r["peak_shear_stress_Pa"].get<double>(), last_peak);
    last_peak = r["peak_shear_stress_Pa"].get<double>();
  }
}
} // namespace

TEST(ShearPaperLong, DryAndHumidAllPressuresThroughTheCli) {
  const nlohmann::json dry = run_paper_shear(kDry, "centridem_shear_dry_long");
  const nlohmann::json humid = run_paper_shear(kHumid, "centridem_shear_humid_long");
  const ShearScenario sc = load_shear_scenario(kDry);
  const double final_strain = sc.test.max_shear_displacement_m / sc.test.box.height_m;
  expect_paper_quality(dry, out_dir("centridem_shear_dry_long"), final_strain);
  expect_paper_quality(humid, out_dir("centridem_shear_humid_long"), final_strain);
  const auto& dp = dry["mohr_coulomb"]["peak"];
  const auto& hp = humid["mohr_coulomb"]["peak"];
  std::printf("Mohr-Coulomb peak: dry c = %.2f kPa, phi = %.1f deg (R^2 %.3f); humid c = %.2f "
              "kPa, phi = %.1f deg (R^2 %.3f)\n",
              dp["cohesion_Pa"].get<double>() / 1e3, dp["friction_angle_deg"].get<double>(),
              dp["r_squared"].get<double>(), hp["cohesion_Pa"].get<double>() / 1e3,
              hp["friction_angle_deg"].get<double>(), hp["r_squared"].get<double>());
  EXPECT_GT(dp["r_squared"].get<double>(), 0.98);
  EXPECT_GT(dp["friction_angle_deg"].get<double>(), 20.0);
  EXPECT_LT(dp["friction_angle_deg"].get<double>(), 55.0);
  // Humid sand: adhesion adds a cohesion intercept.
  EXPECT_GT(hp["cohesion_Pa"].get<double>(), dp["cohesion_Pa"].get<double>());
}
