// Acceptance 9: the result may not depend on the number of threads beyond
// round-off (DESIGN.md "Hot loop"). Same 2,000-particle packing falling in a
// box under gravity with adhesive, frictional contacts (the paper's
// material), 1,000 steps with 1 thread and with 2 threads: positions agree
// per particle id within 1e-9 relative to the box size; contact counts and
// wall forces agree too. Neighbour rebuilds (re-sorting) must happen.
#include "physics_test_util.hpp"
#include "procedures/paper_material.hpp"

#include <gtest/gtest.h>

#include <map>

namespace centridem {
namespace {
using namespace phys_test;

struct RunResult {
  std::map<std::int64_t, Vec3> position;
  long rebuilds = 0;
  std::size_t bb_contacts = 0, bw_contacts = 0;
  Vec3 floor_force;
  double time = 0;
};

constexpr double r = 0.5e-3, spacing = 1.06e-3, L = 20 * spacing + 0.2e-3;

RunResult run(int threads) {
  WorldSettings s;
  s.threads = threads;
  s.neighbour_skin_m = 0.05e-3;
  s.local_damping = paper::local_damping;
  World w(s);
  w.set_ball_ball_defaults(paper::ball_ball());
  const ContactProperties wall = paper::ball_wall(0.3);
  w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), wall);
  w.add_wall(Wall::plane("x0", {0, 0, 0}, {1, 0, 0}), wall);
  w.add_wall(Wall::plane("x1", {L, 0, 0}, {-1, 0, 0}), wall);
  w.add_wall(Wall::plane("y0", {0, 0, 0}, {0, 1, 0}), wall);
  w.add_wall(Wall::plane("y1", {0, L, 0}, {0, -1, 0}), wall);
  // 20 x 20 x 5 lattice, spacing 1.06 mm, radii 0.45-0.525 mm: 2,000
  // balls with gaps of 0.01-0.16 mm, random velocities up to 0.3 m/s and
  // 1000 g: collisions (and contacts with the floor and the walls) start
  // within a few hundred steps. A small skin forces frequent rebuilds.
  add_lattice(w, 2000, 20, 20, spacing, 0.9 * r, 1.05 * r, paper::density_kg_m3,
              {0.6e-3, 0.6e-3, 0.54e-3}, 0.3, false);
  w.set_body_field(BodyField::scaled_gravity(1000.0, 1.0));
  w.cycle(1000);
  RunResult out;
  const auto& P = w.particles();
  for (std::size_t i = 0; i < P.size(); ++i) out.position[P.id[i]] = P.position[i];
  out.rebuilds = w.neighbour_rebuilds();
  out.time = w.time();
  const Measurements m = w.measure();
  out.bb_contacts = m.ball_ball_contacts;
  out.bw_contacts = m.ball_wall_contacts;
  out.floor_force = w.walls()[w.wall_index("floor")].force;
  return out;
}

TEST(PhysicsThreads, OneAndTwoThreadsAgree) {
  const RunResult a = run(1), b = run(2);
  ASSERT_EQ(a.position.size(), 2000u);
  ASSERT_EQ(b.position.size(), 2000u);
  double worst = 0;
  for (const auto& [id, x] : a.position) {
    const auto it = b.position.find(id);
    ASSERT_NE(it, b.position.end()) << "id " << id;
    worst = std::max(worst, norm(x - it->second) / L);
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(a.time, b.time, 1e-9 * a.time) << "automatic timestep differs";
  EXPECT_EQ(a.bb_contacts, b.bb_contacts);
  EXPECT_EQ(a.bw_contacts, b.bw_contacts);
  EXPECT_LT(norm(a.floor_force - b.floor_force), 1e-9 * norm(a.floor_force));
  // Not vacuous: contacts active, re-sorting happened.
  EXPECT_GT(a.rebuilds, 2);
  EXPECT_GT(a.bb_contacts, 1000u);
  EXPECT_GT(a.bw_contacts, 100u);
}

} // namespace
} // namespace centridem
