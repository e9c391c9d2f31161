#include "procedures/bench.hpp"

#include "base/errors.hpp"
#include "engine/world.hpp"
#include "io/particle_file.hpp"
#include "procedures/paper_material.hpp"

#include <chrono>
#include <filesystem>

namespace centridem {

BenchResult run_bench(const BenchOptions& o, int threads) {
  std::error_code ec; // a name too long for the system is "does not exist", not an exception
  if (!std::filesystem::is_regular_file(o.packing, ec))
    throw InputError("--packing", "\"" + o.packing + "\"",
                     "a particle file that exists (x y z r per line, SI)");
  const auto records = read_particle_file(o.packing);
  WorldSettings s;
  s.local_damping = paper::local_damping;
  s.timestep_s = o.timestep_s;
  s.threads = threads;
  World world(s);
  world.particles_mut().reserve(records.size());
  for (const auto& rec : records)
    world.add_particle(rec.position, rec.radius, paper::density_kg_m3);
  world.set_ball_ball_defaults(paper::ball_ball());
  const ContactProperties wall = paper::ball_wall();
  const double L = o.box_side_m;
  world.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), wall);
  world.add_wall(Wall::plane("x0", {0, 0, 0}, {1, 0, 0}), wall);
  world.add_wall(Wall::plane("x1", {L, 0, 0}, {-1, 0, 0}), wall);
  world.add_wall(Wall::plane("y0", {0, 0, 0}, {0, 1, 0}), wall);
  world.add_wall(Wall::plane("y1", {0, L, 0}, {0, -1, 0}), wall);
  world.set_body_field(BodyField::scaled_gravity(o.g_level, 1.0));
  world.cycle(o.warmup_steps);

  const long rebuilds_before = world.neighbour_rebuilds();
  const auto t0 = std::chrono::steady_clock::now();
  world.cycle(o.steps);
  const auto t1 = std::chrono::steady_clock::now();

  BenchResult r;
  r.threads = threads;
  r.particles = world.particles().size();
  r.steps = o.steps;
  r.wall_seconds = std::chrono::duration<double>(t1 - t0).count();
  const Measurements m = world.measure();
  r.contacts_per_particle = m.coordination_number;
  r.neighbours_per_particle =
      static_cast<double>(world.neighbour_entries()) / static_cast<double>(r.particles);
  r.bytes_per_particle = world.bytes_per_particle();
  r.rebuilds = world.neighbour_rebuilds() - rebuilds_before;
  r.particle_steps_per_s =
      static_cast<double>(r.particles) * static_cast<double>(o.steps) / r.wall_seconds;
  return r;
}

} // namespace centridem
