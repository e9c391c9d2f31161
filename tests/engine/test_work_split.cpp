// The threads' blocks of rows (engine/work_split.hpp): equal at first, then
// moved by the measured time of each block towards equal cost. The "clock"
// here is a known cost per row, so the place the blocks must settle at is
// known exactly: with rows 0-499 costing 3 units and rows 500-999 costing 1,
// two threads share the 2,000 units equally at row 333 (3 x 333.3 = 1,000).
// Which thread runs a row does not change the results (that is
// PhysicsThreads.OneTwoAndThreeThreadsAgreeBitForBit's job); this checks that
// the split goes where the work is.
#include "engine/work_split.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <functional>

using namespace centridem;

namespace {

// One pass: each thread's block timed with the given cost per row.
void timed_pass(WorkSplit& s, int team, std::size_t n,
                const std::function<double(std::size_t)>& cost) {
  for (int me = 0; me < team; ++me) {
    const auto [first, last] = s.block(me, team, n);
    double t = 0.0;
    for (std::size_t i = first; i < last; ++i) t += cost(i);
    s.record(me, t);
  }
  s.rebalance();
}

double step_cost(std::size_t i) {
  return i < 500 ? 3.0 : 1.0;
}

} // namespace

TEST(WorkSplit, StartsEqualAndFallsBackToEqualBlocksForAnotherTeamOrSize) {
  WorkSplit s;
  // Not prepared: equal blocks.
  EXPECT_EQ(s.block(0, 2, 1000), (std::pair<std::size_t, std::size_t>{0, 500}));
  EXPECT_EQ(s.block(1, 2, 1000), (std::pair<std::size_t, std::size_t>{500, 1000}));
  s.prepare(2, 1000);
  for (int k = 0; k < 50; ++k) timed_pass(s, 2, 1000, step_cost);
  EXPECT_LT(s.block(0, 2, 1000).second, 400u); // moved
  // Another team or another number of rows: equal blocks, not the moved ones.
  EXPECT_EQ(s.block(1, 3, 1000), (std::pair<std::size_t, std::size_t>{333, 666}));
  EXPECT_EQ(s.block(0, 2, 999), (std::pair<std::size_t, std::size_t>{0, 499}));
  // Preparing for the same team and size keeps the moved split; another resets it.
  s.prepare(2, 1000);
  EXPECT_LT(s.block(0, 2, 1000).second, 400u);
  s.prepare(2, 1200);
  EXPECT_EQ(s.block(0, 2, 1200), (std::pair<std::size_t, std::size_t>{0, 600}));
}

TEST(WorkSplit, TwoThreadsSettleWhereTheCostIsSharedEqually) {
  WorkSplit s;
  s.prepare(2, 1000);
  // An eighth of the way per pass: the first pass moves from 500 towards the
  // target its own estimate gives (block 0's 1,500 units spread evenly: the
  // half of 2,000 at row 333.3), to 500 - 166.7 / 8 = 479.
  timed_pass(s, 2, 1000, step_cost);
  EXPECT_EQ(s.block(0, 2, 1000).second, 479u);
  for (int k = 0; k < 200; ++k) timed_pass(s, 2, 1000, step_cost);
  const std::size_t b = s.block(0, 2, 1000).second;
  EXPECT_NEAR(static_cast<double>(b), 333.3, 8.0); // within 1 % of the equal-cost row
  // The blocks cover every row once.
  EXPECT_EQ(s.block(0, 2, 1000).first, 0u);
  EXPECT_EQ(s.block(1, 2, 1000).first, b);
  EXPECT_EQ(s.block(1, 2, 1000).second, 1000u);
}

TEST(WorkSplit, ThreeThreadsOnARampStayOrderedAndShareTheCost) {
  // Cost growing along the rows (row i costs i + 1): the equal-cost
  // boundaries lie where (i + 1)^2 / 2 reaches a third and two thirds of
  // n^2 / 2, at n / sqrt(3) and n sqrt(2/3).
  const std::size_t n = 3000;
  const auto ramp = [](std::size_t i) { return static_cast<double>(i + 1); };
  WorkSplit s;
  s.prepare(3, n);
  for (int k = 0; k < 300; ++k) timed_pass(s, 3, n, ramp);
  const std::size_t b1 = s.block(1, 3, n).first, b2 = s.block(2, 3, n).first;
  EXPECT_EQ(s.block(0, 3, n).second, b1);
  EXPECT_EQ(s.block(1, 3, n).second, b2);
  EXPECT_LT(b1, b2);
  EXPECT_NEAR(static_cast<double>(b1), 3000.0 / std::sqrt(3.0), 30.0);       // 1732
  EXPECT_NEAR(static_cast<double>(b2), 3000.0 * std::sqrt(2.0 / 3.0), 30.0); // 2449
}

TEST(WorkSplit, AnUntimedBlockLeavesTheSplitAlone) {
  WorkSplit s;
  s.prepare(2, 1000);
  s.record(0, 1.0); // thread 1 not timed (a pass on fewer threads than asked)
  s.rebalance();
  EXPECT_EQ(s.block(0, 2, 1000).second, 500u);
}

TEST(WorkSplit, TheWaitAtAPassEndIsTheSlowestBlockLessTheMean) {
  WorkSplit s;
  s.prepare(2, 1000);
  EXPECT_EQ(s.waited_seconds(), 0.0);
  // Equal blocks: 1,500 and 500 units, so the faster thread waits 1,000 and
  // the team, on the mean, 500 = 1,500 - 2,000 / 2.
  timed_pass(s, 2, 1000, step_cost);
  EXPECT_DOUBLE_EQ(s.waited_seconds(), 500.0);
  // Then blocks [0, 479) and [479, 1000): 1,437 and 563 units, 437 more.
  timed_pass(s, 2, 1000, step_cost);
  EXPECT_DOUBLE_EQ(s.waited_seconds(), 937.0);
  // Settled within 8 rows of the equal-cost row, a pass waits at most 3 x 8
  // units of the mean block's 1,000.
  for (int k = 0; k < 200; ++k) timed_pass(s, 2, 1000, step_cost);
  const double before = s.waited_seconds();
  timed_pass(s, 2, 1000, step_cost);
  EXPECT_LE(s.waited_seconds() - before, 24.0);
  // Three threads timed 3, 1 and 2: the slowest 3 less the mean 2.
  WorkSplit t;
  t.prepare(3, 30);
  t.record(0, 3.0), t.record(1, 1.0), t.record(2, 2.0);
  t.rebalance();
  EXPECT_DOUBLE_EQ(t.waited_seconds(), 1.0);
  // A pass with a block not timed adds nothing; nor does one thread.
  t.record(1, 0.0);
  t.rebalance();
  EXPECT_DOUBLE_EQ(t.waited_seconds(), 1.0);
  WorkSplit one;
  one.prepare(1, 30);
  one.record(0, 5.0);
  one.rebalance();
  EXPECT_EQ(one.waited_seconds(), 0.0);
}
