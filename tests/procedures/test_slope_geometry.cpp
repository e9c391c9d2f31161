// Benched slope geometry (src/procedures/slope_geometry.hpp) against the
// paper's dimensions (Tao et al. section 2.1) and the particle counts it
// states (../shared/REFERENCE.md "Specimens": 47,070 particles in the
// foundation; 30,044 after the cut for the lower first bench, 31,020 for the
// higher one). For a uniform specimen the removed particle fraction equals
// the excavated area fraction of the section.
#include "base/errors.hpp"
#include "engine/world.hpp"
#include "procedures/slope_geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

namespace centridem {
namespace {

constexpr double s = 0.063;
const double tan70 = std::tan(70.0 * std::numbers::pi / 180.0);

TEST(SlopeGeometry, LowerFirstBenchKeyPoints) {
  const SlopeGeometry g(BenchedSlope::paper_lower_first_bench());
  // Model box in DEM coordinates: 0.301 x 0.20 x 0.18 m times 0.063.
  EXPECT_NEAR(g.length(), 0.301 * s, 1e-15);
  EXPECT_NEAR(g.breadth(), 0.20 * s, 1e-15);
  EXPECT_NEAR(g.height(), 0.18 * s, 1e-15);
  EXPECT_NEAR(g.toe_height(), 0.03 * s, 1e-15);
  // Crest edge 13.5 cm from the wall; upper face 11.25 cm high at 70 deg;
  // first bench 3 cm wide at z = 3 + 3.75 cm; lower face 3.75 cm high.
  const double x_crest = 0.135 * s;
  const double x_bench = x_crest + 0.1125 / tan70 * s;
  const double x_bench_edge = x_bench + 0.03 * s;
  const double x_toe = x_bench_edge + 0.0375 / tan70 * s;
  EXPECT_NEAR(g.crest_x(), x_crest, 1e-15);
  EXPECT_NEAR(g.toe_x(), x_toe, 1e-15);
  EXPECT_NEAR(g.toe_x() / s, 0.2196, 1e-4); // 21.96 cm from the back wall, model scale
  EXPECT_DOUBLE_EQ(g.z_surface(0.0), 0.18 * s);
  EXPECT_DOUBLE_EQ(g.z_surface(0.5 * x_crest), 0.18 * s);
  EXPECT_NEAR(g.z_surface(x_crest), 0.18 * s, 1e-15);
  EXPECT_NEAR(g.z_surface(0.5 * (x_crest + x_bench)), (0.18 - 0.1125 / 2) * s, 1e-12);
  EXPECT_NEAR(g.z_surface(x_bench), 0.0675 * s, 1e-12);
  EXPECT_NEAR(g.z_surface(0.5 * (x_bench + x_bench_edge)), 0.0675 * s, 1e-12);
  EXPECT_NEAR(g.z_surface(0.5 * (x_bench_edge + x_toe)), (0.03 + 0.0375 / 2) * s, 1e-12);
  EXPECT_NEAR(g.z_surface(x_toe), 0.03 * s, 1e-12);
  EXPECT_NEAR(g.z_surface(g.length()), 0.03 * s, 1e-15);
  EXPECT_NEAR(g.z_surface(2 * g.length()), 0.03 * s, 1e-15); // clamped

  // Outline: wall top, crest, bench foot, bench edge, toe, end of model.
  const auto outline = g.outline();
  ASSERT_EQ(outline.size(), 6u);
  EXPECT_DOUBLE_EQ(outline[0].x, 0.0);
  EXPECT_NEAR(outline[1].x, x_crest, 1e-15);
  EXPECT_NEAR(outline[2].x, x_bench, 1e-15);
  EXPECT_NEAR(outline[3].x, x_bench_edge, 1e-15);
  EXPECT_NEAR(outline[4].x, x_toe, 1e-15);
  EXPECT_NEAR(outline[5].x, g.length(), 1e-15);
  EXPECT_DOUBLE_EQ(outline[5].z, 0.03 * s);

  // Soil and excavation (centres).
  const double yc = 0.5 * g.breadth();
  EXPECT_TRUE(g.is_soil({0.5 * x_crest, yc, 0.17 * s}));
  EXPECT_FALSE(g.is_soil({0.5 * x_crest, yc, 0.19 * s}));    // above the crest
  EXPECT_FALSE(g.is_soil({0.5 * x_crest, -1e-6, 0.17 * s})); // outside the breadth
  EXPECT_TRUE(g.is_soil({0.5 * (x_bench + x_bench_edge), yc, 0.06 * s}));
  EXPECT_TRUE(g.excavated({0.5 * (x_bench + x_bench_edge), yc, 0.07 * s}));
  EXPECT_TRUE(g.excavated({0.28 * s, yc, 0.04 * s}));
  EXPECT_FALSE(g.excavated({0.28 * s, yc, 0.02 * s}));

  // Bench columns.
  EXPECT_EQ(g.bench_at(0.0), 2);
  EXPECT_EQ(g.bench_at(x_bench - 1e-9), 2);
  EXPECT_EQ(g.bench_at(x_bench + 1e-9), 1);
  EXPECT_EQ(g.bench_at(x_toe - 1e-9), 1);
  EXPECT_EQ(g.bench_at(x_toe + 1e-9), 0);
  EXPECT_NEAR(g.bench_column(1).first, x_bench, 1e-15);
  EXPECT_NEAR(g.bench_column(1).second, x_toe, 1e-15);
  EXPECT_THROW((void)g.bench_column(3), InputError);
}

TEST(SlopeGeometry, ClassifyZones) {
  const SlopeGeometry g(BenchedSlope::paper_lower_first_bench());
  const double x_crest = g.crest_x();
  const double x_bench = x_crest + 0.1125 / tan70 * s;
  const double x_toe = g.toe_x();
  EXPECT_EQ(g.classify(0.5 * x_crest, 0.175 * s), (ZoneId{SlopeZone::crest, 2}));
  EXPECT_EQ(g.classify(x_crest + 0.02 * s, 0.12 * s), (ZoneId{SlopeZone::upper_face, 2}));
  EXPECT_EQ(g.classify(x_bench + 0.015 * s, 0.066 * s), (ZoneId{SlopeZone::bench_top, 1}));
  EXPECT_EQ(g.classify(x_toe - 0.005 * s, 0.045 * s), (ZoneId{SlopeZone::lower_face, 1}));
  EXPECT_EQ(g.classify(x_toe + 0.03 * s, 0.029 * s), (ZoneId{SlopeZone::toe, 0}));
  // A point above the excavated floor (debris) is a toe point too.
  EXPECT_EQ(g.classify(0.29 * s, 0.06 * s), (ZoneId{SlopeZone::toe, 0}));
  EXPECT_EQ(to_string(ZoneId{SlopeZone::bench_top, 1}), "bench_top_1");
  EXPECT_EQ(to_string(ZoneId{SlopeZone::upper_face, 2}), "upper_face");
  // Three benches: the middle bench's face is a lower face of bench 2.
  BenchedSlope three;
  three.benches = {{0.05, 0.02, 70}, {0.05, 0.02, 60}, {0.05, std::nullopt, 50}};
  const SlopeGeometry g3(three);
  const auto [c0, c1] = g3.bench_column(2);
  EXPECT_EQ(g3.bench_at(0.5 * (c0 + c1)), 2);
  EXPECT_EQ(g3.classify(c1 - 1e-4 * s, 0.09 * s).zone, SlopeZone::lower_face);
  EXPECT_EQ(g3.classify(c1 - 1e-4 * s, 0.09 * s).bench, 2);
  const double run3 = 0.05 / std::tan(50.0 * std::numbers::pi / 180.0) * s;
  EXPECT_EQ(g3.classify(c0 - 0.5 * run3 + 0.002 * s, 0.155 * s).zone, SlopeZone::upper_face);
  EXPECT_EQ(g3.classify(c0 + 0.01 * s, 0.132 * s), (ZoneId{SlopeZone::bench_top, 2}));
}

// The removed fraction of the foundation, area against REFERENCE.md's
// particle counts: lower first bench 17,026 / 47,070 = 36.2 %; higher first
// bench (47,070 - 31,020) / 47,070 = 34.1 %.
TEST(SlopeGeometry, ExcavatedFractionsMatchThePapersParticleCounts) {
  const SlopeGeometry lower(BenchedSlope::paper_lower_first_bench());
  const SlopeGeometry higher(BenchedSlope::paper_higher_first_bench());
  const double ref_lower = (47070.0 - 30044.0) / 47070.0;
  const double ref_higher = (47070.0 - 31020.0) / 47070.0;
  std::printf("excavated area fraction: lower %.4f (paper %.4f), higher %.4f (paper %.4f)\n",
              lower.excavated_fraction(), ref_lower, higher.excavated_fraction(), ref_higher);
  EXPECT_NEAR(lower.excavated_fraction(), ref_lower, 0.015);
  EXPECT_NEAR(higher.excavated_fraction(), ref_higher, 0.015);
  // The two slopes differ by the 3 cm x 3.75 cm block (REFERENCE.md), which at
  // 70 degrees is the parallelogram of the shifted first bench.
  EXPECT_NEAR(lower.excavated_area_model_m2() - higher.excavated_area_model_m2(), 0.03 * 0.0375,
              1e-12);
  // Analytical check of the lower slope's excavated area (model scale).
  const double r1 = 0.0375 / tan70, r2 = 0.1125 / tan70;
  const double x_toe = 0.135 + r2 + 0.03 + r1;
  const double area = 0.5 * 0.1125 * r2 + 0.1125 * 0.03 + (0.1125 * r1 + 0.5 * 0.0375 * r1) +
                      0.15 * (0.301 - x_toe);
  EXPECT_NEAR(lower.excavated_area_model_m2(), area, 1e-12);
  EXPECT_NEAR(lower.section_area_model_m2(), 0.301 * 0.18, 1e-15);
}

TEST(SlopeGeometry, ExcavateRemovesParticlesAboveTheSurface) {
  // A lattice of particles filling the DEM box: what is left is the soil.
  const SlopeGeometry g(BenchedSlope::paper_higher_first_bench());
  WorldSettings ws;
  ws.threads = 1;
  World w(ws);
  // Cell-centred lattice partitioning the box (midpoint rule in x and z).
  const int nx = 120, ny = 4, nz = 72;
  const double hx = g.length() / nx, hy = g.breadth() / ny, hz = g.height() / nz;
  std::size_t inside = 0;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) {
        const Vec3 x{(i + 0.5) * hx, (j + 0.5) * hy, (k + 0.5) * hz};
        w.add_particle(x, 0.05e-3, 2633);
        if (g.is_soil(x)) ++inside;
      }
  const std::size_t total = w.particles().size();
  const std::size_t removed = g.excavate(w);
  EXPECT_EQ(w.particles().size(), inside);
  EXPECT_EQ(removed, total - inside);
  for (const Vec3& x : w.particles().position) EXPECT_TRUE(g.is_soil(x));
  // The lattice fraction approximates the area fraction.
  EXPECT_NEAR(static_cast<double>(removed) / static_cast<double>(total), g.excavated_fraction(),
              0.005);
}

TEST(SlopeGeometry, VerticalFacesAndJson) {
  BenchedSlope v = BenchedSlope::paper_lower_first_bench();
  for (Bench& b : v.benches) b.face_angle_deg = 90;
  const SlopeGeometry g(v);
  EXPECT_NEAR(g.toe_x(), (0.135 + 0.03) * s, 1e-15);
  EXPECT_NEAR(g.z_surface(g.crest_x()), 0.18 * s, 1e-15); // upper value at a vertical face
  EXPECT_NEAR(g.z_surface(g.crest_x() + 1e-9), 0.0675 * s, 1e-12);
  const nlohmann::json j = to_json(g);
  EXPECT_EQ(j["model_scale"]["benches"].size(), 2u);
  EXPECT_DOUBLE_EQ(j["model_scale"]["benches"][1]["width_m"].get<double>(), 0.135);
  EXPECT_EQ(j["outline_xz_m"].size(), 6u);
  EXPECT_EQ(j["zones"][0]["zone"], "crest");
}

// Validation names the offending key.
std::string key_of(const BenchedSlope& b) {
  try {
    validate(b);
  } catch (const InputError& e) {
    return e.key();
  }
  return "";
}

TEST(SlopeGeometry, ValidationNamesTheKey) {
  const BenchedSlope ok = BenchedSlope::paper_lower_first_bench();
  EXPECT_EQ(key_of(ok), "");
  EXPECT_EQ(key_of(BenchedSlope::paper_higher_first_bench()), "");
  auto with = [&](auto change) {
    BenchedSlope b = ok;
    change(b);
    return key_of(b);
  };
  EXPECT_EQ(with([](BenchedSlope& b) { b.total_height_m = -0.18; }), "slope.total_height_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.foundation_height_m = -0.01; }),
            "slope.foundation_height_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.foundation_height_m = 0.2; }),
            "slope.foundation_height_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.breadth_m = 0; }), "slope.breadth_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.crest_to_wall_m = -1; }), "slope.crest_to_wall_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.length_m = NAN; }), "slope.length_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.size_reduction_factor = 0; }),
            "slope.size_reduction_factor");
  EXPECT_EQ(with([](BenchedSlope& b) { b.benches.clear(); }), "slope.benches");
  EXPECT_EQ(with([](BenchedSlope& b) { b.benches[1].face_angle_deg = 0; }),
            "slope.benches[1].face_angle_deg");
  EXPECT_EQ(with([](BenchedSlope& b) { b.benches[0].face_angle_deg = 91; }),
            "slope.benches[0].face_angle_deg");
  EXPECT_EQ(with([](BenchedSlope& b) { b.benches[0].height_m = -0.0375; }),
            "slope.benches[0].height_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.benches[0].width_m = -0.03; }),
            "slope.benches[0].width_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.benches[0].width_m.reset(); }),
            "slope.benches[0].width_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.benches[1].width_m = 0.1; }), "slope.benches[1].width_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.benches[1].width_m = 0.135; }), ""); // = crest plateau
  // Heights must add up to the slope height (15 cm).
  EXPECT_EQ(with([](BenchedSlope& b) { b.benches[1].height_m = 0.1; }), "slope.benches");
  // Benches that do not fit: a 2 cm long model, or gentle faces.
  EXPECT_EQ(with([](BenchedSlope& b) { b.length_m = 0.2; }), "slope.length_m");
  EXPECT_EQ(with([](BenchedSlope& b) { b.benches[1].face_angle_deg = 30; }), "slope.length_m");
  // The message states the value and what is allowed; the constructor checks.
  BenchedSlope bad = ok;
  bad.benches[0].face_angle_deg = 120;
  try {
    SlopeGeometry g(bad);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("(0, 90]"), std::string::npos) << e.what();
  }
  // A custom prefix for the key.
  try {
    validate(bad, "trial.slope");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "trial.slope.benches[0].face_angle_deg");
  }
}

} // namespace
} // namespace centridem
