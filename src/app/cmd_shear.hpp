// `centridem shear SCENARIO.toml [--out DIR] [--jobs N] [--pressure KPA]...`
// `centridem shear --resume DIR [--jobs N]` and `centridem shear --report DIR`
// (summary and plots of what DIR holds now, runs still going included): the numerical direct shear
// test (Tao et al. section 3.1; docs/shear.md).
// One run per normal pressure, each on the same specimen (same seed) built
// into a fresh World; with --jobs N > 1 the runs are forked child processes
// (one pressure each), else they run in sequence. Writes to DIR:
// shear_<kPa>kPa.csv per pressure, shear_curves.png, mohr_coulomb.png,
// summary.json, scenario.toml (the resolved scenario) and pressures.json (the
// pressures run, read by --resume). Each run checkpoints into
// shear_<kPa>kPa.checkpoint.bin (every shear.checkpoint_interval_min, at the
// start of shearing, on SIGINT/SIGTERM); finished runs leave
// shear_<kPa>kPa.json. Progress lines go to stderr at most every 10 s.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace centridem {

struct ShearCommandOptions {
  std::string scenario;
  std::string out_dir;               // "" = runs/<scenario stem>_shear
  std::string resume_dir;            // continue the runs in this folder
  std::string report_dir;            // only rewrite this folder's summary and plots
  int jobs = 1;                      // parallel runs (child processes)
  bool jobs_given = true;            // false: no --jobs on the command line, so --resume takes
                                     // the started run's (pressures.json)
  std::vector<double> pressures_kPa; // empty: the scenario's list
  int threads = -1;                  // per run; < 0: the started run's (--resume), else the
                                     // scenario's shear.threads
  double progress_interval_s = 10.0; // seconds between progress lines
  std::vector<std::string> set;      // --set KEY=VALUE over the scenario
  bool check = false;                // --check: print the resolved scenario, run nothing
  bool resume_hint = true;           // print "continue with centridem shear --resume" when stopped
                                     // (false inside `calibrate`, which prints its own)
};

// "shear_<kPa>kPa": the stem of one pressure's files in a run folder
// (shear_<kPa>kPa.json holds a finished run's result and curve).
std::string shear_run_stem(double normal_stress_Pa);

// Runs the command; returns the exit code (0; 128 + signal when stopped, with
// checkpoints written). Throws InputError for bad input and InstabilityError
// when a run goes unstable (with --jobs > 1: when any child failed, with the
// first failure's class).
int run_shear_command(const ShearCommandOptions& options);

// Registers the `shear` subcommand on `app` (errors: exit 2 bad input,
// 3 unstable, 1 other). Returns the subcommand.
CLI::App* add_shear_subcommand(CLI::App& app);

} // namespace centridem
