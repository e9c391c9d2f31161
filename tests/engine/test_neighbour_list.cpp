// The neighbour list against brute force: after a rebuild it holds exactly
// the pairs whose centres are closer than r_i + r_j + skin, once each. The
// rebuild sweeps the cells with a SIMD distance test over a cell's particles
// several at a time (engine/neighbour_search.cpp); a lost lane, a lane read
// past the end of a cell, or a pair kept twice changes the count. 4,000
// spheres with radii spread by 4x (so cells hold different numbers of them,
// and most cells end in a partial batch), in a closed box and with two
// periodic axes (pairs found through the boundary, at their image).
#include "engine/world.hpp"

#include <gtest/gtest.h>
#include <memory>
#include <random>

using namespace centridem;

namespace {
constexpr double kSkin = 0.05e-3; // [m]
constexpr double kBox = 8e-3;     // cube side [m]

struct Sphere {
  Vec3 x;
  double r;
};

std::vector<Sphere> random_spheres(unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> pos(0.6e-3, kBox - 0.6e-3), rad(0.125e-3, 0.5e-3);
  std::vector<Sphere> s(4000);
  for (Sphere& p : s) p = {{pos(rng), pos(rng), pos(rng)}, rad(rng)};
  return s;
}

// Pairs i < j with some image of j within r_i + r_j + skin of i, by brute
// force: the test the rebuild makes, norm2(x_j + shift - x_i) < reach^2.
std::size_t brute_force_pairs(const std::vector<Sphere>& s, const PeriodicBox& pb) {
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    for (std::size_t j = i + 1; j < s.size(); ++j) {
      const double reach = s[i].r + s[j].r + kSkin;
      bool near = false;
      const int ax = pb.axis[0] ? 1 : 0, ay = pb.axis[1] ? 1 : 0, az = pb.axis[2] ? 1 : 0;
      const Vec3 L = pb.hi - pb.lo;
      for (int a = -ax; a <= ax; ++a)
        for (int b = -ay; b <= ay; ++b)
          for (int c = -az; c <= az; ++c) {
            const Vec3 shift{a * L.x, b * L.y, c * L.z};
            near = near || norm2(s[j].x + shift - s[i].x) < reach * reach;
          }
      pairs += near ? 1 : 0;
    }
  }
  return pairs;
}

std::size_t listed_pairs(const std::vector<Sphere>& s, const PeriodicBox& pb) {
  WorldSettings settings;
  settings.neighbour_skin_m = kSkin;
  World w(settings);
  ContactProperties p;
  p.model = ContactModel::rrlinear;
  p.effective_modulus_Pa = 1e8;
  w.set_ball_ball_defaults(p);
  if (pb.any()) w.set_periodic(pb);
  for (const Sphere& q : s) w.add_particle(q.x, q.r, 2600.0);
  w.cycle(0); // builds the lists, moves nothing
  return w.neighbour_entries();
}
} // namespace

TEST(NeighbourList, HoldsExactlyThePairsWithinReachInABox) {
  const auto s = random_spheres(7);
  const std::size_t expected = brute_force_pairs(s, PeriodicBox{});
  ASSERT_GT(expected, 10'000u); // a dense enough set to fill every batch width
  EXPECT_EQ(listed_pairs(s, PeriodicBox{}), expected);
}

TEST(NeighbourList, HoldsExactlyThePairsWithinReachThroughPeriodicBoundaries) {
  PeriodicBox pb;
  pb.axis = {true, true, false};
  pb.lo = {0, 0, 0};
  pb.hi = {kBox, kBox, kBox};
  auto s = random_spheres(11);
  // Some spheres right at the periodic faces, so that pairs cross them.
  for (std::size_t k = 0; k < s.size(); k += 10)
    s[k].x.x = (k % 20 == 0) ? 0.05e-3 : kBox - 0.05e-3;
  const std::size_t expected = brute_force_pairs(s, pb);
  ASSERT_GT(expected, brute_force_pairs(s, PeriodicBox{})); // pairs through the boundary exist
  EXPECT_EQ(listed_pairs(s, pb), expected);
}

// The rebuild reuses the old lists' storage. Lists that grow or shrink from
// rebuild to rebuild must not keep more than a little spare: built up by
// adding spheres 200 at a time (the lists grow at each rebuild), then cut
// down by removing half of them, the engine holds at most 10 % more bytes
// per particle than a World given the same spheres at once. (When the
// storage grew as `resize` grows it, by doubling, the grown World held 1.3
// to 1.6 times as much.)
TEST(NeighbourList, StorageFollowsTheListsAcrossRebuilds) {
  const auto s = random_spheres(5);
  auto world = [] {
    WorldSettings settings;
    settings.neighbour_skin_m = kSkin;
    auto w = std::make_unique<World>(settings);
    ContactProperties p;
    p.model = ContactModel::rrlinear;
    p.effective_modulus_Pa = 1e8;
    w->set_ball_ball_defaults(p);
    return w;
  };
  auto fresh_bytes = [&](std::size_t count) {
    auto w = world();
    for (std::size_t k = 0; k < count; ++k) w->add_particle(s[k].x, s[k].r, 2600.0);
    w->cycle(0);
    return static_cast<double>(w->bytes_per_particle());
  };
  auto grown = world();
  for (std::size_t k = 0; k < s.size(); ++k) {
    grown->add_particle(s[k].x, s[k].r, 2600.0);
    if ((k + 1) % 200 == 0) grown->cycle(0); // a rebuild with more entries
  }
  EXPECT_LE(static_cast<double>(grown->bytes_per_particle()), 1.10 * fresh_bytes(s.size()));
  // Half the spheres removed (the second half in the order they were added).
  grown->remove_particles([&](std::size_t i) { return grown->particles().id[i] > 2000; });
  grown->cycle(0);
  ASSERT_EQ(grown->particles().size(), 2000u);
  EXPECT_LE(static_cast<double>(grown->bytes_per_particle()), 1.10 * fresh_bytes(2000));
}
