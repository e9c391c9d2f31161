// `centridem generate SCENARIO.toml [--out DIR] [--threads N] [--set K=V]...`:
// builds the scenario's [specimen] alone (docs/specimens.md) and writes it to
// DIR: specimen.vtu (ParaView), specimen.xyzr (x y z r per line, SI),
// specimen.json (the report), specimen.toml (the resolved [specimen]) and
// brick.json (the relaxed periodic brick with its contacts). The report is
// also printed.
//
// A slope scenario (a [slope] table) gets its foundation instead, built and,
// with [preparation], prepared exactly as `slope` prepares it before its
// trials (procedures/foundation.hpp; cached in --cache, so a later `slope`
// run with the same cache starts from it): foundation.vtu, foundation.xyzr,
// foundation.json (the preparation report and the porosity profile against
// height) and scenario.toml (the resolved scenario). `--scale` as in `slope`.
// A shear box is compacted by its servo at each normal pressure when `shear`
// runs, so `generate` writes its loose specimen and says so.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace centridem {

struct GenerateOptions {
  std::string scenario;
  std::string out_dir;          // "" = runs/<scenario stem>_specimen (_foundation for a slope)
  int threads = -1;             // < 0: the OpenMP default
  std::vector<std::string> set; // KEY=VALUE overrides (TOML values)
  double scale = 0;             // slope only: another size reduction factor (0 = the file's)
  std::string cache_dir = "runs/cache"; // slope only: bricks and prepared foundations
  bool check = false;                   // --check: print the resolved scenario, generate nothing
};

// Runs the command; returns the exit code (0). Throws InputError for bad
// input and InstabilityError if the preparation goes unstable.
int run_generate_command(const GenerateOptions& options);

// Registers the `generate` subcommand and its options on `app`. The
// subcommand runs from its own callback during app.parse(); on failure it
// prints "centridem: error: ..." / "centridem: unstable: ..." to stderr and
// exits with the project's codes (2 bad input, 3 unstable, 1 other), so
// main.cpp needs only this one call. Returns the subcommand.
CLI::App* add_generate_subcommand(CLI::App& app);

} // namespace centridem
