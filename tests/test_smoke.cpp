#include "engine/world.hpp"

#include <gtest/gtest.h>

TEST(Smoke, EmptyWorldCycles) {
  centridem::World w;
  w.cycle(3);
  EXPECT_EQ(w.step_count(), 3);
}
