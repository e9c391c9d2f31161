// Cycling a World in chunks with checkpoints, for the long procedures (slope
// trial, direct shear). The procedure makes its decisions at checks (chunk
// boundaries counted from a fixed step, so a resume mid-chunk finishes the
// chunk first) and calls `at_check()` there; it advances with `advance(n)`.
//
// At a check, a checkpoint is written when one is due (wall-clock minutes or
// steps since the last one) or asked for (SIGINT / SIGTERM,
// base/interrupt.hpp); after a stop request's checkpoint `Interrupted` is
// thrown (exit code 128 + signal), naming the checkpoint. Writing one does not
// perturb the run (io/checkpoint.hpp), so a run stopped and resumed any number
// of times ends bit for bit like one never stopped (same thread count).
#pragma once

#include <chrono>
#include <functional>
#include <string>

namespace centridem {

class World;

struct CheckpointPolicy {
  double interval_min = 10; // wall-clock minutes between checkpoints; 0 = not by time
  long interval_steps = 0;  // steps between checkpoints; 0 = not by steps
};

class CheckpointedCycling {
public:
  // `progress` returns the procedure's own state (the checkpoint's blob) at
  // the moment a checkpoint is written. An empty `path` turns checkpoints off
  // (then this only cycles and counts).
  CheckpointedCycling(World& world, std::string path, CheckpointPolicy policy,
                      std::function<std::string()> progress);

  // Cycles n steps.
  void advance(long n);
  // At a check: writes a checkpoint if one is due or a stop was asked for
  // (then throws Interrupted).
  void at_check();
  // Writes a checkpoint now.
  void write_now();

  const std::string& path() const { return path_; }
  // Steps, particle-steps and wall seconds spent cycling through this object.
  long steps() const { return steps_; }
  double particle_steps() const { return particle_steps_; }
  double cycling_seconds() const { return seconds_; }
  double particle_steps_per_s() const { return seconds_ > 0 ? particle_steps_ / seconds_ : 0.0; }

private:
  using Clock = std::chrono::steady_clock;

  World& world_;
  std::string path_;
  CheckpointPolicy policy_;
  std::function<std::string()> progress_;
  Clock::time_point last_time_;
  long last_step_;
  long steps_ = 0;
  double particle_steps_ = 0;
  double seconds_ = 0;
};

} // namespace centridem
