#include "procedures/gsd.hpp"

#include "base/errors.hpp"
#include "io/plot.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <numbers>
#include <numeric>

namespace centridem {

namespace {

constexpr double kFractionTolerance = 1e-6;

std::string mm(double m) {
  return fmt::format("{:g} mm", m * 1e3);
}

double sphere_volume(double r) {
  return 4.0 / 3.0 * std::numbers::pi * r * r * r;
}

// Truncation (Tao et al. section 3.1): bins entirely at or below the cutoff
// are dropped, a bin that straddles it starts at the cutoff, and the dropped
// volume (with `fines`, volume below the first bin) joins the first remaining
// bin. Expects bins in increasing size.
std::vector<GradationBin> truncate(const std::vector<GradationBin>& bins, double fines,
                                   double cutoff_m, const std::string& cutoff_key) {
  const double largest = bins.back().d_max_m;
  if (!(cutoff_m >= 0) || !std::isfinite(cutoff_m))
    throw InputError(cutoff_key, fmt::format("{:g}", cutoff_m),
                     "must be >= 0 [m] (0 = no truncation)");
  if (cutoff_m >= largest)
    throw InputError(cutoff_key, fmt::format("{:g}", cutoff_m),
                     fmt::format("must be below the largest size of the gradation ({} = {:g} m): "
                                 "nothing would be left",
                                 mm(largest), largest));
  std::vector<GradationBin> out;
  double dropped = fines;
  for (const GradationBin& b : bins) {
    if (b.d_max_m <= cutoff_m && b.d_max_m < largest) {
      dropped += b.volume_fraction;
      continue;
    }
    GradationBin k = b;
    if (out.empty()) {
      k.d_min_m = std::max(k.d_min_m, cutoff_m);
      k.volume_fraction += dropped;
    }
    out.push_back(k);
  }
  return out;
}

} // namespace

std::vector<GradationBin> gradation_from_sieve(const SieveTable& t, double cutoff_m,
                                               const std::string& key) {
  if (t.rows.size() < 2)
    throw InputError(t.source, fmt::format("{} rows", t.rows.size()),
                     "a sieve table needs at least two sieves");
  std::vector<GradationBin> bins;
  for (std::size_t k = 1; k < t.rows.size(); ++k)
    bins.push_back({t.rows[k - 1].size_m, t.rows[k].size_m,
                    (t.rows[k].percent_passing - t.rows[k - 1].percent_passing) / 100.0});
  const SieveRow& smallest = t.rows.front();
  const double fines = smallest.percent_passing / 100.0;
  if (fines > 0 && cutoff_m < smallest.size_m && cutoff_m < t.rows.back().size_m)
    throw InputError(key, fmt::format("{:g}", cutoff_m),
                     fmt::format("{}:{}: {:g} % passes the smallest sieve ({}), and the sizes of "
                                 "that material are unknown: set {} to at least {:g} m (its volume "
                                 "then joins the first remaining bin), or add a sieve with 0 % "
                                 "passing",
                                 t.source, smallest.line, smallest.percent_passing,
                                 mm(smallest.size_m), key, smallest.size_m));
  return truncate(bins, fines, cutoff_m, key);
}

std::vector<GradationBin> gradation_from_bins(std::vector<GradationBin> bins, bool normalise,
                                              double cutoff_m, const std::string& where,
                                              const std::string& cutoff_key) {
  if (bins.empty()) throw InputError(where, "[]", "give at least one bin");
  double sum = 0;
  for (std::size_t k = 0; k < bins.size(); ++k) {
    const GradationBin& b = bins[k];
    const std::string at = fmt::format("{}[{}]", where, k);
    if (!(b.d_min_m > 0) || !std::isfinite(b.d_min_m))
      throw InputError(at + ".d_min_m", fmt::format("{:g}", b.d_min_m), "must be > 0 [m]");
    if (!(b.d_max_m >= b.d_min_m) || !std::isfinite(b.d_max_m))
      throw InputError(at + ".d_max_m", fmt::format("{:g}", b.d_max_m),
                       fmt::format("must be >= d_min_m = {:g} [m]", b.d_min_m));
    if (!(b.volume_fraction >= 0) || !std::isfinite(b.volume_fraction))
      throw InputError(at + ".volume_fraction", fmt::format("{:g}", b.volume_fraction),
                       "must be >= 0 (a share of the solid volume)");
    if (k > 0 && b.d_min_m < bins[k - 1].d_max_m)
      throw InputError(at + ".d_min_m", fmt::format("{:g}", b.d_min_m),
                       fmt::format("bins must be in increasing size without overlap: must be >= "
                                   "{}[{}].d_max_m = {:g} [m]",
                                   where, k - 1, bins[k - 1].d_max_m));
    sum += b.volume_fraction;
  }
  if (!(sum > 0)) throw InputError(where, "fractions summing to 0", "at least one must be > 0");
  if (std::abs(sum - 1.0) > kFractionTolerance) {
    if (!normalise)
      throw InputError(where, fmt::format("volume fractions summing to {:.9g}", sum),
                       fmt::format("they must sum to 1 (tolerance {:g}); correct them, or set "
                                   "normalise = true in the gradation to scale them to 1",
                                   kFractionTolerance));
  }
  if (normalise)
    for (GradationBin& b : bins) b.volume_fraction /= sum;
  return truncate(bins, 0.0, cutoff_m, cutoff_key);
}

std::vector<GradationBin> resolve_gradation(const SpecimenSpec& s) {
  if (s.sieve) return gradation_from_sieve(*s.sieve, s.cutoff_m, "specimen.cutoff_m");
  if (!s.bins.empty())
    return gradation_from_bins(s.bins, s.normalise, s.cutoff_m, "specimen.gradation.bins",
                               "specimen.cutoff_m");
  return {};
}

double mean_particle_volume(const GradationBin& b) {
  const double a = 0.5 * b.d_min_m, c = 0.5 * b.d_max_m;
  if (c - a <= 1e-12 * c) return sphere_volume(c);
  // <r^3> for r uniform in [a, c]: (c^4 - a^4) / (4 (c - a)).
  const double mean_r3 = (c * c * c * c - a * a * a * a) / (4.0 * (c - a));
  return 4.0 / 3.0 * std::numbers::pi * mean_r3;
}

double particles_per_solid_volume(const std::vector<GradationBin>& bins) {
  double n = 0;
  for (const GradationBin& b : bins) n += b.volume_fraction / mean_particle_volume(b);
  return n;
}

double target_d50(const std::vector<GradationBin>& bins) {
  // Within a bin with radii uniform in [a, c] the volume below radius r grows
  // as r^4 - a^4.
  double below = 0;
  for (const GradationBin& b : bins) {
    if (b.volume_fraction <= 0) continue;
    if (below + b.volume_fraction >= 0.5) {
      const double a = 0.5 * b.d_min_m, c = 0.5 * b.d_max_m;
      const double share = (0.5 - below) / b.volume_fraction;
      const double a4 = a * a * a * a, c4 = c * c * c * c;
      return 2.0 * std::pow(a4 + share * (c4 - a4), 0.25);
    }
    below += b.volume_fraction;
  }
  return bins.empty() ? 0.0 : bins.back().d_max_m;
}

double mass_median_diameter(std::vector<double> radii) {
  if (radii.empty()) return 0.0;
  std::sort(radii.begin(), radii.end());
  double total = 0;
  for (double r : radii) total += r * r * r;
  double cum = 0;
  for (std::size_t k = 0; k < radii.size(); ++k) {
    const double next = cum + radii[k] * radii[k] * radii[k];
    if (next >= 0.5 * total) {
      if (k == 0) return 2.0 * radii[0];
      // Linear in the cumulative fraction between particle k-1 and k.
      const double t = (0.5 * total - cum) / (next - cum);
      return 2.0 * (radii[k - 1] + t * (radii[k] - radii[k - 1]));
    }
    cum = next;
  }
  return 2.0 * radii.back();
}

std::vector<double> volume_fractions(const std::vector<double>& radii,
                                     const std::vector<GradationBin>& bins) {
  std::vector<double> v(bins.size() + 1, 0.0);
  double total = 0;
  for (double r : radii) {
    const double d = 2.0 * r, vol = r * r * r;
    total += vol;
    std::size_t k = 0;
    while (k < bins.size() &&
           !(d >= bins[k].d_min_m * (1 - 1e-12) && d <= bins[k].d_max_m * (1 + 1e-12)))
      ++k;
    v[k] += vol;
  }
  if (total > 0)
    for (double& x : v) x /= total;
  return v;
}

std::vector<double> draw_radii(const std::vector<GradationBin>& bins, double solid_volume_m3,
                               SpecimenRandom& random) {
  std::vector<double> radii;
  if (!(solid_volume_m3 > 0)) return radii;
  std::size_t finest = bins.size(); // the finest non-empty bin
  for (std::size_t k = 0; k < bins.size(); ++k)
    if (bins[k].volume_fraction > 0) {
      finest = k;
      break;
    }
  if (finest == bins.size()) return radii;
  radii.reserve(
      static_cast<std::size_t>(1.05 * solid_volume_m3 * particles_per_solid_volume(bins) + 16));
  double carry = 0; // volume the coarser bins missed [m^3]
  for (std::size_t k = bins.size(); k-- > finest;) {
    const GradationBin& b = bins[k];
    if (b.volume_fraction <= 0) continue;
    const double target = b.volume_fraction * solid_volume_m3 + carry;
    const double count = std::max(0.0, std::round(target / mean_particle_volume(b)));
    const auto n = static_cast<std::size_t>(count);
    const double a = 0.5 * b.d_min_m, c = 0.5 * b.d_max_m;
    double got = 0;
    for (std::size_t j = 0; j < n; ++j) {
      // Stratified: one radius uniformly within each of n equal slices of
      // [a, c]; the marginal stays uniform in [a, c].
      const double r = a + (c - a) * (static_cast<double>(j) + random.uniform()) / count;
      radii.push_back(r);
      got += sphere_volume(r);
    }
    carry = target - got;
  }
  return radii;
}

std::vector<std::pair<double, double>> passing_curve(std::vector<double> radii) {
  std::sort(radii.begin(), radii.end());
  double total = 0;
  for (double r : radii) total += r * r * r; // volumes up to 4/3 pi
  std::vector<std::pair<double, double>> out;
  double sum = 0;
  for (double r : radii) {
    sum += r * r * r;
    out.emplace_back(2 * r, total > 0 ? 100.0 * sum / total : 0.0);
  }
  return out;
}

std::vector<std::pair<double, double>> target_passing_curve(const std::vector<GradationBin>& bins) {
  std::vector<std::pair<double, double>> out;
  if (bins.empty()) return out;
  out.emplace_back(bins.front().d_min_m, 0.0);
  double sum = 0;
  for (const GradationBin& b : bins) {
    sum += b.volume_fraction;
    out.emplace_back(b.d_max_m, 100.0 * sum);
  }
  return out;
}

void plot_grain_size_curves(const std::vector<double>& radii, const SpecimenSpec& spec,
                            const std::string& png_path) {
  LinePlot p;
  p.title = "grain-size curves";
  p.x_label = "particle diameter (mm)";
  p.y_label = "percent passing by mass (%)";
  p.log_x = true;
  p.y_range = AxisRange{0, 100};
  p.legend = LegendPlace::upper_left;
  auto add = [&](const std::string& name, const std::vector<std::pair<double, double>>& c) {
    std::vector<double> x, y;
    for (const auto& [d, pct] : c) x.push_back(1e3 * d), y.push_back(pct);
    return &p.add(name, std::move(x), std::move(y));
  };
  if (spec.sieve) {
    std::vector<std::pair<double, double>> c;
    for (const SieveRow& r : spec.sieve->rows)
      if (r.size_m > 0) c.emplace_back(r.size_m, r.percent_passing);
    add("sieve analysis (" + spec.sieve_csv + ")", c)->markers(Marker::circle).dashed_line();
  }
  const std::vector<GradationBin> bins = resolve_gradation(spec);
  if (!bins.empty())
    add("target (the gradation generated from)", target_passing_curve(bins))
        ->markers(Marker::square);
  // The particles' curve, thinned to about 400 points.
  const auto all = passing_curve(radii);
  std::vector<std::pair<double, double>> thin;
  const std::size_t step = std::max<std::size_t>(1, all.size() / 400);
  for (std::size_t k = 0; k < all.size(); k += step) thin.push_back(all[k]);
  if (!all.empty() && (all.size() - 1) % step != 0) thin.push_back(all.back());
  add(fmt::format("generated ({} particles)", radii.size()), thin);
  p.render(png_path, 900, 600);
}

} // namespace centridem
