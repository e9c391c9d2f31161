// `centridem slope SCENARIO.toml [--out DIR] [--g N]... [--search STABLE FAILED]
// [--tolerance G] [--jobs N] [--threads N] [--cache DIR]` and
// `centridem slope --resume RUN_DIR`: the benched slope in the centrifuge
// (Tao et al. sections 3.2-3.3; docs/slope.md). Runs the scenario's campaign
// (or the one given on the command line): independent trials at a list of
// g-levels, a bracketing search for the critical g, or one model whose g is
// raised in steps. Trials are independent processes (--jobs). Writes to DIR:
// scenario.toml (resolved), campaign.json, trial_<g>g/ (or schedule/) per
// trial (pictures, ParaView frames, checks.csv, result.json, log.txt),
// summary.json, summary.md and g_levels.png.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace centridem {

struct SlopeCommandOptions {
  std::string scenario;
  std::string out_dir;             // "" = runs/<scenario stem>_slope
  std::string resume_dir;          // continue this run folder instead
  std::string cache_dir;           // brick cache; "" = <out>/../cache
  std::vector<double> g_levels;    // --g: independent trials at these levels
  std::vector<double> search;      // --search STABLE FAILED
  bool search_auto = false;        // --search-auto: the bracket from the limit-equilibrium estimate
  std::vector<double> schedule;    // --schedule START STEP MAX: one model, g raised in steps
  std::vector<std::string> set;    // --set KEY=VALUE: overrides of the scenario's keys
  double tolerance_g = 0;          // --tolerance (0: the scenario's)
  double scale = 0;                // --scale: size reduction factor s instead of the scenario's
  int jobs = 0;                    // 0: campaign.jobs
  int threads = -1;                // < 0: trial.threads
  double progress_interval_s = 10; // seconds between progress lines
  bool check = false;              // --check: print the resolved scenario, run nothing
};

// Runs the command; returns the exit code. Throws InputError for bad input,
// InstabilityError when a trial went unstable, Interrupted when stopped.
int run_slope_command(const SlopeCommandOptions& options);

// Registers the `slope` subcommand on `app` (exit codes: 0, 2 bad input,
// 3 unstable, 130 / 143 interrupted after a checkpoint, 1 other).
CLI::App* add_slope_subcommand(CLI::App& app);

} // namespace centridem
