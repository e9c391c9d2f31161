// `centridem calibrate SCENARIO.toml [--out DIR] [--jobs N]` and
// `centridem calibrate --resume DIR`: contact parameters fitted to measured
// direct shear results (docs/calibrate.md). The scenario is a shear scenario
// with a [calibrate] table (procedures/calibration_config.hpp). Each stage
// runs BOBYQA (procedures/calibration.hpp) over its parameters; each
// evaluation is a `centridem shear` run folder DIR/<stage>/eval_NNN (the
// stage's pressures as --jobs child processes), recorded in
// DIR/<stage>/history.csv as soon as it finishes, so that --resume repeats
// none. Writes per stage misfit.png and curves.png, and at the end
// summary.json, fitted.toml (the resolved shear scenario of the fitted
// material) and fitted_set.txt (the fitted values as --set flags).
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace centridem {

struct CalibrateCommandOptions {
  std::string scenario;
  std::string out_dir;    // "" = runs/<scenario stem>_calibrate
  std::string resume_dir; // continue the calibration in this folder
  int jobs = 1;           // pressures of one evaluation run at once
  int threads = -1;       // per run; < 0: the scenario's shear.threads
  std::vector<std::string> set;
  bool check = false;
};

// Runs the command; returns the exit code (0; 128 + signal when stopped).
// Throws InputError for bad input and InstabilityError when a run goes
// unstable.
int run_calibrate_command(const CalibrateCommandOptions& options);

CLI::App* add_calibrate_subcommand(CLI::App& app);

} // namespace centridem
