#include "procedures/checkpointed_cycling.hpp"

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "core/world.hpp"
#include "io/checkpoint.hpp"

#include <fmt/format.h>
#include <utility>

namespace centridem {

CheckpointedCycling::CheckpointedCycling(World& world, std::string path, CheckpointPolicy policy,
                                         long check_interval_steps,
                                         std::function<std::string()> progress)
    : world_(world), path_(std::move(path)), policy_(policy),
      chunk_(check_interval_steps > 0 ? check_interval_steps : 1), progress_(std::move(progress)),
      last_time_(Clock::now()), last_step_(world.step_count()) {}

void CheckpointedCycling::cycle_chunk(long n) {
  const auto t0 = Clock::now();
  world_.cycle(n);
  seconds_ += std::chrono::duration<double>(Clock::now() - t0).count();
  steps_ += n;
  particle_steps_ += static_cast<double>(n) * static_cast<double>(world_.particles().size());
}

void CheckpointedCycling::write_now() {
  write_checkpoint(world_, path_, progress_ ? progress_() : std::string());
  last_time_ = Clock::now();
  last_step_ = world_.step_count();
}

void CheckpointedCycling::write_wanted() {
  write_now();
  wanted_ = false;
  if (const int sig = stop_signal())
    throw Interrupted(sig, fmt::format("stopped by signal {} at step {} (t = {:.5f} s); "
                                       "checkpoint written to {}",
                                       sig, world_.step_count(), world_.time(), path_));
}

void CheckpointedCycling::advance(long n) {
  while (n > 0) {
    if (!wanted_) {
      cycle_chunk(n);
      return;
    }
    const long patience = (stop_signal() ? 2 : policy_.patience_checks) * chunk_;
    while (n > 0 && !world_.rebuild_pending() && world_.step_count() - wanted_since_ < patience) {
      cycle_chunk(1);
      --n;
    }
    if (world_.rebuild_pending() || world_.step_count() - wanted_since_ >= patience) write_wanted();
  }
}

void CheckpointedCycling::at_check() {
  const bool by_time =
      policy_.interval_min > 0 &&
      std::chrono::duration<double>(Clock::now() - last_time_).count() >= 60 * policy_.interval_min;
  const bool by_steps =
      policy_.interval_steps > 0 && world_.step_count() - last_step_ >= policy_.interval_steps;
  if (!wanted_ && (by_time || by_steps || stop_signal())) {
    wanted_ = true;
    wanted_since_ = world_.step_count();
  }
  if (wanted_ && world_.rebuild_pending()) write_wanted();
}

} // namespace centridem
