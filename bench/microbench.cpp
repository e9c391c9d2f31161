// Google Benchmark micro-benchmarks: the contact law alone, and whole steps
// of a small packing. The scenario benchmark is `centridem bench`.
#include "physics/contact_law.hpp"
#include "procedures/paper_material.hpp"

#include <benchmark/benchmark.h>

using namespace centridem;

static void BM_ContactLaw(benchmark::State& st) {
  const ContactProperties p = paper::ball_ball();
  ContactGeometry g{{0, 0, 1}, 1e-6, {1e-4, 2e-4, -1e-5}, {1, 2, 3}, 2e-4, 5e-4, 1e-4, 1e-8};
  ContactState s{};
  for (auto _ : st) {
    ContactResult r = contact_law(p, g, s, 1e-7);
    benchmark::DoNotOptimize(r);
    g.normal = Vec3{1e-3, 0, 1} / norm(Vec3{1e-3, 0, 1});
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_ContactLaw);

BENCHMARK_MAIN();
