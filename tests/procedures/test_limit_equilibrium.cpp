// Bishop's simplified method and the critical-circle search
// (src/procedures/limit_equilibrium.hpp) against closed forms and classical
// results: exact moment equilibrium for phi = 0; Taylor's stability numbers
// for phi = 0 toe circles (Taylor, D.W. 1937, Stability of earth slopes,
// J. Boston Soc. Civ. Eng. 24(3):197-246); the infinite-slope limit for
// c = 0; a published c-phi benchmark; the consistency of the critical g-level.
#include "base/errors.hpp"
#include "physics/body_field.hpp"
#include "procedures/limit_equilibrium.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace centridem {
namespace {

constexpr double deg = std::numbers::pi / 180;

// A simple slope of height H and angle beta facing +x: crest plateau from
// x = 0, toe at z = 0, floor at -depth.
LeSection simple_slope(double H, double beta_deg, double crest = 30, double toe = 40,
                       double depth = 15) {
  const double run = beta_deg == 90 ? 0 : H / std::tan(beta_deg * deg);
  return {{{0, H}, {crest, H}, {crest + run, 0}, {crest + run + toe, 0}}, -depth};
}

LeSection mirrored(const LeSection& s) {
  LeSection m{{}, s.floor_z_m};
  for (auto it = s.surface.rbegin(); it != s.surface.rend(); ++it)
    m.surface.emplace_back(-it->first, it->second);
  return m;
}

// Ground level of a section (upper value at a vertical face), for the
// independent strip integration below.
double ground(const LeSection& s, double x) {
  double z = -1e300;
  for (std::size_t i = 0; i + 1 < s.surface.size(); ++i) {
    const auto [x0, z0] = s.surface[i];
    const auto [x1, z1] = s.surface[i + 1];
    if (x < x0 || x > x1) continue;
    z = std::max(z, x1 == x0 ? std::max(z0, z1) : z0 + (z1 - z0) * (x - x0) / (x1 - x0));
  }
  return z;
}

TEST(LimitEquilibrium, UndrainedCircleIsExactMomentEquilibrium) {
  // phi = 0: FS = c R L_arc / sum(W x lever arm), integrated here with
  // 400,000 strips, independent of the library's slices.
  const LeSection s = simple_slope(10, 60);
  const LeSoil soil{40e3, 0, 18e3};
  const LeCircle c{32, 22, 23};
  const double R = c.radius_m;
  const auto h = [&](double x) {
    return ground(s, x) - (c.zc_m - std::sqrt(std::max(0.0, R * R - (x - c.xc_m) * (x - c.xc_m))));
  };
  const auto cross = [&](double out, double in) { // bisection between a point outside and inside
    for (int i = 0; i < 200; ++i) {
      const double m = 0.5 * (out + in);
      (h(m) > 0 ? in : out) = m;
    }
    return 0.5 * (out + in);
  };
  const double x0 = cross(c.xc_m - R, c.xc_m), x1 = cross(c.xc_m + R, c.xc_m);
  const int n = 400000;
  double moment = 0;
  for (int i = 0; i < n; ++i) {
    const double x = x0 + (i + 0.5) * (x1 - x0) / n;
    moment += soil.unit_weight_N_m3 * std::max(0.0, h(x)) * (x1 - x0) / n * (c.xc_m - x);
  }
  const double arc = R * (std::asin((x1 - c.xc_m) / R) - std::asin((x0 - c.xc_m) / R));
  const double exact = soil.cohesion_Pa * R * arc / moment;
  const auto fs = bishop_factor_of_safety(s, soil, c, 60);
  ASSERT_TRUE(fs.has_value());
  std::printf("phi = 0 circle: Bishop %.6f, exact moment equilibrium %.6f (x %.2f..%.2f m)\n", *fs,
              exact, x0, x1);
  EXPECT_NEAR(*fs, exact, 0.005 * exact);
  // The mirrored circle on the mirrored section: the same FS.
  const auto fs_m = bishop_factor_of_safety(mirrored(s), soil, {-c.xc_m, c.zc_m, R}, 60);
  ASSERT_TRUE(fs_m.has_value());
  EXPECT_NEAR(*fs_m, *fs, 1e-9 * *fs);
}

TEST(LimitEquilibrium, RejectsInadmissibleCircles) {
  const LeSection s = simple_slope(10, 60);
  const LeSoil soil{40e3, 30, 18e3};
  EXPECT_FALSE(bishop_factor_of_safety(s, soil, {32, 40, 5}).has_value());  // in the air
  EXPECT_FALSE(bishop_factor_of_safety(s, soil, {32, 5, 100}).has_value()); // beyond the ends
  const LeSection wide = simple_slope(10, 60, 60, 60, 15);
  EXPECT_TRUE(bishop_factor_of_safety(wide, soil, {62, 22, 36}).has_value());  // bottom at -14
  EXPECT_FALSE(bishop_factor_of_safety(wide, soil, {62, 22, 38}).has_value()); // -16 < floor
  EXPECT_EQ(bishop_factor_of_safety(s, {0, 0, 18e3}, {32, 22, 23}), 0.0);      // no strength
  // m_alpha guard: with phi = 0, m_alpha = cos(alpha) < 0.2 at a near-vertical
  // crest entry (centre 0.5 m above the crest) rejects the circle.
  const LeSection s45 = simple_slope(10, 45);
  EXPECT_FALSE(bishop_factor_of_safety(s45, {20e3, 0, 18e3}, {25, 10.5, 15}).has_value());
  EXPECT_TRUE(bishop_factor_of_safety(s45, {20e3, 0, 18e3}, {25, 14, 15}).has_value());
}

// phi = 0: the critical g-level n of a slope of height H gives Taylor's
// stability number N_s = gamma(n) H / c.
double stability_number(double beta_deg) {
  const double H = 10, c = 500e3, rho = 2000;
  const LeCriticalG r = critical_g_level(simple_slope(H, beta_deg), c, 0, rho);
  EXPECT_TRUE(r.bracketed);
  EXPECT_NEAR(r.at_critical.factor_of_safety, 1, 1e-4);
  const auto& k = r.at_critical.circle;
  std::printf("beta %g: N_s = %.4f at n = %.3f; circle (%.2f, %.2f) R %.2f, x %.2f..%.2f, "
              "%d circles\n",
              beta_deg, r.g_level * rho * standard_gravity_m_s2 * H / c, r.g_level, k.xc_m, k.zc_m,
              k.radius_m, r.at_critical.x_entry_m, r.at_critical.x_exit_m,
              r.at_critical.circles_tried);
  return r.g_level * rho * standard_gravity_m_s2 * H / c;
}

TEST(LimitEquilibrium, TaylorStabilityNumberVerticalCut) {
  EXPECT_NEAR(stability_number(90), 3.83, 0.02 * 3.83);
}

TEST(LimitEquilibrium, TaylorStabilityNumberSixtyDegrees) {
  EXPECT_NEAR(stability_number(60), 5.24, 0.03 * 5.24);
}

TEST(LimitEquilibrium, CohesionlessSlopeApproachesInfiniteSlope) {
  const LeSearchResult r = critical_circle(simple_slope(10, 30), {0, 35, 18e3});
  const double infinite = std::tan(35 * deg) / std::tan(30 * deg);
  std::printf("c = 0: FS %.4f vs tan(phi)/tan(beta) %.4f; circle (%.2f, %.2f) R %.2f, "
              "x %.2f..%.2f\n",
              r.factor_of_safety, infinite, r.circle.xc_m, r.circle.zc_m, r.circle.radius_m,
              r.x_entry_m, r.x_exit_m);
  EXPECT_GE(r.factor_of_safety, infinite * 0.999);
  EXPECT_NEAR(r.factor_of_safety, infinite, 0.03 * infinite);
}

// ACADS slope stability programs review, problem 1(a) (Giam & Donald 1989,
// used in the verification manuals of slope programs): a 2:1 slope 10 m high
// on a 5 m foundation, c = 3 kPa, phi = 19.6 deg, gamma = 20 kN/m^3, no water;
// referee FS 1.00, Bishop-method programs about 0.99. This section faces -x.
TEST(LimitEquilibrium, CohesiveFrictionalSlope) {
  const LeSection s{{{20, 25}, {30, 25}, {50, 35}, {70, 35}}, 20};
  const LeSearchResult r = critical_circle(s, {3e3, 19.6, 20e3});
  std::printf("ACADS 1(a): FS %.4f; circle (%.2f, %.2f) R %.2f, x %.2f..%.2f\n", r.factor_of_safety,
              r.circle.xc_m, r.circle.zc_m, r.circle.radius_m, r.x_entry_m, r.x_exit_m);
  EXPECT_NEAR(r.factor_of_safety, 1.0, 0.03);
}

TEST(LimitEquilibrium, CriticalGLevelConsistency) {
  const LeSection s = simple_slope(10, 45);
  const double c = 100e3, phi = 25, rho = 1800;
  double previous = std::numeric_limits<double>::infinity();
  for (double n : {1.0, 2.0, 4.0, 8.0, 16.0}) {
    const double fs =
        critical_circle(s, {c, phi, rho * standard_gravity_m_s2 * n}).factor_of_safety;
    std::printf("c-phi slope: n = %g, FS %.4f\n", n, fs);
    EXPECT_LT(fs, previous);
    previous = fs;
  }
  const LeCriticalG g = critical_g_level(s, c, phi, rho);
  ASSERT_TRUE(g.bracketed);
  const double fs =
      critical_circle(s, {c, phi, rho * standard_gravity_m_s2 * g.g_level}).factor_of_safety;
  std::printf("c-phi slope: critical n = %.4f, FS there %.6f\n", g.g_level, fs);
  EXPECT_NEAR(fs, 1.0, 1e-3);
  EXPECT_NEAR(g.at_critical.factor_of_safety, fs, 1e-12);
  // Not bracketed: already failing at n_lo, still stable at n_hi.
  LeCriticalGOptions o;
  o.n_lo = 1.5 * g.g_level, o.n_hi = 1000;
  const LeCriticalG low = critical_g_level(s, c, phi, rho, o);
  EXPECT_FALSE(low.bracketed);
  EXPECT_EQ(low.g_level, o.n_lo);
  EXPECT_LT(low.at_critical.factor_of_safety, 1);
  o.n_lo = 1, o.n_hi = 0.5 * g.g_level;
  const LeCriticalG high = critical_g_level(s, c, phi, rho, o);
  EXPECT_FALSE(high.bracketed);
  EXPECT_EQ(high.g_level, o.n_hi);
  EXPECT_GT(high.at_critical.factor_of_safety, 1);
}

TEST(LimitEquilibrium, MirroredSectionSameMinimum) {
  const LeSection s = simple_slope(10, 45);
  const LeSoil soil{20e3, 30, 19e3};
  const LeSearchResult a = critical_circle(s, soil), b = critical_circle(mirrored(s), soil);
  std::printf("facing +x: FS %.5f (x %.2f..%.2f); facing -x: FS %.5f (x %.2f..%.2f)\n",
              a.factor_of_safety, a.x_entry_m, a.x_exit_m, b.factor_of_safety, b.x_entry_m,
              b.x_exit_m);
  EXPECT_NEAR(a.factor_of_safety, b.factor_of_safety, 1e-3 * a.factor_of_safety);
  EXPECT_NEAR(a.x_entry_m, -b.x_exit_m, 0.01 * 10);
  // The slip lies on the slope: below the crest at its upslope end.
  EXPECT_LT(a.x_entry_m, 30 + 5);
  EXPECT_GT(b.x_exit_m, -30 - 5);
}

TEST(LimitEquilibrium, RefusesBadInput) {
  const LeSection s = simple_slope(10, 60);
  const LeCircle c{32, 22, 23};
  const auto key = [&](const LeSection& sec, const LeSoil& soil) {
    try {
      bishop_factor_of_safety(sec, soil, c);
    } catch (const InputError& e) {
      return e.key();
    }
    return std::string("(accepted)");
  };
  EXPECT_EQ(key(s, {-1, 30, 18e3}), "soil.cohesion_Pa");
  EXPECT_EQ(key(s, {10e3, 90, 18e3}), "soil.friction_angle_deg");
  EXPECT_EQ(key(s, {10e3, -1, 18e3}), "soil.friction_angle_deg");
  EXPECT_EQ(key(s, {10e3, 30, 0}), "soil.unit_weight_N_m3");
  EXPECT_EQ(key(s, {NAN, 30, 18e3}), "soil.cohesion_Pa");
  EXPECT_EQ(key({{{0, 10}}, 0}, {10e3, 30, 18e3}), "section.surface");
  EXPECT_EQ(key({{{0, 10}, {5, NAN}}, 0}, {10e3, 30, 18e3}), "section.surface[1].z");
  EXPECT_EQ(key({{{0, 10}, {5, 10}, {4, 0}}, 0}, {10e3, 30, 18e3}), "section.surface[2].x");
  EXPECT_EQ(key({{{0, 10}, {5, -1}}, 0}, {10e3, 30, 18e3}), "section.surface[1].z");
  EXPECT_THROW(bishop_factor_of_safety(s, {10e3, 30, 18e3}, {32, 22, -1}), InputError);
  EXPECT_THROW(critical_g_level(s, 10e3, 30, -5), InputError);
  EXPECT_EQ(key(s, {10e3, 30, 18e3}), "(accepted)");
}

// A benched slope of ~20 points at centrifuge model scale (70 degree faces
// 3 cm high, 2 cm benches, 0.3 m in all): the time one critical g-level
// takes, for information.
TEST(LimitEquilibrium, BenchedSlopeTiming) {
  std::vector<std::pair<double, double>> pts{{0, 0.30}};
  double x = 0.20, z = 0.30;
  pts.emplace_back(x, z);
  for (int i = 0; i < 8; ++i) {
    x += 0.03 / std::tan(70 * deg), z -= 0.03;
    pts.emplace_back(x, z);
    if (i < 7) x += 0.02, pts.emplace_back(x, z);
  }
  pts.emplace_back(x + 0.25, z);
  const LeSection s{pts, 0};
  const auto t0 = std::chrono::steady_clock::now();
  const LeCriticalG g = critical_g_level(s, 2e3, 35, 1600);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("benched slope (%zu points): critical n = %.3f (bracketed %d, FS %.5f), "
              "x %.3f..%.3f m, %.2f s\n",
              pts.size(), g.g_level, g.bracketed, g.at_critical.factor_of_safety,
              g.at_critical.x_entry_m, g.at_critical.x_exit_m, secs);
  RecordProperty("critical_g_level_seconds", std::to_string(secs));
  EXPECT_TRUE(g.bracketed);
  EXPECT_NEAR(g.at_critical.factor_of_safety, 1, 1e-4);
  EXPECT_EQ(g.at_critical.slip_surface.size(), 61u);
}

} // namespace
} // namespace centridem
