// The shared preparation and the prepared slope foundation
// (io/preparation_config, procedures/foundation; docs/specimens.md
// "Preparation"; issue 16, acceptance 1 and 2): the paper examples share one
// [preparation] block; a small foundation and a small shear specimen prepared
// by the same block at the same compaction stress are equally dense; a
// prepared foundation is homogeneous, stood above the design before it was
// trimmed to it, and is cached; the layer porosity and the kinetic-energy
// ratio against closed forms.
#include "base/errors.hpp"
#include "engine/world.hpp"
#include "io/checkpoint.hpp"
#include "physics/body_field.hpp"
#include "procedures/direct_shear.hpp"
#include "procedures/foundation.hpp"
#include "procedures/paper_material.hpp"
#include "procedures/shear_config.hpp"
#include "procedures/slope_config.hpp"
#include "procedures/specimen.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <unistd.h>

using namespace centridem;
namespace fs = std::filesystem;

namespace {

// One material and one preparation block for both specimens (0.4-0.6 mm
// grains: few particles, so the test stays short).
const std::string kMaterial = R"(
[specimen]
gradation = { bins = [{ d_min_m = 0.4e-3, d_max_m = 0.6e-3, volume_fraction = 1.0 }] }
porosity = 0.50
density_kg_m3 = 2633.0
seed = 5
brick = { size_m = [3e-3, 3e-3, 3e-3] }
REGION

[contact.ball_ball]
model = "arrlinear"
effective_modulus_Pa = 300e6
stiffness_ratio = 1.5
friction = 0.5
rolling_friction = 0.16
attraction_force_N = 1.2e-4

[preparation]
during_compaction = { friction = 0.2, rolling_friction = 0.0, attraction_force_N = 0.0 }
ratio = 1e-3
COMPACTION
)";

std::string with(std::string s, const std::string& key, const std::string& value) {
  s.replace(s.find(key), key.size(), value);
  return s;
}

// A slope of s = 0.05 in a chamber 15 x 5 x 9 mm (about 6,500 grains when
// overfilled; s = 0.03: 9 x 3 x 5.4 mm, about 1,400); the benches do not
// matter before the cut.
SlopeScenario small_slope(const std::string& compaction, double s = 0.05) {
  const std::string text = with(with(kMaterial, "REGION", ""), "COMPACTION", compaction) +
                           "\n[slope]\nsize_reduction_factor = " + std::to_string(s) + R"(
benches = [{ height_m = 0.075, width_m = 0.03 }, { height_m = 0.075 }]
breadth_m = 0.10
[trial]
check_interval_steps = 1000
[campaign]
g_levels = [50]
)";
  return parse_slope_scenario(text, "small_slope.toml", ".");
}

FoundationResult prepare(const SlopeScenario& sc) {
  const SlopeGeometry geometry(sc.slope);
  WorldSettings ws;
  ws.local_damping = sc.trial.local_damping;
  World world(ws);
  FoundationResult f;
  const auto t0 = std::chrono::steady_clock::now();
  build_foundation(world, sc, geometry, "", sc.preparation.overfill, f);
  prepare_foundation(world, sc, geometry, f);
  std::printf("foundation prepared in %ld + %ld steps, %.0f s\n", f.compaction_steps,
              f.settle_steps,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return f;
}

double spread(const std::array<double, 3>& n) {
  return *std::max_element(n.begin(), n.end()) - *std::min_element(n.begin(), n.end());
}

double mean(const std::array<double, 3>& n) {
  return (n[0] + n[1] + n[2]) / 3.0;
}

} // namespace

// The shear and slope examples name the same preparation (the slope's soil is
// the soil the shear box calibrated, by construction).
TEST(Preparation, PaperExamplesShareOneBlock) {
  const std::string root = CENTRIDEM_SOURCE_DIR;
  const ShearScenario dry = load_shear_scenario(root + "/examples/paper/shear_dry.toml");
  const ShearScenario humid = load_shear_scenario(root + "/examples/paper/shear_humid.toml");
  const SlopeScenario lower = load_slope_scenario(root + "/examples/paper/slope_lower_bench.toml");
  const SlopeScenario higher =
      load_slope_scenario(root + "/examples/paper/slope_higher_bench.toml");
  const SlopeScenario demo = load_slope_scenario(root + "/examples/demo_slope.toml");
  ASSERT_TRUE(dry.preparation.enabled);
  EXPECT_EQ(dry.preparation, humid.preparation);
  EXPECT_EQ(dry.preparation, lower.preparation);
  EXPECT_EQ(dry.preparation, higher.preparation);
  EXPECT_EQ(dry.preparation, demo.preparation);
  // The compaction properties are the material's but for the patch.
  const DirectShearSpec s = humid.run_spec(40e3);
  ASSERT_TRUE(s.ball_ball_during_consolidation.has_value());
  EXPECT_EQ(s.ball_ball_during_consolidation->friction, 0.2);
  EXPECT_EQ(s.ball_ball_during_consolidation->attraction_force_N, 0.0);
  // The paper's after-cut rule is the slopes' default: only mu_r = 0.
  EXPECT_EQ(lower.soil_after_cut().rolling_friction, 0.0);
  EXPECT_EQ(lower.soil_after_cut().attraction_force_N, lower.soil().attraction_force_N);
}

// Acceptance 1: the shear box compacted by its servo at 20 kPa and the
// foundation compacted by a top plate at 20 kPa (its own weight adds about
// 3 kPa at the floor), both with the same block, reach porosities within
// 0.01 of each other (each measured away from its walls: one d_max left out
// inside every wall, three layers averaged).
TEST(Preparation, FoundationAndShearBoxPreparedAtOneStressAreEquallyDense) {
  const double sigma = 20e3;
  // The shear box (9 x 9 x 6 mm, about 2,600 grains), consolidated and
  // settled; a token shear.
  const ShearScenario sc = parse_shear_scenario(
      with(with(kMaterial, "REGION", "region = { lo_m = [0, 0, 0], hi_m = [9e-3, 9e-3, 6e-3] }"),
           "COMPACTION", "") +
          "\n[shear]\nnormal_stresses_Pa = [20e3]\nmax_shear_displacement_m = 1e-6\n"
          "shear_rate_m_per_s = 0.02\nrecord_interval_steps = 100\nservo_max_speed_m_per_s = 1.0\n",
      "small_box.toml", ".");
  WorldSettings ws;
  ws.local_damping = sc.local_damping;
  World box(ws);
  const BuiltSpecimen built = build_specimen(sc.specimen, box);
  box.set_ball_ball_defaults(sc.ball_ball);
  box.set_body_field(BodyField::scaled_gravity(sc.g_level, 1.0));
  const auto t0 = std::chrono::steady_clock::now();
  const DirectShearResult r = run_direct_shear(box, sc.run_spec(sigma));
  std::printf("shear box prepared in %ld steps, %.0f s\n", r.consolidation_steps,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  double d_max = 0;
  for (double rad : box.particles().radius) d_max = std::max(d_max, 2 * rad);
  const double zb = box.walls()[box.wall_index("bottom")].point.z;
  const double zt = box.walls()[box.wall_index("top")].point.z;
  const double box_porosity = mean(layer_porosities(box, Box{{0, 0, zb}, {9e-3, 9e-3, zt}}, d_max));

  // The foundation, the same block with a top plate at the same stress.
  const FoundationResult f =
      prepare(small_slope("compaction_g_level = 1.0\ncompaction_stress_Pa = 20e3"));
  const double foundation_porosity = mean(f.layer_porosity);
  std::printf("porosity away from the walls: shear box %.4f (%zu particles, whole box %.4f), "
              "foundation %.4f (layers %.4f / %.4f / %.4f)\n",
              box_porosity, built.report.particles, r.consolidated_porosity, foundation_porosity,
              f.layer_porosity[0], f.layer_porosity[1], f.layer_porosity[2]);
  EXPECT_GT(r.settling_steps, 0) << "the box was prepared (switched, then settled)";
  EXPECT_LT(std::abs(box_porosity - foundation_porosity), 0.01);
  // Both much denser than generated (0.50 ignoring overlaps).
  EXPECT_LT(box_porosity, 0.46);
}

// Acceptance 2 with the examples' compaction (gravity at 50 g, no plate):
// the prepared surface stood at or above the design before the trim, the
// excess was removed, and the three layers are within 0.01 of each other.
// The prepared foundation is cached by recipe: asked again it is read, not
// made; another recipe has another file.
TEST(Foundation, PreparedUnderGravityIsHomogeneousTrimmedToTheDesignAndCached) {
  const SlopeScenario sc = small_slope("compaction_g_level = 50.0");
  const std::string cache =
      (fs::temp_directory_path() / ("centridem_foundation_" + std::to_string(::getpid()))).string();
  fs::remove_all(cache);
  const PreparedFoundationFile pf = ensure_prepared_foundation(sc, cache);
  const FoundationResult& r = pf.result;
  const SlopeGeometry geometry(sc.slope);
  const double H = geometry.height();
  World w;
  read_checkpoint(w, pf.path);
  double top_centre = 0;
  for (const Vec3& x : w.particles().position) top_centre = std::max(top_centre, x.z);
  std::printf("generated %zu, trimmed %zu, kept %zu; surface before the trim %.3f mm (design "
              "%.3f mm); layers %.4f / %.4f / %.4f; coordination %.2f; %ld + %ld steps\n",
              r.generated_particles, r.trimmed, r.particles, 1e3 * r.prepared_surface_min_m,
              1e3 * H, r.layer_porosity[0], r.layer_porosity[1], r.layer_porosity[2],
              r.coordination_number, r.compaction_steps, r.settle_steps);
  EXPECT_TRUE(pf.made_now);
  EXPECT_TRUE(r.prepared);
  EXPECT_GE(r.prepared_surface_min_m, H);
  EXPECT_GT(r.trimmed, 0u);
  EXPECT_EQ(r.particles + r.trimmed, r.generated_particles);
  EXPECT_EQ(w.particles().size(), r.particles);
  EXPECT_LE(top_centre, H) << "nothing whose centre is above the design is left";
  EXPECT_LE(spread(r.layer_porosity), 0.01);
  EXPECT_LT(mean(r.layer_porosity), 0.46);
  EXPECT_GT(r.coordination_number, 3.0);
  EXPECT_EQ(w.ball_ball_defaults(), sc.soil()) << "switched to the soil";

  const PreparedFoundationFile again = ensure_prepared_foundation(sc, cache);
  EXPECT_FALSE(again.made_now);
  EXPECT_EQ(again.path, pf.path);
  EXPECT_EQ(to_json(again.result), to_json(pf.result));
  SlopeScenario other = sc;
  other.preparation.compaction_g_level = 40;
  EXPECT_NE(prepared_foundation_path(other, cache), pf.path);
  other = sc;
  other.ball_ball.attraction_range_m = 2e-6;
  EXPECT_NE(prepared_foundation_path(other, cache), pf.path);
  // The field is not in the key: the foundation is compacted under uniform
  // gravity whatever the trial's field, so trials in the radial field share it.
  other = sc;
  other.field.kind = FieldKind::centrifuge;
  other.field.base_radius_m = 1.5;
  other.field.coriolis = true;
  EXPECT_EQ(prepared_foundation_path(other, cache), pf.path);
  fs::remove_all(cache);
}

// Too little soil: the prepared surface below the design is refused, naming
// the key that fixes it.
TEST(Foundation, TooLittleOverfillIsRefusedWithTheKey) {
  try {
    prepare(small_slope("compaction_g_level = 50.0\noverfill = 1.0", 0.03));
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("preparation.overfill"), std::string::npos) << e.what();
  }
}

// Closed form: a simple cubic lattice of spheres (radius r, spacing d = 2r)
// has porosity 1 - pi/6 in any layer that spans whole lattice periods, with x
// and y bounds between the centres: with the bounds at the spheres' tangent
// planes, and with the layers cut through the sphere centres.
TEST(Foundation, LayerPorosityOfACubicLatticeIsOneMinusPiOverSix) {
  World w;
  const double r = 0.5e-3, d = 2 * r;
  const int n = 11;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        w.add_particle({(2 * i + 1) * r, (2 * j + 1) * r, (2 * k + 1) * r}, r, 2633.0);
  // Margin d: x and y from 2r to 20r (9 columns of centres over 9 spacings),
  // layers of 3 d from z = 2r.
  for (double v : layer_porosities(w, Box{{0, 0, 0}, {n * d, n * d, n * d}}, d))
    EXPECT_NEAR(v, 1 - std::numbers::pi / 6, 1e-12);
  // The box raised by r: the layers start and end at sphere centres.
  for (double v : layer_porosities(w, Box{{0, 0, r}, {n * d, n * d, n * d + r}}, d))
    EXPECT_NEAR(v, 1 - std::numbers::pi / 6, 1e-12);
}

// Closed form: one particle of diameter d moving at v under gravity g has
// kinetic energy / (m g d) = v^2 / (2 g d); at rest the ratio is 0.
TEST(Foundation, KineticEnergyRatioIsHalfVSquaredOverGD) {
  World w;
  const double r = 0.2e-3, v = 0.03, g = standard_gravity_m_s2 * 40;
  w.add_particle({0, 0, 1e-3}, r, 2633.0);
  w.set_body_field(BodyField::scaled_gravity(40.0, 1.0));
  EXPECT_DOUBLE_EQ(kinetic_energy_ratio(w, {0, 0, 0}, 2 * r), 0.0);
  w.particles_mut().velocity[0] = {v, 0, 0};
  EXPECT_NEAR(kinetic_energy_ratio(w, {0, 0, 0}, 2 * r), v * v / (2 * g * 2 * r), 1e-12);
}

// Closed form: the porosity profile of a simple cubic lattice (12 x 12 x 12
// spheres of diameter d): d_max = d50 = d, so the span 10 d is cut into 5
// layers of 2 d, each spanning whole lattice periods: 1 - pi/6 in every layer;
// three layers agree with the thirds.
TEST(Foundation, PorosityProfileOfACubicLatticeIsOneMinusPiOverSixInEveryLayer) {
  World w;
  const double r = 0.5e-3, d = 2 * r;
  const int n = 12;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        w.add_particle({(2 * i + 1) * r, (2 * j + 1) * r, (2 * k + 1) * r}, r, 2633.0);
  const Box box{{0, 0, 0}, {n * d, n * d, n * d}};
  const PorosityProfile p = foundation_porosity_profile(w, box);
  ASSERT_EQ(p.porosity.size(), 5u);
  EXPECT_NEAR(p.layer_m, 2 * d, 1e-15);
  EXPECT_NEAR(p.margin_m, d, 1e-15);
  for (std::size_t k = 0; k < p.porosity.size(); ++k) {
    EXPECT_NEAR(p.porosity[k], 1 - std::numbers::pi / 6, 1e-12) << "layer " << k;
    EXPECT_NEAR(p.z_bottom_m[k], d + 2 * d * static_cast<double>(k), 1e-15);
  }
  const std::vector<double> three = porosity_layers(w, box, d, 3);
  const std::array<double, 3> thirds = layer_porosities(w, box, d);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(three[k], thirds[k]);
  // A vacancy in the middle layer raises only that layer's porosity, by one
  // sphere over the layer's volume (10 d x 10 d x 2 d).
  w.remove_particles([&](std::size_t i) {
    const Vec3& x = w.particles().position[i];
    return std::abs(x.x - 5.5 * d) < r && std::abs(x.y - 5.5 * d) < r &&
           std::abs(x.z - 5.5 * d) < r;
  });
  const PorosityProfile q = foundation_porosity_profile(w, box);
  const double sphere = 4.0 / 3.0 * std::numbers::pi * r * r * r;
  for (std::size_t k = 0; k < q.porosity.size(); ++k)
    EXPECT_NEAR(q.porosity[k] - p.porosity[k], k == 2 ? sphere / (200 * d * d * d) : 0.0, 1e-12)
        << "layer " << k;
}
