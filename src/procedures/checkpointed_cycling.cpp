#include "procedures/checkpointed_cycling.hpp"

#include "base/errors.hpp"
#include "base/interrupt.hpp"
#include "engine/world.hpp"
#include "io/checkpoint.hpp"

#include <fmt/format.h>
#include <utility>

namespace centridem {

CheckpointedCycling::CheckpointedCycling(World& world, std::string path, CheckpointPolicy policy,
                                         std::function<std::string()> progress)
    : world_(world), path_(std::move(path)), policy_(policy), progress_(std::move(progress)),
      last_time_(Clock::now()), last_step_(world.step_count()) {}

void CheckpointedCycling::advance(long n) {
  if (n <= 0) return;
  const auto t0 = Clock::now();
  world_.cycle(n);
  seconds_ += std::chrono::duration<double>(Clock::now() - t0).count();
  steps_ += n;
  particle_steps_ += static_cast<double>(n) * static_cast<double>(world_.particles().size());
}

void CheckpointedCycling::write_now() {
  if (path_.empty()) return;
  write_checkpoint(world_, path_, progress_ ? progress_() : std::string());
  last_time_ = Clock::now();
  last_step_ = world_.step_count();
}

void CheckpointedCycling::at_check() {
  if (path_.empty()) return;
  const bool by_time =
      policy_.interval_min > 0 &&
      std::chrono::duration<double>(Clock::now() - last_time_).count() >= 60 * policy_.interval_min;
  const bool by_steps =
      policy_.interval_steps > 0 && world_.step_count() - last_step_ >= policy_.interval_steps;
  const int sig = stop_signal();
  if (!(by_time || by_steps || sig)) return;
  write_now();
  if (sig)
    throw Interrupted(sig, fmt::format("stopped by signal {} at step {} (t = {:.5f} s); "
                                       "checkpoint written to {}",
                                       sig, world_.step_count(), world_.time(), path_));
}

} // namespace centridem
