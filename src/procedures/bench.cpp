#include "procedures/bench.hpp"

#include "base/errors.hpp"
#include "engine/world.hpp"
#include "io/particle_file.hpp"
#include "procedures/paper_material.hpp"

#include <chrono>
#include <filesystem>

namespace centridem {

namespace {

// The peer codes' law (bench/peers/lammps_granular.in, liggghts_rolling.in):
// Hooke kn = 5e4 N/m, kt = kn / 1.5, Coulomb mu = 0.5, rolling spring ks R^2
// with limit 0.16 R Fn (PFC rrlinear, LAMMPS `rolling sds`), no adhesion. The
// peers damp with a mass-proportional dashpot (LAMMPS `damping mass_velocity`,
// eta_n = 1.4e5 1/s: c_n = eta_n m_eff; tangential 0.5 of it); PFC's dashpot is
// a ratio of critical, beta = c / (2 sqrt(m_eff k)), which for the median grain
// (d = 0.53 mm, 2633 kg/m^3: m_eff = 1.03e-7 kg) is beta_n = 0.10 and
// beta_s = 0.5 c_n / (2 sqrt(m_eff kt)) = 0.06. Same cost per contact, not the
// same damping for every size (stated in docs/results/bench.md).
ContactProperties peers_law() {
  ContactProperties p;
  p.model = ContactModel::rrlinear;
  p.stiffness_method = StiffnessMethod::direct;
  p.normal_stiffness_N_per_m = 5e4;
  p.shear_stiffness_N_per_m = 5e4 / 1.5;
  p.friction = 0.5;
  p.rolling_friction = 0.16;
  p.dashpot_normal_ratio = 0.10;
  p.dashpot_shear_ratio = 0.06;
  return p;
}

} // namespace

std::string to_string(BenchLaw law) {
  return law == BenchLaw::paper ? "paper" : "peers";
}
std::string to_string(BenchWorkload w) {
  return w == BenchWorkload::packed ? "packed" : "flowing";
}

BenchResult run_bench(const BenchOptions& o, int threads) {
  std::error_code ec; // a name too long for the system is "does not exist", not an exception
  if (!std::filesystem::is_regular_file(o.packing, ec))
    throw InputError("--packing", "\"" + o.packing + "\"",
                     "a particle file that exists (x y z r per line, SI)");
  const auto records = read_particle_file(o.packing);
  const bool peers = o.law == BenchLaw::peers;
  const bool flowing = o.workload == BenchWorkload::flowing;
  WorldSettings s;
  // The peers run without local damping; so does the flowing column, whose
  // grains must be free to fall (the dashpot dissipates at the contacts).
  s.local_damping = peers || flowing ? 0.0 : paper::local_damping;
  s.timestep_s = o.timestep_s;
  s.neighbour_skin_m = o.skin_m;
  s.threads = threads;
  World world(s);
  world.particles_mut().reserve(records.size());
  for (const auto& rec : records)
    if (!flowing || rec.position.x + rec.radius <= o.flow_cut_x_m)
      world.add_particle(rec.position, rec.radius, paper::density_kg_m3);
  if (world.particles().size() == 0)
    throw InputError("--packing", "\"" + o.packing + "\"",
                     "a packing with grains at x + r <= 6.3 mm for the flowing workload");
  ContactProperties ball_ball = peers ? peers_law() : paper::ball_ball();
  if (flowing && !peers) ball_ball.dashpot_normal_ratio = 0.10; // the same dashpot as the peers
  world.set_ball_ball_defaults(ball_ball);
  const ContactProperties wall = peers ? peers_law() : paper::ball_wall();
  const double L = o.box_side_m;
  world.add_wall(Wall::plane("floor", {0, 0, 0}, {0, 0, 1}), wall);
  world.add_wall(Wall::plane("x0", {0, 0, 0}, {1, 0, 0}), wall);
  if (!flowing) world.add_wall(Wall::plane("x1", {L, 0, 0}, {-1, 0, 0}), wall);
  world.add_wall(Wall::plane("y0", {0, 0, 0}, {0, 1, 0}), wall);
  world.add_wall(Wall::plane("y1", {0, L, 0}, {0, -1, 0}), wall);
  world.set_body_field(BodyField::scaled_gravity(o.g_level, 1.0));
  world.cycle(o.warmup_steps);

  const long rebuilds_before = world.neighbour_rebuilds();
  const World::PhaseSeconds before = world.phase_seconds();
  const auto t0 = std::chrono::steady_clock::now();
  world.cycle(o.steps);
  const auto t1 = std::chrono::steady_clock::now();
  const World::PhaseSeconds after = world.phase_seconds();

  BenchResult r;
  r.threads = threads;
  r.particles = world.particles().size();
  r.steps = o.steps;
  r.wall_seconds = std::chrono::duration<double>(t1 - t0).count();
  const Measurements m = world.measure();
  r.contacts_per_particle = m.coordination_number;
  r.ball_ball_contacts_per_particle =
      2.0 * static_cast<double>(m.ball_ball_contacts) / static_cast<double>(r.particles);
  r.neighbours_per_particle =
      static_cast<double>(world.neighbour_entries()) / static_cast<double>(r.particles);
  r.bytes_per_particle = world.bytes_per_particle();
  r.rebuilds = world.neighbour_rebuilds() - rebuilds_before;
  r.skin_m = world.skin();
  r.particle_steps_per_s =
      static_cast<double>(r.particles) * static_cast<double>(o.steps) / r.wall_seconds;
  if (r.wall_seconds > 0) {
    // A phase clock's time over the timed steps, as a share of their wall time.
    const auto share = [&](double World::PhaseSeconds::*clock) {
      return (after.*clock - before.*clock) / r.wall_seconds;
    };
    r.share_neighbour_search = share(&World::PhaseSeconds::neighbour_search);
    r.share_contact_pass = share(&World::PhaseSeconds::contact_pass);
    r.share_integration = share(&World::PhaseSeconds::integration);
    r.share_contact_pass_wait = share(&World::PhaseSeconds::contact_pass_wait);
    r.share_integration_wait = share(&World::PhaseSeconds::integration_wait);
  }
  return r;
}

} // namespace centridem
