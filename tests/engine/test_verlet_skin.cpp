// The automatic Verlet skin (engine/verlet_skin.hpp): the skin the motion
// uses up in about 100 steps, between 1/32 and 1/2 of the smallest radius.
// A gas of 512 spheres in a box of walls, colliding (contacts made and
// broken all the time), fixed timestep, no gravity:
// - slow (0.5 m/s at most per axis): the lists thin to well below the
//   largest skin; fast (5 m/s): they keep the largest;
// - at every step the contacts the World finds are exactly the touching
//   pairs, counted by brute force: a skin used up before its rebuild would
//   miss the pairs that closed it;
// - a checkpoint taken with a thinned skin, between rebuilds and with a
//   rebuild pending, resumes bit for bit.
#include "engine/world.hpp"
#include "io/checkpoint.hpp"
#include "physics/physics_test_util.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <gtest/gtest.h>

using namespace centridem;

namespace {

constexpr double kRmin = 0.95e-3, kRmax = 1.0e-3; // radii [m]
constexpr double kSpacing = 2.15e-3;              // lattice: gaps of 0.15-0.25 mm [m]

World make_gas(double speed_m_per_s) {
  WorldSettings s;
  s.timestep_s = 1e-6; // critical about 1e-5 s for kn below
  World w(s);
  ContactProperties p;
  p.model = ContactModel::linear;
  p.stiffness_method = StiffnessMethod::direct;
  p.normal_stiffness_N_per_m = 1e5;
  p.shear_stiffness_N_per_m = 1e5;
  p.friction = 0.3;
  w.set_ball_ball_defaults(p);
  const double L = 8 * kSpacing;
  w.add_wall(Wall::plane("x0", {0, 0, 0}, {1, 0, 0}), p);
  w.add_wall(Wall::plane("x1", {L, 0, 0}, {-1, 0, 0}), p);
  w.add_wall(Wall::plane("y0", {0, 0, 0}, {0, 1, 0}), p);
  w.add_wall(Wall::plane("y1", {0, L, 0}, {0, -1, 0}), p);
  w.add_wall(Wall::plane("z0", {0, 0, 0}, {0, 0, 1}), p);
  w.add_wall(Wall::plane("z1", {0, 0, L}, {0, 0, -1}), p);
  const double o = 0.5 * kSpacing;
  phys_test::add_lattice(w, 512, 8, 8, kSpacing, kRmin, kRmax, 2600.0, {o, o, o}, speed_m_per_s,
                         true);
  return w;
}

// Touching pairs (overlap r_i + r_j - |d| > 0, the linear law's test) by brute force.
std::size_t touching_pairs(const ParticleStore& P) {
  std::size_t count = 0;
  for (std::size_t i = 0; i < P.size(); ++i)
    for (std::size_t j = i + 1; j < P.size(); ++j)
      count += P.radius[i] + P.radius[j] - std::sqrt(norm2(P.position[j] - P.position[i])) > 0.0;
  return count;
}

struct GasRun {
  std::size_t mismatched_steps = 0, contacts_seen = 0;
  long rebuilds = 0;
  double skin_m = 0, largest_skin_m = 0; // the lists' skin; half the smallest radius [m]
};

// Steps the gas one step at a time; at each step the World's ball-ball
// contacts (found by the contact pass at the positions before the step)
// against brute force at those positions.
GasRun run_gas(double speed_m_per_s, long steps) {
  World w = make_gas(speed_m_per_s);
  GasRun out;
  for (long k = 0; k < steps; ++k) {
    const std::size_t expected = touching_pairs(w.particles());
    w.cycle(1);
    const std::size_t found = w.measure().ball_ball_contacts;
    out.mismatched_steps += found != expected;
    out.contacts_seen += found;
  }
  out.rebuilds = w.neighbour_rebuilds();
  out.skin_m = w.neighbour_skin_m();
  const auto& r = w.particles().radius;
  out.largest_skin_m = 0.5 * *std::min_element(r.begin(), r.end());
  return out;
}

} // namespace

TEST(VerletSkin, ThinsForSlowMotionAndTheListsMissNoContact) {
  const GasRun slow = run_gas(0.5, 2000);
  EXPECT_EQ(slow.mismatched_steps, 0u);
  EXPECT_GT(slow.contacts_seen, 2000u); // collisions all along
  EXPECT_GT(slow.rebuilds, 10);         // lists used up and rebuilt, many times
  // At most 0.87 m/s a particle: twice 0.87 um per step, x 100 steps = 0.17 mm.
  EXPECT_LT(slow.skin_m, 0.5 * slow.largest_skin_m);
  EXPECT_GE(slow.skin_m, slow.largest_skin_m / 16.0);
}

TEST(VerletSkin, FastMotionKeepsTheLargestSkin) {
  const GasRun fast = run_gas(5.0, 600);
  EXPECT_EQ(fast.mismatched_steps, 0u);
  EXPECT_GT(fast.contacts_seen, 500u);
  EXPECT_GT(fast.rebuilds, 10);
  EXPECT_EQ(fast.skin_m, fast.largest_skin_m);
}

TEST(VerletSkin, ResumeWithAThinnedSkinIsBitForBit) {
  const auto dir = std::filesystem::temp_directory_path() / "centridem_skin_test";
  std::filesystem::create_directories(dir);
  // The gas thins its skin over N steps, then is sped up four times: the
  // next rebuild chooses a much thicker skin than the lists have, so a
  // checkpoint with that rebuild pending must carry the choice.
  const long N = 1200, total = 2500;
  auto thinned_then_sped_up = [&] {
    World w = make_gas(0.5);
    w.cycle(N);
    for (Vec3& v : w.particles_mut().velocity) v = 4.0 * v; // no rebuild needed
    return w;
  };
  World a = thinned_then_sped_up();
  a.cycle(total - N);

  for (const bool pending : {false, true}) {
    SCOPED_TRACE(pending ? "checkpoint with a rebuild pending" : "checkpoint between rebuilds");
    World w = thinned_then_sped_up();
    long done = N;
    while (w.rebuild_pending() != pending) w.cycle(1), ++done;
    ASSERT_LT(w.neighbour_skin_m(), 0.5 * 0.5 * kRmin); // the lists' skin is a thinned one
    const std::string path = (dir / (pending ? "pending.ckpt" : "built.ckpt")).string();
    write_checkpoint(w, path);
    World b;
    read_checkpoint(b, path);
    b.cycle(total - done);
    const auto& pa = a.particles();
    const auto& pb = b.particles();
    ASSERT_EQ(pa.size(), pb.size());
    std::size_t differing = 0;
    for (std::size_t i = 0; i < pa.size(); ++i)
      differing += pa.id[i] != pb.id[i] || !(pa.position[i] == pb.position[i]) ||
                   !(pa.velocity[i] == pb.velocity[i]) || !(pa.spin[i] == pb.spin[i]);
    EXPECT_EQ(differing, 0u);
    EXPECT_EQ(a.neighbour_skin_m(), b.neighbour_skin_m());
    EXPECT_EQ(a.step_count(), b.step_count());
  }
}
