// Cycling a World in chunks with checkpoints, for the long procedures (slope
// trial, direct shear). The procedure makes its decisions at checks (chunk
// boundaries counted from a fixed step, so a resume mid-chunk finishes the
// chunk first) and calls `at_check()` there; it advances with `advance(n)`.
//
// A checkpoint forces a neighbour rebuild (io/checkpoint.hpp). Written where
// a rebuild is pending anyway it does not perturb the run, so a run stopped
// and resumed (any number of times, same thread count) ends bit for bit like
// one never stopped. A wanted checkpoint (by wall time, by steps, or a stop
// request: SIGINT / SIGTERM, core/interrupt.hpp) therefore waits for the
// first step boundary with a rebuild pending. A model at rest may not rebuild
// for long: after `patience` checks (2 for a stop request) it is written
// anyway, and that run then differs from an unstopped one by round-off only.
// After a stop request's checkpoint, `Interrupted` is thrown (exit code
// 128 + signal), naming the checkpoint.
#pragma once

#include <chrono>
#include <functional>
#include <string>

namespace centridem {

class World;

struct CheckpointPolicy {
  double interval_min = 10; // wall-clock minutes between checkpoints; 0 = not by time
  long interval_steps = 0;  // steps between checkpoints; 0 = not by steps
  int patience_checks = 10; // checks to wait for a pending rebuild before writing anyway
};

class CheckpointedCycling {
public:
  // `progress` returns the procedure's own state (the checkpoint's blob) at
  // the moment a checkpoint is written. `check_interval_steps` is the
  // procedure's chunk (it sets the patience in steps).
  CheckpointedCycling(World& world, std::string path, CheckpointPolicy policy,
                      long check_interval_steps, std::function<std::string()> progress);

  // Cycles n steps; a wanted checkpoint is written at the first step with a
  // neighbour rebuild pending (or when the patience runs out).
  void advance(long n);
  // At a check: a checkpoint that is due (time, steps) or asked for (stop
  // request) becomes wanted, and is written now if a rebuild is pending.
  void at_check();
  // Writes a checkpoint now (forces a rebuild).
  void write_now();

  const std::string& path() const { return path_; }
  // Steps, particle-steps and wall seconds spent cycling through this object.
  long steps() const { return steps_; }
  double particle_steps() const { return particle_steps_; }
  double cycling_seconds() const { return seconds_; }
  double particle_steps_per_s() const { return seconds_ > 0 ? particle_steps_ / seconds_ : 0.0; }

private:
  using Clock = std::chrono::steady_clock;
  void cycle_chunk(long n);
  void write_wanted();

  World& world_;
  std::string path_;
  CheckpointPolicy policy_;
  long chunk_;
  std::function<std::string()> progress_;
  Clock::time_point last_time_;
  long last_step_;
  bool wanted_ = false;
  long wanted_since_ = 0;
  long steps_ = 0;
  double particle_steps_ = 0;
  double seconds_ = 0;
};

} // namespace centridem
