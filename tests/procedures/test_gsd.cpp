// Grain size distribution: sieve tables, explicit bins, the paper's
// truncation rule, target statistics, drawing radii, and the messages a bad
// distribution stops with (issue 3, acceptance 1 and 5).
#include "base/errors.hpp"
#include "io/specimen_config.hpp"
#include "procedures/gsd.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numbers>
#include <string>

using namespace centridem;

namespace {

const std::string kPaperCsv =
    std::string(CENTRIDEM_SOURCE_DIR) + "/examples/data/hiroshima_sand_gsd.csv";

// Runs f, expects an InputError whose message contains every one of `parts`.
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

double sphere_volume(double r) {
  return 4.0 / 3.0 * std::numbers::pi * r * r * r;
}

} // namespace

// The paper's rule applied to the example sieve table (a copy of the shared
// reference): 72/15/10/3 % in 0.25-0.425/0.425-0.6/0.6-0.85/0.85-1.0 mm and a
// mass-median diameter of 0.393 mm with radii uniform within the bins.
TEST(Gsd, PaperSieveTableTruncatedAtQuarterMillimetre) {
  const SieveTable t = read_sieve_csv(kPaperCsv);
  ASSERT_EQ(t.rows.size(), 8u);
  EXPECT_DOUBLE_EQ(t.rows.front().size_m, 0.075e-3);
  const std::vector<GradationBin> bins = gradation_from_sieve(t, 0.25e-3, "cutoff_m");
  ASSERT_EQ(bins.size(), 4u);
  const double lo[4] = {0.25e-3, 0.425e-3, 0.6e-3, 0.85e-3};
  const double hi[4] = {0.425e-3, 0.6e-3, 0.85e-3, 1.0e-3};
  const double f[4] = {0.72, 0.15, 0.10, 0.03};
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_DOUBLE_EQ(bins[k].d_min_m, lo[k]);
    EXPECT_DOUBLE_EQ(bins[k].d_max_m, hi[k]);
    EXPECT_NEAR(bins[k].volume_fraction, f[k], 1e-12);
  }
  EXPECT_NEAR(target_d50(bins), 0.393e-3, 0.0005e-3);
  // 17.3 particles per mm^3 at porosity 0.52 (REFERENCE.md, "Specimens").
  EXPECT_NEAR(0.48 * particles_per_solid_volume(bins) * 1e-9, 17.35, 0.05);
}

// A cutoff inside a sieve interval: the interval starts at the cutoff and
// takes everything finer.
TEST(Gsd, CutoffInsideAnIntervalStartsTheFirstBinThere) {
  const SieveTable t = read_sieve_csv(kPaperCsv);
  const std::vector<GradationBin> bins = gradation_from_sieve(t, 0.3e-3, "cutoff_m");
  ASSERT_EQ(bins.size(), 4u);
  EXPECT_DOUBLE_EQ(bins[0].d_min_m, 0.3e-3);
  EXPECT_NEAR(bins[0].volume_fraction, 0.72, 1e-12);
  // Truncation at the smallest sieve keeps every interval; the 6 % passing
  // it joins the first.
  const std::vector<GradationBin> all = gradation_from_sieve(t, 0.075e-3, "cutoff_m");
  ASSERT_EQ(all.size(), 7u);
  EXPECT_NEAR(all[0].volume_fraction, 0.09, 1e-12);
}

TEST(Gsd, ExplicitBinsTruncatedAndNormalised) {
  std::vector<GradationBin> in = {
      {0.1e-3, 0.2e-3, 0.2}, {0.2e-3, 0.4e-3, 0.5}, {0.4e-3, 0.8e-3, 0.3}};
  auto out = gradation_from_bins(in, false, 0.25e-3, "bins", "cutoff_m");
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out[0].d_min_m, 0.25e-3);
  EXPECT_NEAR(out[0].volume_fraction, 0.7, 1e-12);
  EXPECT_NEAR(out[1].volume_fraction, 0.3, 1e-12);
  // Fractions summing to 2: refused, unless normalisation is asked for.
  for (auto& b : in) b.volume_fraction *= 2;
  expect_input_error([&] { gradation_from_bins(in, false, 0, "specimen.gradation.bins", "c"); },
                     {"specimen.gradation.bins", "summing to 2", "must sum to 1", "normalise"});
  out = gradation_from_bins(in, true, 0, "bins", "cutoff_m");
  ASSERT_EQ(out.size(), 3u);
  EXPECT_NEAR(out[1].volume_fraction, 0.5, 1e-12);
}

// Acceptance 5: a bad distribution stops with a message that names where,
// the value and what is allowed.
TEST(Gsd, BadDistributionsStopWithClearMessages) {
  const std::string src = "gsd.csv";
  // Fractions not summing to 1 (beyond 1e-6).
  expect_input_error(
      [] {
        gradation_from_bins({{0.25e-3, 0.5e-3, 0.5}, {0.5e-3, 1e-3, 0.4999}}, false, 0,
                            "specimen.gradation.bins", "specimen.cutoff_m");
      },
      {"specimen.gradation.bins", "0.9999", "must sum to 1", "tolerance 1e-06"});
  // Percent passing not increasing.
  expect_input_error(
      [&] { parse_sieve_csv("sieve_mm,percent_passing\n0.25,30\n0.5,20\n1.0,100\n", src); },
      {"gsd.csv:3", "percent_passing", "20", "must not decrease", ">= 30"});
  // Sizes not increasing.
  expect_input_error(
      [&] { parse_sieve_csv("# c\nsieve_mm,percent_passing\n0.5,30\n0.25,40\n1.0,100\n", src); },
      {"gsd.csv:4", "sieve_mm", "0.25", "must increase"});
  // Cutoff above the largest size.
  const SieveTable t = parse_sieve_csv("sieve_mm,percent_passing\n0.25,0\n1.0,100\n", src);
  expect_input_error([&] { gradation_from_sieve(t, 2e-3, "specimen.cutoff_m"); },
                     {"specimen.cutoff_m = 0.002", "must be below the largest size", "1 mm"});
  expect_input_error(
      [] {
        gradation_from_bins({{0.25e-3, 1e-3, 1.0}}, false, 1e-3, "bins", "specimen.cutoff_m");
      },
      {"specimen.cutoff_m", "must be below the largest size"});
  // Negative values.
  expect_input_error([&] { parse_sieve_csv("sieve_mm,percent_passing\n0.25,-3\n1,100\n", src); },
                     {"gsd.csv:2", "percent_passing", "-3", ">= 0"});
  expect_input_error(
      [] {
        gradation_from_bins({{0.25e-3, 1e-3, -1.0}}, false, 0, "bins", "c");
      },
      {"bins[0].volume_fraction", "-1", ">= 0"});
  expect_input_error(
      [] {
        gradation_from_bins({{-1e-3, 1e-3, 1.0}}, false, 0, "bins", "c");
      },
      {"bins[0].d_min_m", "> 0"});
  // Wrong or missing CSV columns, bad numbers, a curve that does not reach 100 %.
  expect_input_error(
      [&] { parse_sieve_csv("size_mm,percent_passing\n0.25,0\n1,100\n", src); },
      {"gsd.csv:1 header", "unexpected column \"size_mm\"", "sieve_mm,percent_passing"});
  expect_input_error([&] { parse_sieve_csv("sieve_mm\n0.25\n1\n", src); },
                     {"gsd.csv:1 header", "missing column percent_passing"});
  expect_input_error([&] { parse_sieve_csv("sieve_mm,percent_passing\n0.25,abc\n1,100\n", src); },
                     {"gsd.csv:2 column percent_passing", "\"abc\"", "finite number"});
  expect_input_error([&] { parse_sieve_csv("sieve_mm,percent_passing\n0.25,0,7\n1,100\n", src); },
                     {"gsd.csv:2", "expected 2 values"});
  expect_input_error([&] { parse_sieve_csv("sieve_mm,percent_passing\n0.25,0\n1,90\n", src); },
                     {"gsd.csv:3", "90", "largest sieve must pass 100 %"});
  // Bins that overlap; fines of unknown size below the cutoff.
  expect_input_error(
      [] {
        gradation_from_bins({{0.25e-3, 0.5e-3, 0.5}, {0.4e-3, 1e-3, 0.5}}, false, 0, "bins", "c");
      },
      {"bins[1].d_min_m", "increasing size without overlap"});
  const SieveTable fines = parse_sieve_csv("sieve_mm,percent_passing\n0.25,10\n1,100\n", src);
  expect_input_error([&] { gradation_from_sieve(fines, 0.0, "specimen.cutoff_m"); },
                     {"specimen.cutoff_m", "10 % passes the smallest sieve", "at least 0.00025"});
}

TEST(Gsd, MassMedianOfParticles) {
  // Equal volumes at 1 and 3 mm radius classes: the median lies between.
  EXPECT_DOUBLE_EQ(mass_median_diameter({1.0}), 2.0);
  EXPECT_DOUBLE_EQ(mass_median_diameter({1.0, 1.0, 1.0, 1.0}), 2.0);
  // Volumes 1, 1, 8: half the volume (5) is reached inside the last particle.
  const double d = mass_median_diameter({1.0, 1.0, 2.0});
  EXPECT_GT(d, 2.0);
  EXPECT_LE(d, 4.0);
}

// Drawing radii: per-bin volume fractions and the total solid volume match
// the target closely; the count is the expected one; seeds reproduce.
TEST(Gsd, DrawnRadiiMatchTheGradation) {
  const std::vector<GradationBin> bins =
      gradation_from_sieve(read_sieve_csv(kPaperCsv), 0.25e-3, "cutoff_m");
  const double solid = 0.48 * std::pow(4.4e-3, 3);
  SpecimenRandom r1(1), r2(1), r3(2);
  const std::vector<double> a = draw_radii(bins, solid, r1);
  const std::vector<double> b = draw_radii(bins, solid, r2);
  const std::vector<double> c = draw_radii(bins, solid, r3);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  for (const auto* radii : {&a, &c}) {
    double v = 0;
    for (double r : *radii) v += sphere_volume(r);
    EXPECT_NEAR(v, solid, sphere_volume(0.2125e-3)); // within one particle of the finest bin
    const std::vector<double> f = volume_fractions(*radii, bins);
    for (std::size_t k = 0; k < bins.size(); ++k)
      EXPECT_NEAR(f[k], bins[k].volume_fraction, 0.01) << "bin " << k;
    EXPECT_EQ(f.back(), 0.0);
    EXPECT_NEAR(mass_median_diameter(*radii), target_d50(bins), 0.01 * target_d50(bins));
    EXPECT_NEAR(static_cast<double>(radii->size()), solid * particles_per_solid_volume(bins), 3.0);
    for (double r : *radii) {
      EXPECT_GE(2 * r, 0.25e-3);
      EXPECT_LE(2 * r, 1.0e-3);
    }
  }
}

// The curves of the gsd.png picture `generate` draws: percent passing by mass
// (volume) against diameter, closed form.
TEST(GrainSizeCurves, PassingByMassOfParticlesAndOfTheTargetBins) {
  // Radii 1, 1, 2 (volumes 1, 1, 8 in units of 4/3 pi): 20 % at d = 2, 100 % at d = 4.
  const auto c = passing_curve({2.0, 1.0, 1.0});
  ASSERT_EQ(c.size(), 3u);
  EXPECT_DOUBLE_EQ(c[0].first, 2.0);
  EXPECT_DOUBLE_EQ(c[0].second, 10.0);
  EXPECT_DOUBLE_EQ(c[1].second, 20.0);
  EXPECT_DOUBLE_EQ(c[2].first, 4.0);
  EXPECT_DOUBLE_EQ(c[2].second, 100.0);
  // Bins: 0 at the smallest d_min, then the cumulative fraction at each d_max.
  const auto t = target_passing_curve({{0.25e-3, 0.425e-3, 0.7}, {0.425e-3, 0.85e-3, 0.3}});
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0], std::make_pair(0.25e-3, 0.0));
  EXPECT_DOUBLE_EQ(t[1].first, 0.425e-3);
  EXPECT_DOUBLE_EQ(t[1].second, 70.0);
  EXPECT_DOUBLE_EQ(t[2].second, 100.0);
}
