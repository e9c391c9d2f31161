// A staged run (`centridem run SCENARIO.toml`): builds the World a scenario
// describes, then for each stage applies its changes and cycles it in chunks,
// measuring, writing frames and printing progress between chunks (never per
// step). Writes the run folder described in docs/scenario.md.
//
// It keeps its work like the slope trial and the shear test: a checkpoint
// (checkpoint.bin in the run folder, io/checkpoint.hpp) at the start, every
// simulation.checkpoint_interval_min minutes and/or checkpoint_interval_steps
// steps, and on SIGINT / SIGTERM (then Interrupted); resume_run continues from
// it bit for bit (same thread count), the outputs continuing where the
// checkpoint left them (no row or frame lost or repeated).
#pragma once

#include "engine/world.hpp"
#include "io/scenario.hpp"

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace centridem {

struct RunOptions {
  std::string output_dir;     // "" = the scenario's simulation.output_dir
  std::optional<int> threads; // overrides simulation.threads
  std::FILE* out = stdout;    // start-up echo and stage lines (nullptr: only log.txt)
  std::FILE* err = stderr;    // progress lines and warnings (nullptr: only log.txt)
};

struct WallReading {
  std::string name;
  Vec3 force_N; // force the balls exert on the wall [N]
  std::uint32_t contacts = 0;
};

struct StageReport {
  std::string name;
  StageEnd end = StageEnd::steps;
  long first_step = 0, steps = 0;      // world step count at the start; steps taken
  double start_time_s = 0, time_s = 0; // simulated time at the start; simulated duration
  bool reached_equilibrium = false;    // until_equilibrium stages
  std::size_t particles_removed = 0;
  std::size_t contacts_modified = 0;
  Measurements end_state;
  std::vector<WallReading> walls;
  double wall_time_s = 0;
  double particle_steps_per_s = 0;
  std::string particles_file; // stage_NN_<name>_particles.txt (relative to the run folder)
  std::size_t frames = 0;     // frames written during the stage
};

struct RunReport {
  std::string output_dir;
  std::vector<StageReport> stages;
  double wall_time_s = 0;
};

// The World at the start of the scenario: settings, particles, walls, contact
// defaults and gravity. Throws InputError on bad content.
World build_world(const Scenario& scenario);

struct StageChanges {
  std::size_t particles_removed = 0;
  std::size_t contacts_modified = 0;
};

// Applies the changes a stage makes before it cycles, in the documented
// order: remove_walls, remove_particles, walls, gravity, contact.ball_ball,
// modify_contacts, local_damping, reset_displacements. `path` names the stage
// in messages ("stages[2]").
StageChanges apply_stage_changes(World& world, const StageSpec& stage, const std::string& path);

// Runs every stage and writes the run folder. Throws InputError for bad
// input (also found while running, e.g. a fixed timestep above the critical
// one), InstabilityError when the run goes unstable and Interrupted after a
// stop request's checkpoint; summary.json and log.txt then hold what was
// done, with the error. A folder holding an unfinished run (checkpoint.bin)
// is refused (InputError naming --out). On success the checkpoint is removed
// and final_state.csv holds the final particles, every double exactly.
RunReport run_scenario(Scenario scenario, const RunOptions& options = {});

// Continues the run in folder `dir` (its scenario.resolved.toml and
// checkpoint.bin) to its end. options.output_dir and options.threads must be
// unset (the run keeps its folder and thread count). A run that completed
// earlier is reported and left alone (a report without stages). Throws
// InputError naming --resume when `dir` is not a resumable run folder.
RunReport resume_run(const std::string& dir, const RunOptions& options = {});

} // namespace centridem
