// How a pass over the particle rows is divided among the threads
// (engine-internal).
//
// Each thread takes one contiguous block of rows: the particles are in cell
// order, so most neighbours of a row lie in the same block and stay in one
// core's caches. Equal numbers of rows are not equal work, though: the rows
// at the bottom of a packing have more contacts than those near its surface
// (2 threads on the shared packing: the contact pass's busier thread 2.8 %
// longer than the other). So the blocks follow the clock: each pass times
// every thread's block, and the next pass moves each boundary an eighth of
// the way towards the row where the measured cost would be shared equally.
//
// Which thread computes a row never changes a bit of the results: a row's
// sums are its own, made in a fixed order (engine/contact_pass.cpp,
// engine/integration.cpp). The split may therefore depend on timing.
#pragma once

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

namespace centridem {

class WorkSplit {
public:
  // The rows [first, last) of thread `me` of `team` in a pass over n rows.
  // The measured split is used when it was made for this team and these
  // rows; otherwise equal blocks.
  std::pair<std::size_t, std::size_t> block(int me, int team, std::size_t n) const {
    const auto t = static_cast<std::size_t>(team), k = static_cast<std::size_t>(me);
    if (bound_.size() != t + 1 || bound_.back() != n) return {n * k / t, n * (k + 1) / t};
    return {bound_[k], bound_[k + 1]};
  }

  // The boundaries of all team blocks, as block() gives them (team + 1 rows).
  void bounds(int team, std::size_t n, std::vector<std::size_t>& out) const {
    out.resize(static_cast<std::size_t>(team) + 1);
    for (int k = 0; k < team; ++k) out[static_cast<std::size_t>(k)] = block(k, team, n).first;
    out.back() = n;
  }

  // Each thread's time in its block [s], written by that thread only, in a
  // pass where team > 1. Outside the parallel region, before the pass:
  // prepare(team, n).
  void prepare(int team, std::size_t n) {
    const auto t = static_cast<std::size_t>(team);
    if (bound_.size() == t + 1 && bound_.back() == n) return;
    bound_.resize(t + 1);
    for (std::size_t k = 0; k <= t; ++k) bound_[k] = n * k / t;
    busy_s_.assign(t, 0.0);
  }
  void record(int me, double seconds) {
    if (static_cast<std::size_t>(me) < busy_s_.size())
      busy_s_[static_cast<std::size_t>(me)] = seconds;
  }

  // After the pass: each inner boundary moves an eighth of the way towards
  // the row where the cumulative cost (each block's time spread evenly over
  // its rows) reaches its share. The eighth damps the clock's step-to-step
  // noise (a few per cent of a block's time): moved halfway, the boundary
  // wandered by 2 % of the rows around its place, as much as it gains. A
  // step growing with the gap (to half the way at 20 %) did not lower the
  // wait on a noisy host (docs/results/bench.md, 2026-12-07): the gaps there
  // change from step to step, faster than a split made after the pass.
  void rebalance() {
    const std::size_t t = busy_s_.size();
    if (t < 2 || bound_.size() != t + 1) return;
    double total = 0.0, slowest = 0.0;
    for (double s : busy_s_) {
      if (!(s > 0.0)) return; // a block not timed (first pass, an empty block)
      total += s;
      slowest = std::max(slowest, s);
    }
    waited_s_ += slowest - total / static_cast<double>(t);
    next_ = bound_;
    std::size_t k = 0;   // the block the target lies in
    double before = 0.0; // cost of the blocks before block k [s]
    for (std::size_t b = 1; b < t; ++b) {
      const double want = total * static_cast<double>(b) / static_cast<double>(t);
      while (k + 1 < t && before + busy_s_[k] < want) before += busy_s_[k++];
      const double rows = static_cast<double>(bound_[k + 1] - bound_[k]);
      const double target = static_cast<double>(bound_[k]) +
                            rows * std::clamp((want - before) / busy_s_[k], 0.0, 1.0);
      const double moved =
          static_cast<double>(bound_[b]) + 0.125 * (target - static_cast<double>(bound_[b]));
      next_[b] = std::clamp(static_cast<std::size_t>(moved), next_[b - 1], bound_.back());
    }
    bound_.swap(next_);
  }

  // The time the threads waited for the slowest at the end of the passes
  // since construction, averaged over the team: the sum over timed passes of
  // the slowest block's time minus the mean block time [s] (0 with one
  // thread). What a pass loses to unequal blocks, be it the split or a core
  // slowed by other work; the bench prints it as a share of the wall time.
  double waited_seconds() const { return waited_s_; }

private:
  std::vector<std::size_t> bound_; // team + 1 row boundaries
  std::vector<double> busy_s_;     // each thread's time in its block at the last pass [s]
  std::vector<std::size_t> next_;  // rebalance()'s new boundaries (kept: no allocation per pass)
  double waited_s_ = 0.0;          // see waited_seconds() [s]
};

} // namespace centridem
