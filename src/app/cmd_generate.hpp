// `centridem generate SCENARIO.toml [--out DIR] [--threads N]`: builds the
// scenario's [specimen] alone (docs/specimens.md) and writes it to DIR:
// specimen.vtu (ParaView), specimen.xyzr (x y z r per line, SI),
// specimen.json (the report), specimen.toml (the resolved [specimen]) and
// brick.json (the relaxed periodic brick with its contacts). The report is
// also printed.
#pragma once

#include <string>

namespace CLI {
class App;
}

namespace centridem {

// Runs the command; returns the exit code (0). Throws InputError for bad
// input and InstabilityError if relaxing the brick goes unstable.
// out_dir "" = runs/<scenario stem>_specimen. threads < 0: the OpenMP default.
int run_generate_command(const std::string& scenario, const std::string& out_dir, int threads = -1);

// Registers the `generate` subcommand and its options on `app`. The
// subcommand runs from its own callback during app.parse(); on failure it
// prints "centridem: error: ..." / "centridem: unstable: ..." to stderr and
// exits with the project's codes (2 bad input, 3 unstable, 1 other), so
// main.cpp needs only this one call. Returns the subcommand.
CLI::App* add_generate_subcommand(CLI::App& app);

} // namespace centridem
