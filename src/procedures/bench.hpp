// The throughput benchmark (`centridem bench`, docs/results/bench.md) on the
// shared 30,000-sphere packing (../shared/bench), two contact laws and two
// workloads:
// - law `paper`: the paper's ARRLM material (Table 1: E*-based stiffness,
//   adhesion, local damping 0.7), as the slope and shear runs use it;
// - law `peers`: exactly what the peer codes run in bench/peers/ (kn = 5e4 N/m,
//   ks = kn / 1.5, mu = 0.5, rolling kr = ks R^2 limited at 0.16 R Fn, no
//   adhesion, the same law against the walls, no local damping; the peers'
//   mass-proportional dashpot as PFC dashpot ratios of the median grain), so
//   that a ratio of speeds compares the same law on the same contacts;
// - workload `packed`: the packing at rest under 600 g in its box;
// - workload `flowing`: its left half (x + r <= 6.3 mm) released against the
//   floor and the walls x = 0, y = 0 and y = 12.6 mm at 600 g: a collapsing
//   column where contacts are made and broken and the lists rebuilt often
//   (bench/peers/lammps_flow.in is the same case for LAMMPS).
#pragma once

#include <string>
#include <vector>

namespace centridem {

enum class BenchLaw { paper, peers };
enum class BenchWorkload { packed, flowing };

struct BenchOptions {
  std::string packing = "../shared/bench/packing_30k.xyzr";
  long steps = 5000;
  long warmup_steps = 200;
  double timestep_s = 1e-7;
  double g_level = 600.0;
  std::vector<int> threads{1, 2};
  double box_side_m = 0.0126; // walls at x, y = 0 and this value; floor at z = 0
  BenchLaw law = BenchLaw::paper;
  BenchWorkload workload = BenchWorkload::packed;
  double flow_cut_x_m = 6.3e-3; // flowing: the grains with x + r at most this [m]
  // Verlet skin [m] (`--skin`); 0 = the engine's default (half the smallest
  // radius, 62.5 um on the shared packing). The peers' inputs use 5e-5.
  double skin_m = 0.0;
};

struct BenchResult {
  int threads = 0;
  std::size_t particles = 0;
  long steps = 0;
  double wall_seconds = 0;
  double contacts_per_particle = 0;           // (2 ball-ball + ball-wall) / N, at the end
  double ball_ball_contacts_per_particle = 0; // 2 ball-ball / N (LAMMPS `contact/atom`)
  double neighbours_per_particle = 0;
  std::size_t bytes_per_particle = 0;
  long rebuilds = 0;
  double skin_m = 0; // the skin the run used [m]
  double particle_steps_per_s = 0;
  // Shares of the timed steps' wall time [-].
  double share_neighbour_search = 0, share_contact_pass = 0, share_integration = 0;
  // Of those, the threads' mean wait for the slowest at the end of each
  // contact pass and each integration (World::PhaseSeconds; 0 on 1 thread).
  double share_contact_pass_wait = 0, share_integration_wait = 0;
};

BenchResult run_bench(const BenchOptions& options, int threads);

std::string to_string(BenchLaw law);
std::string to_string(BenchWorkload workload);

} // namespace centridem
