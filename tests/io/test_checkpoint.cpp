// Checkpoints: a run split by a checkpoint and resumed in a new World is
// identical bit for bit to the same run in one go; corrupt files are refused.
#include "base/errors.hpp"
#include "engine/world.hpp"
#include "io/checkpoint.hpp"
#include "procedures/paper_material.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <random>

using namespace centridem;

namespace {

World make_column() {
  WorldSettings s;
  s.local_damping = 0.7;
  World w(s);
  w.set_ball_ball_defaults(paper::ball_ball());
  const double L = 0.0043; // 9 lattice columns of 0.46 mm fit inside
  w.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), paper::ball_wall(0.2));
  w.add_wall(Wall::rectangle("x0", {0, L / 2, L}, {1, 0, 0}, {0, 1, 0}, L, 2 * L),
             paper::ball_wall());
  w.add_wall(Wall::rectangle("x1", {L, L / 2, L}, {-1, 0, 0}, {0, 1, 0}, L, 2 * L),
             paper::ball_wall());
  w.add_wall(Wall::plane("y0", {0, 0, 0}, {0, 1, 0}), paper::ball_wall());
  w.add_wall(Wall::plane("y1", {0, L, 0}, {0, -1, 0}), paper::ball_wall());
  w.set_body_field(BodyField::scaled_gravity(1000, 1.0));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> rr(1.9e-4, 2.2e-4), jit(-1e-5, 1e-5);
  const double a = 4.6e-4; // a loose lattice that falls onto the floor and packs
  for (int iz = 0; iz < 14; ++iz)
    for (int iy = 0; iy < 9; ++iy)
      for (int ix = 0; ix < 9; ++ix)
        w.add_particle({(ix + 0.6) * a + jit(rng), (iy + 0.6) * a + jit(rng), (iz + 0.6) * a},
                       rr(rng), paper::density_kg_m3);
  return w;
}

void expect_identical(const World& a, const World& b) {
  const auto& pa = a.particles();
  const auto& pb = b.particles();
  ASSERT_EQ(pa.size(), pb.size());
  for (std::size_t i = 0; i < pa.size(); ++i) {
    ASSERT_EQ(pa.id[i], pb.id[i]);
    ASSERT_EQ(pa.position[i], pb.position[i]) << "particle id " << pa.id[i];
    ASSERT_EQ(pa.velocity[i], pb.velocity[i]) << "particle id " << pa.id[i];
    ASSERT_EQ(pa.spin[i], pb.spin[i]) << "particle id " << pa.id[i];
  }
  const auto ca = a.ball_ball_contacts(), cb = b.ball_ball_contacts();
  ASSERT_EQ(ca.size(), cb.size());
  for (std::size_t k = 0; k < ca.size(); ++k) ASSERT_EQ(ca[k].force_on_j, cb[k].force_on_j);
  EXPECT_EQ(a.step_count(), b.step_count());
  EXPECT_EQ(a.time(), b.time());
}

} // namespace

TEST(Checkpoint, ResumeIsBitForBit) {
  const auto dir = std::filesystem::temp_directory_path() / "centridem_ckpt_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "a.ckpt").string();
  const long N = 1500;

  World a = make_column();
  a.cycle(2 * N); // A: 2N steps in one go, no checkpoint

  World w = make_column();
  w.cycle(N);
  ASSERT_FALSE(w.rebuild_pending()); // the checkpoint falls between rebuilds
  write_checkpoint(w, path, "procedure-progress");
  World b;
  const LoadedCheckpoint info = read_checkpoint(b, path);
  EXPECT_EQ(info.procedure_state, "procedure-progress");
  b.cycle(N);                                      // B: N steps, checkpoint, N steps after it
  ASSERT_GT(a.measure().ball_ball_contacts, 300u); // history matters
  ASSERT_GT(a.neighbour_rebuilds(), 2);            // lists rebuilt after the resume, too
  expect_identical(a, b);
  // Writing a checkpoint does not perturb the World that wrote it.
  w.cycle(N);
  expect_identical(a, w);
}

// After particles are removed (the excavation of a slope), the lists are
// rebuilt from the kept particles only: a checkpoint taken later resumes bit
// for bit even when the smallest and the largest particle (which set the
// skin and the cell size) were among the removed.
TEST(Checkpoint, ResumeAfterRemovingTheExtremeParticlesIsBitForBit) {
  const auto dir = std::filesystem::temp_directory_path() / "centridem_ckpt_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "removed.ckpt").string();
  const long N = 800;
  auto run_to_removal = [&] {
    World w = make_column();
    // A large and a small grain on top: they set the cell size and the skin
    // until they are removed.
    w.add_particle({1.2e-3, 2.1e-3, 7.5e-3}, 3.2e-4, paper::density_kg_m3);
    w.add_particle({3.0e-3, 2.1e-3, 7.5e-3}, 1.0e-4, paper::density_kg_m3);
    w.cycle(N);
    const auto& r = w.particles().radius;
    const auto [small, large] = std::minmax_element(r.begin(), r.end());
    const std::size_t smallest = static_cast<std::size_t>(small - r.begin());
    const std::size_t largest = static_cast<std::size_t>(large - r.begin());
    const double top = 0.6 * 4.6e-4 * 14 * 0.8;
    w.remove_particles([&](std::size_t i) {
      return i == smallest || i == largest || w.particles().position[i].z > top;
    });
    return w;
  };
  World a = run_to_removal();
  a.cycle(2 * N);

  // The checkpoint right after the removal, before any later rebuild.
  World w = run_to_removal();
  w.cycle(1);
  ASSERT_FALSE(w.rebuild_pending());
  write_checkpoint(w, path);
  World b;
  read_checkpoint(b, path);
  b.cycle(2 * N - 1);
  expect_identical(a, b);
}

TEST(Checkpoint, CorruptOrTruncatedFileIsRefused) {
  const auto dir = std::filesystem::temp_directory_path() / "centridem_ckpt_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "b.ckpt").string();
  World a = make_column();
  a.cycle(50);
  write_checkpoint(a, path);
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  {
    std::string flipped = bytes;
    flipped[flipped.size() / 2] ^= 0x10;
    std::ofstream(path, std::ios::binary) << flipped;
    World b;
    try {
      read_checkpoint(b, path);
      FAIL() << "a flipped byte was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
    }
  }
  {
    std::ofstream(path, std::ios::binary) << bytes.substr(0, bytes.size() - 7);
    World b;
    try {
      read_checkpoint(b, path);
      FAIL() << "a truncated file was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    }
  }
}
