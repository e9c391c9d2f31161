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
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
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
    stolen_s_.assign(t * t, 0.0);
  }
  void record(int me, double seconds) {
    if (static_cast<std::size_t>(me) < busy_s_.size())
      busy_s_[static_cast<std::size_t>(me)] = seconds;
  }
  // Time thread `thief` spent on rows it took from thread `victim`'s block
  // (RowClaims below) in this pass [s]: counted as the victim's block's cost.
  // Each thread clears its own entries at the start of a pass (begin_thefts).
  void begin_thefts(int me) {
    const std::size_t t = busy_s_.size(), k = static_cast<std::size_t>(me);
    if (k < t) std::fill_n(stolen_s_.begin() + static_cast<std::ptrdiff_t>(k * t), t, 0.0);
  }
  void record_theft(int thief, int victim, double seconds) {
    const std::size_t t = busy_s_.size();
    const auto a = static_cast<std::size_t>(thief), b = static_cast<std::size_t>(victim);
    if (a < t && b < t) stolen_s_[a * t + b] += seconds;
  }

  // Test hook: the boundaries of the blocks (team + 1 rows, first 0, last n),
  // as if the clock had moved them there.
  void set_bounds(std::vector<std::size_t> bounds) {
    bound_ = std::move(bounds);
    busy_s_.assign(bound_.size() - 1, 0.0);
    stolen_s_.assign(busy_s_.size() * busy_s_.size(), 0.0);
  }

  // After the pass: each inner boundary moves an eighth of the way towards
  // the row where the cumulative cost (each block's time spread evenly over
  // its rows) reaches its share. The eighth damps the clock's step-to-step
  // noise (a few per cent of a block's time): moved halfway, the boundary
  // wandered by 2 % of the rows around its place, as much as it gains.
  void rebalance() {
    const std::size_t t = busy_s_.size();
    if (t < 2 || bound_.size() != t + 1) return;
    // A block's cost: its owner's time and the time others spent on the rows
    // they took from it.
    for (std::size_t a = 0; a < t && stolen_s_.size() == t * t; ++a)
      for (std::size_t b = 0; b < t; ++b) busy_s_[b] += stolen_s_[a * t + b];
    double total = 0.0;
    for (double s : busy_s_) {
      if (!(s > 0.0)) return; // a block not timed (first pass, an empty block)
      total += s;
    }
    std::vector<std::size_t> next(bound_);
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
      next[b] = std::clamp(static_cast<std::size_t>(moved), next[b - 1], bound_.back());
    }
    bound_ = std::move(next);
  }

private:
  std::vector<std::size_t> bound_; // team + 1 row boundaries
  std::vector<double> busy_s_;     // each thread's time in its block at the last pass [s]
  std::vector<double> stolen_s_;   // [thief * team + victim]: time on taken rows [s]
};

// The rows of a pass handed out while it runs, so that a thread that ends its
// block early helps the others (the contact pass: on a shared machine one core
// is now and then slowed for a few hundred microseconds, and the other then
// waited at the end of the pass; per step the two blocks' times differed by
// 50-160 us of a 1 ms step, docs/results/bench.md).
//
// Each thread's block [first, end) is a range of unclaimed rows. Its owner
// claims rows from the top, kClaimRows at a time, and walks them downwards;
// a thread whose own range is empty takes the lower half of the largest range
// left (if it holds at least 2 kClaimRows), which becomes a block of its own.
// Every row is claimed exactly once. The results do not depend on who takes
// what: a particle's sums run in an order that does not depend on where the
// blocks start and end (engine/contact_pass.cpp), and every block boundary is
// reported to integrate() (boundaries()).
class RowClaims {
public:
  static constexpr std::size_t kClaimRows = 128;

  // The ranges are a pass's scratch: a copied World starts without them.
  RowClaims() = default;
  RowClaims(const RowClaims&) {}
  RowClaims& operator=(const RowClaims&) { return *this; }

  // Before the pass: one range per thread, the blocks of `split`.
  void prepare(const WorkSplit& split, int team, std::size_t n) {
    const auto t = static_cast<std::size_t>(team);
    if (size_ != t) {
      range_ = std::make_unique<Range[]>(t);
      taken_.assign(t, {});
      for (auto& v : taken_) v.reserve(64); // no allocation in the pass, as a rule
      size_ = t;
    }
    for (int k = 0; k < team; ++k) {
      const auto [a, b] = split.block(k, team, n);
      range_[static_cast<std::size_t>(k)].lo_hi.store(pack(a, b), std::memory_order_relaxed);
      taken_[static_cast<std::size_t>(k)].clear();
    }
  }

  // The owner: claims up to kClaimRows more rows below `limit` (its range's
  // top); false when none are left.
  bool claim(int me, std::size_t& limit) {
    std::atomic<std::uint64_t>& a = range_[static_cast<std::size_t>(me)].lo_hi;
    std::uint64_t cur = a.load(std::memory_order_relaxed);
    for (;;) {
      const std::size_t lo = cur >> 32, hi = cur & 0xFFFFFFFFu;
      if (lo >= hi) return false;
      const std::size_t top = hi - std::min(kClaimRows, hi - lo);
      if (a.compare_exchange_weak(cur, pack(lo, top), std::memory_order_relaxed)) {
        limit = top;
        return true;
      }
    }
  }

  // A thread done with its own range: takes rows [first, end) from the
  // bottom of the largest range left, or returns false when none holds 2
  // kClaimRows rows. `victim` is whose block they were.
  bool take(int me, std::size_t& first, std::size_t& end, int& victim) {
    for (;;) {
      std::size_t best = size_, most = 0;
      std::uint64_t seen = 0;
      for (std::size_t k = 0; k < size_; ++k) {
        if (k == static_cast<std::size_t>(me)) continue;
        const std::uint64_t cur = range_[k].lo_hi.load(std::memory_order_relaxed);
        const std::size_t left = (cur & 0xFFFFFFFFu) - std::min(cur >> 32, cur & 0xFFFFFFFFu);
        if (left > most) best = k, most = left, seen = cur;
      }
      if (most < 2 * kClaimRows) return false;
      const std::size_t lo = seen >> 32, hi = seen & 0xFFFFFFFFu, cut = lo + most / 2;
      if (range_[best].lo_hi.compare_exchange_strong(seen, pack(cut, hi),
                                                     std::memory_order_relaxed)) {
        first = lo, end = cut, victim = static_cast<int>(best);
        taken_[static_cast<std::size_t>(me)].push_back({lo, cut});
        return true;
      }
    }
  }

  // After the pass: every block boundary (the split's, and the upper end of
  // each range taken), ascending.
  void boundaries(std::vector<std::size_t>& blocks) const {
    for (const auto& t : taken_)
      for (const auto& r : t) blocks.push_back(r.second);
    std::sort(blocks.begin(), blocks.end());
  }

  // Rows taken from other threads' blocks in the pass, over all threads.
  std::size_t rows_taken() const {
    std::size_t k = 0;
    for (const auto& t : taken_)
      for (const auto& r : t) k += r.second - r.first;
    return k;
  }

private:
  static std::uint64_t pack(std::size_t lo, std::size_t hi) {
    return static_cast<std::uint64_t>(lo) << 32 | static_cast<std::uint64_t>(hi);
  }
  struct alignas(64) Range {
    std::atomic<std::uint64_t> lo_hi{0}; // lowest unclaimed row << 32 | end of the unclaimed rows
  };
  std::unique_ptr<Range[]> range_;
  std::size_t size_ = 0;
  // Per thread: the rows [first, end) of each range it took.
  std::vector<std::vector<std::pair<std::size_t, std::size_t>>> taken_;
};

} // namespace centridem
