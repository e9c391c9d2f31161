// Grain size distribution (GSD): from a sieve table or explicit bins to the
// size classes a specimen is generated from, the paper's truncation rule, the
// statistics of a target gradation and of generated particles, and the
// seeded drawing of radii.
//
// Conventions (docs/specimens.md):
//   - A bin is a diameter range [d_min, d_max] with its share of the solid
//     volume. Within a bin the RADIUS is uniformly distributed (PFC's
//     convention for `ball distribute` / `ball generate` with a size range),
//     so the bin's mean particle volume is (4/3) pi <r^3> with
//     <r^3> = (r_max^4 - r_min^4) / (4 (r_max - r_min)).
//   - Truncation (Tao et al. section 3.1): sizes below the cutoff are dropped
//     and their volume is added to the first remaining bin (which starts at
//     the cutoff when the cutoff falls inside it).
//   - Volume fractions are mass fractions (one particle density).
#pragma once

#include "io/specimen_config.hpp"

#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace centridem {

// Bins from a sieve table truncated at cutoff_m: one bin per pair of
// consecutive sieves with the difference of their percent passing; the
// material passing the smallest sieve has unknown sizes, so it needs a cutoff
// at or above the smallest sieve (then it joins the first remaining bin).
// `key` names the cutoff in messages (e.g. "specimen.cutoff_m").
std::vector<GradationBin> gradation_from_sieve(const SieveTable& table, double cutoff_m,
                                               const std::string& key);

// Checks explicit bins (`where` names them, e.g. "specimen.gradation.bins"):
// diameters > 0, d_min <= d_max, bins in increasing size without overlap,
// fractions >= 0 summing to 1 within 1e-6 (or scaled to 1 when `normalise`),
// then truncates at cutoff_m (0 = none).
std::vector<GradationBin> gradation_from_bins(std::vector<GradationBin> bins, bool normalise,
                                              double cutoff_m, const std::string& where,
                                              const std::string& cutoff_key);

// The gradation a spec generates (sieve or explicit bins, truncated); empty
// when the spec gives none. Throws InputError.
std::vector<GradationBin> resolve_gradation(const SpecimenSpec& spec);

// Mean particle volume of a bin with radii uniform in [d_min/2, d_max/2] [m^3].
double mean_particle_volume(const GradationBin& bin);

// Expected particles per unit solid volume (1 / mean particle volume by
// volume fractions) [1/m^3].
double particles_per_solid_volume(const std::vector<GradationBin>& bins);

// Mass-median diameter of the target gradation (radii uniform within bins):
// the diameter below which half the volume lies [m].
double target_d50(const std::vector<GradationBin>& bins);

// Mass-median diameter of a set of particles: the diameter at which the
// cumulative volume (particles sorted by size) reaches one half, interpolated
// linearly between the two particles that straddle it [m].
double mass_median_diameter(std::vector<double> radii);

// Volume fraction of `radii` falling in each bin (a particle belongs to the
// first bin with d_min <= d <= d_max); the last entry is the fraction outside
// every bin. Size bins.size() + 1.
std::vector<double> volume_fractions(const std::vector<double>& radii,
                                     const std::vector<GradationBin>& bins);

// Grain-size curves, percent passing by mass against diameter, as a sieve
// analysis reports them. Of a set of particles: one point per particle in
// increasing size, (d, 100 x volume of the particles up to and including it /
// total volume) [m, %]. Of a target gradation: the bin edges, (d_min of the
// first bin, 0), then (d_max of each bin, cumulative fraction) [m, %].
std::vector<std::pair<double, double>> passing_curve(std::vector<double> radii);
std::vector<std::pair<double, double>> target_passing_curve(const std::vector<GradationBin>& bins);

// gsd.png: the target's curve, the sieve analysis it came from (when the spec
// has one) and the generated particles' curve, on a log diameter axis in mm.
void plot_grain_size_curves(const std::vector<double>& radii, const SpecimenSpec& spec,
                            const std::string& png_path);

// The random source of specimen generation: std::mt19937_64 with the
// specimen's seed, turned into doubles by the top 53 bits (the same on every
// platform, unlike std::uniform_real_distribution).
class SpecimenRandom {
public:
  explicit SpecimenRandom(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; } // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  std::uint64_t bits() { return engine_(); }

private:
  std::mt19937_64 engine_;
};

// Radii whose total volume is `solid_volume_m3` split between the bins by
// their volume fractions. For each bin, from the coarsest, the number of
// particles is the bin's volume (plus what the coarser bins missed) over its
// mean particle volume, rounded; the radii are drawn uniformly within the
// bin, stratified (one radius uniformly within each of n equal slices of the
// radius range, so the marginal distribution is still uniform but the bin's
// volume stays at its expected value); what a bin misses is carried to the
// next finer one, so the total misses by at most about half a particle of the
// finest bin. Returned in drawing order (coarse bins first, increasing size
// within a bin); shuffle before placing.
std::vector<double> draw_radii(const std::vector<GradationBin>& bins, double solid_volume_m3,
                               SpecimenRandom& random);

} // namespace centridem
