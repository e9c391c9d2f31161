// Google Benchmark micro-benchmarks: the contact law alone, and whole steps
// of a small packing. The scenario benchmark is `centridem bench`.
#include "physics/contact_law.hpp"
#include "physics/lanes.hpp"
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

// The same law on a batch of ContactLanes::size contacts (8 with AVX-512): items are contacts.
static void BM_ContactLawLanes(benchmark::State& st) {
  using T = ContactLanes;
  using V = LaneVec<T>;
  const ContactProperties p = paper::ball_ball();
  ContactGeometryT<T> g{V{T(0.0), T(0.0), T(1.0)},
                        T(1e-6),
                        V{T(1e-4), T(2e-4), T(-1e-5)},
                        V{T(1.0), T(2.0), T(3.0)},
                        T(2e-4),
                        T(5e-4),
                        T(1e-4),
                        T(1e-8)};
  ContactStateT<T> s{};
  const Vec3 turned = Vec3{1e-3, 0, 1} / norm(Vec3{1e-3, 0, 1});
  for (auto _ : st) {
    ContactResultT<T> r = contact_law(p, g, s, 1e-7);
    benchmark::DoNotOptimize(r);
    g.normal = V{T(turned.x), T(turned.y), T(turned.z)};
  }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(T::size));
}
BENCHMARK(BM_ContactLawLanes);

BENCHMARK_MAIN();
