// The throughput benchmark (`centridem bench`): the shared 30,000-sphere
// packing under 600 g with the paper's contact properties at a fixed timestep.
#pragma once

#include <string>
#include <vector>

namespace centridem {

struct BenchOptions {
  std::string packing = "../shared/bench/packing_30k.xyzr";
  long steps = 5000;
  long warmup_steps = 200;
  double timestep_s = 1e-7;
  double g_level = 600.0;
  std::vector<int> threads{1, 2};
  double box_side_m = 0.0126; // walls at x, y = 0 and this value; floor at z = 0
};

struct BenchResult {
  int threads = 0;
  std::size_t particles = 0;
  long steps = 0;
  double wall_seconds = 0;
  double contacts_per_particle = 0;
  double neighbours_per_particle = 0;
  std::size_t bytes_per_particle = 0;
  long rebuilds = 0;
  double particle_steps_per_s = 0;
};

BenchResult run_bench(const BenchOptions& options, int threads);

} // namespace centridem
