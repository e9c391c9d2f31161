// One benched-slope trial in the centrifuge (Tao et al. sections 3.2-3.3;
// DESIGN.md "Procedures"; docs/slope.md "Trial"):
//
//   foundation  the specimen (a brick, cached by recipe, tiled into the
//               slope's box) inside the chamber walls, or with [preparation]
//               the prepared foundation from the cache (procedures/
//               foundation.hpp), brought to rest under the field of the
//               first g-level (mean unbalanced-force ratio below
//               trial.equilibrium_ratio, kinetic energy below
//               trial.rest_kinetic_ratio);
//   cut         the excavation deleted (centre based); with [moisture] F0
//               graded by the height of each contact (procedures/
//               moisture.hpp); new contacts from now on get trial.after_cut
//               (mu_r = 0), their F0 graded by the height where they are
//               made; displacements reset;
//   level       cycling under the level's field, a failure check every
//               trial.check_interval_steps, until the FailureMonitor says
//               stable, or failed and the slide came to rest (or
//               after_failure_time_s passed), or max_time_s;
//   schedule    (stepped) the next level raises g on the same model, with
//               displacements reset and a fresh monitor, until max_g or
//               max_slides slides.
//
// Writes into the trial folder: pictures/frame_NNNN.png (side views, log
// displacement colours, red undeformed outline, g-level and time),
// frames/*.vtu + slope.pvd (ParaView), checks.csv, result.json,
// final_state.csv (id, position, radius, velocity, displacement; exact), and
// checkpoint.bin while running (every trial.checkpoint_interval_min minutes
// or _steps steps, and on SIGINT / SIGTERM). A folder holding checkpoint.bin
// is resumed from it; one holding result.json is finished.
#pragma once

#include "io/specimen_config.hpp"
#include "procedures/failure.hpp"
#include "procedures/foundation.hpp"
#include "procedures/slope_config.hpp"
#include "procedures/slope_geometry.hpp"

#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace centridem {

class World;
struct BodyField;
struct SideViewInput;

struct SlopeTrialPlan {
  std::vector<double> g_levels; // one level: a trial; several: a stepped schedule
  int max_slides = 1;           // schedule: stop after this many failed levels
};

struct LevelResult {
  double g_level = 0;
  FailureReport report;
  std::vector<FailureCheck> history;
  long first_step = 0, steps = 0;
  double time_s = 0;       // DEM time held at this level
  bool time_limit = false; // ended by trial.max_time_s before a decision
};

struct SlopeTrialResult {
  FoundationResult foundation;
  std::size_t excavated = 0, slope_particles = 0;
  std::vector<LevelResult> levels;
  long total_steps = 0;
  double timestep_s = 0;
  double wall_seconds = 0;           // this process's share when resumed
  double particle_steps_per_s = 0;   // over this process's cycling
  std::vector<std::string> pictures; // relative to the trial folder
  bool resumed = false;
  // Whether the trial (or schedule) failed: the first failed level, if any.
  const LevelResult* first_failure() const;
};

struct SlopeTrialOptions {
  std::string dir;                           // the trial folder (created)
  std::string cache_dir;                     // brick cache (created); "" = no cache
  double progress_interval_s = 10;           // seconds between progress lines
  int threads = -1;                          // < 0: trial.threads
  std::function<void(std::string_view)> log; // progress lines (none when empty)
};

// The body field of a trial at g-level n (uniform n g / s, or the radial
// centrifuge field with the chamber's middle under the axis).
BodyField slope_field(const SlopeScenario& sc, const SlopeGeometry& geometry, double g_level);

// The framing every picture of a trial shares: the window (the slope's
// section with a small margin) and the undeformed outline, set on `in`.
// `centridem render` frames its pictures the same way.
void frame_slope_picture(const SlopeGeometry& geometry, SideViewInput& in);

// Runs (or resumes) the trial in options.dir. Throws InputError for bad
// input, InstabilityError if it goes unstable (the last checkpoint stays),
// Interrupted after writing a checkpoint when a stop was requested.
SlopeTrialResult run_slope_trial(const SlopeScenario& sc, const SlopeTrialPlan& plan,
                                 const SlopeTrialOptions& options);

nlohmann::json to_json(const SlopeTrialResult& result);

} // namespace centridem
