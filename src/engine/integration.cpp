// Integration: gathers the forces on each particle, applies Cundall local
// damping and advances it by central differences; moves the walls, sums the
// forces on them and runs their servos; flags a rebuild when anything moved
// half the skin.
#include "engine/thread_count.hpp"
#include "engine/world.hpp"

#include "base/errors.hpp"
#include "physics/damping.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <omp.h>

namespace centridem {

void World::integrate() {
  const std::size_t n = p_.size();
  const double dt = dt_;
  const double alpha = settings_.local_damping;
  const bool damped = alpha != 0.0;
  auto& P = p_;
  // The rebuild test needs each particle's distance from where the lists
  // were built only when the bound on it could fail the test: a bound that
  // has room for this step's largest move at twice the pace of the last one
  // (and for the walls' moves at their present speed) skips the distances,
  // and their array, this step.
  const double skin_m = skin();
  double wall_move_ahead = 0.0;
  for (std::size_t k = 0; k < walls_.size(); ++k)
    wall_move_ahead =
        std::max(wall_move_ahead, norm(wall_motion_since_build_[k] + walls_[k].velocity * dt));
  const double bound_ahead = move_bound_m_ + 2.0 * last_step_move_m_;
  const bool measure_moves = !(2.0 * bound_ahead < kMoveBoundRoom * skin_m &&
                               bound_ahead + wall_move_ahead < kMoveBoundRoom * skin_m);
  double max_move2 = 0.0, max_step2 = 0.0, max_coordinate = 0.0;
  std::uint32_t bad = UINT32_MAX;

  // The force [N] the balls exert on each wall, their contact count and, for
  // a servo, the walls' normal stiffness [N/m].
  auto sum_wall_forces = [&] {
    for (Wall& wl : walls_) {
      wl.force = {};
      wl.contact_count = 0;
      wl.normal_stiffness_N_per_m = 0.0;
    }
    for (std::size_t e = 0; e < bw_.entries(); ++e) {
      if (bw_.properties[e] == kNoContact) continue;
      Wall& wl = walls_[bw_.wall[e]];
      wl.force += bw_.force_on_wall[e];
      ++wl.contact_count;
      if (wl.servo.active) {
        const double R = p_.radius[bw_.ball[e]];
        const ContactGeometry g{{}, 0.0, {}, {}, R, R, R, 0.0};
        wl.normal_stiffness_N_per_m += contact_stiffness(props_[bw_.properties[e]], g).kn;
      }
    }
  };

  int team = 1;
  const int threads = thread_count(settings_, n);
  integration_split_.prepare(threads, n);
  // Each thread a contiguous block of rows, moved towards equal measured time
  // (engine/work_split.hpp; a row's sums do not depend on who makes them).
  // clang-format off
#pragma omp parallel num_threads(threads) \
    reduction(max : max_move2, max_step2, max_coordinate) reduction(min : bad)
  // clang-format on
  {
    const int size = omp_get_num_threads(), me = omp_get_thread_num();
    if (me == 0) team = size;
    const double t_start = size > 1 ? omp_get_wtime() : 0.0;
    const auto [first_row, end_row] = integration_split_.block(me, size, n);
    // The contact pass summed each particle's own rows and the loads of the
    // contacts whose first end lay in the same block (in decreasing row
    // order). What is left are the records of the contacts whose first end
    // lay in an earlier block (only with more than one thread): they come
    // last in that order, added here from the highest row down, so the sums
    // are those of one thread, bit for bit. In the transpose, a particle's
    // slots run in increasing row order: those records are its first slots.
    // Only the particles the contact pass flagged have a record other than
    // +0 (BallBallContacts::record_waits); reading the transpose of every
    // particle cost the 2-thread integration a fifth of its time.
    const std::vector<std::size_t>& blocks = contact_blocks_;
    std::size_t b = 0; // the contact block of row i (followed at flagged rows)
    const bool records = blocks.size() > 2;
    for (std::size_t i = first_row; i < end_row; ++i) {
      if (records && bb_.record_waits[i]) {
        bb_.record_waits[i] = 0;
        while (i >= blocks[b + 1]) ++b;
        const std::uint32_t k0 = bb_.incoming_offset[i], k1 = bb_.incoming_offset[i + 1];
        std::uint32_t k = k0;
        while (k < k1 && bb_.slot_row[k] < blocks[b]) ++k;
        while (k > k0) {
          const std::uint32_t e = bb_.incoming[--k];
          P.force[i] += bb_.force_on_2[e];
          P.moment[i] += bb_.moment_on_2[e];
        }
      }
      const Vec3 f = P.force[i];
      const Vec3 mo = P.moment[i];
      // Central differences (PFC): v(t+dt/2) = v(t-dt/2) + (F + Fd)/m dt.
      // Undamped runs (alpha = 0: the flowing workloads) skip the damping
      // force, which is then zero: the same sums, bit for bit, for finite F.
      if (!(P.flags[i] & fix_translation))
        P.velocity[i] +=
            (damped ? f + local_damping_force(f, P.velocity[i], alpha) : f) * (dt / P.mass[i]);
      if (!(P.flags[i] & fix_rotation))
        P.spin[i] +=
            (damped ? mo + local_damping_force(mo, P.spin[i], alpha) : mo) * (dt / P.inertia[i]);
      const Vec3 dx = P.velocity[i] * dt;
      P.position[i] += dx;
      P.displacement[i] += dx;
      if (!is_finite(P.position[i]) || !is_finite(P.spin[i]))
        bad = std::min(bad, static_cast<std::uint32_t>(i));
      max_step2 = std::max(max_step2, norm2(dx));
      max_coordinate =
          std::max(max_coordinate, std::max({std::abs(P.position[i].x), std::abs(P.position[i].y),
                                             std::abs(P.position[i].z)}));
      if (measure_moves)
        max_move2 = std::max(max_move2, norm2(P.position[i] - position_at_build_[i]));
    }
    // The first thread also sums the forces the balls exert on the walls, in
    // entry order (the same sums with any team); its block of rows shrinks
    // by as much, since the split follows each thread's measured time.
    if (me == 0) sum_wall_forces();
    if (size > 1) integration_split_.record(me, omp_get_wtime() - t_start);
  }
  integration_split_.rebalance();
  threads_used_ = team;

  if (bad != UINT32_MAX)
    throw InstabilityError(fmt::format(
        "unstable at step {}: particle id {} has a non-finite position or spin (NaN/inf). Likely "
        "cause: timestep too large for the contact stiffness (critical estimate {:.3g} s, "
        "timestep {:.3g} s), or an input that produced an infinite force.",
        step_, P.id[bad], critical_timestep(), dt_));

  // Walls: prescribed motion (the force on them was summed above).
  double max_wall_move = 0.0;
  bool any_servo = false;
  for (std::size_t k = 0; k < walls_.size(); ++k) {
    walls_[k].point += walls_[k].velocity * dt;
    wall_motion_since_build_[k] += walls_[k].velocity * dt;
    max_wall_move = std::max(max_wall_move, norm(wall_motion_since_build_[k]));
    any_servo = any_servo || walls_[k].servo.active;
  }
  if (any_servo) {
    for (Wall& wl : walls_) {
      if (!wl.servo.active) continue;
      WallServo& sv = wl.servo;
      const double measured = -dot(wl.force, sv.direction); // balls push against `direction`
      const double error = sv.target_force_N - measured;
      const double demand = sv.integral_time_s > 0
                                ? error + sv.error_integral_N_s / sv.integral_time_s
                                : error; // [N]
      const double free_speed = wl.normal_stiffness_N_per_m > 0
                                    ? sv.gain_factor * demand / (wl.normal_stiffness_N_per_m * dt)
                                    : (demand > 0 ? sv.max_speed_m_per_s : -sv.max_speed_m_per_s);
      const double speed = std::clamp(free_speed, -sv.max_speed_m_per_s, sv.max_speed_m_per_s);
      if (sv.integral_time_s > 0 && (speed == free_speed || error * free_speed < 0))
        sv.error_integral_N_s += error * dt;
      wl.velocity =
          wl.velocity - dot(wl.velocity, sv.direction) * sv.direction + speed * sv.direction;
    }
  }

  // Rebuild when anything moved half the skin (or a particle and a wall the
  // skin between them). The bound on the particles' moves since the build
  // grows by this step's largest move, plus the rounding of the positions'
  // updates (half a unit in the last place of the largest coordinate, per
  // component); the distances are measured, in a pass of their own if the
  // loop above skipped them, whenever the bound no longer shows the test
  // passes. The test's outcome is the same as measuring every step.
  const double step_move = std::sqrt(max_step2);
  last_step_move_m_ = step_move;
  double max_move = 0.0;
  if (measure_moves) {
    max_move = std::sqrt(max_move2);
    move_bound_m_ = max_move;
  } else {
    move_bound_m_ += step_move * (1.0 + 1e-12) + 1e-15 * max_coordinate;
    const double b = move_bound_m_ * (1.0 + 1e-9);
    if (!(2.0 * b <= skin_m && b + max_wall_move <= skin_m)) {
      for (std::size_t i = 0; i < n; ++i)
        max_move2 = std::max(max_move2, norm2(P.position[i] - position_at_build_[i]));
      max_move = std::sqrt(max_move2);
      move_bound_m_ = max_move;
    }
  }
  if (2.0 * max_move > skin_m || max_move + max_wall_move > skin_m) dirty_ = true;
}

} // namespace centridem
