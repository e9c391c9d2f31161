// The automatic Verlet skin (WorldSettings::neighbour_skin_m = 0): how thick a
// shell the neighbour lists keep around each particle, chosen at every rebuild
// from how fast the last lists were used up.
//
// A thicker skin lists more pairs that do not touch (each read and tested every
// step, and its history and end-2 slots stored); a thinner one is used up
// sooner and the lists are rebuilt more often (a rebuild re-sorts the
// particles and costs about what 4 to 5 steps cost). The rule: the skin the
// motion uses up in about kRebuildIntervalSteps steps,
//   s = kRebuildIntervalSteps x r,
// r [m/step] the rate at which the skin is used up: the larger of its mean
// over the last lists (twice the largest particle displacement, or the
// largest particle plus wall displacement, the rebuild criterion of
// World::integrate, over the steps since the rebuild) and the rate at the
// present speeds (2 v_max dt, or (v_max + wall speed) dt: a packing that
// starts to move after a long rest is not judged by its rest), bounded to [largest / 16, largest],
// largest = half the smallest radius (the fixed skin before the choice was automatic, so a list is
// never thicker than it was then). So rebuilds take at most about 5 % of the time, and a packing
// that barely moves keeps a thin shell.
//
// Measured (issue 18, docs/results/bench.md): on the 30,000-sphere bench
// packing at rest the lists fall from 3.49 to about 2.6 entries per particle
// and the benchmark runs faster; the flowing column, whose motion uses up the
// largest skin in about 90 steps, keeps it. The rule reads only the run's own
// state (displacements and step counts), never a timing, so the skin, the
// rebuild steps and the bits of a run do not depend on the machine or the
// thread count.
#pragma once

#include <algorithm>

namespace centridem {

inline constexpr double kRebuildIntervalSteps = 100.0; // [steps]

// The skin [m] for the next lists. used_m: how much of the skin the last lists
// used up [m] over `steps` steps; rate_now_m_per_step: the rate at the present
// speeds [m/step]; largest_m: the bound above [m].
inline double automatic_skin_m(double used_m, long steps, double rate_now_m_per_step,
                               double largest_m) {
  if (steps <= 0) return largest_m;
  const double rate = std::max(used_m / static_cast<double>(steps), rate_now_m_per_step);
  return std::clamp(kRebuildIntervalSteps * rate, largest_m / 16.0, largest_m);
}

} // namespace centridem
