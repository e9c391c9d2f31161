#include "app/cmd_generate.hpp"

#include "core/errors.hpp"
#include "core/world.hpp"
#include "io/specimen_config.hpp"
#include "procedures/specimen.hpp"

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <memory>

namespace centridem {

int run_generate_command(const std::string& scenario, const std::string& out_dir, int threads) {
  const auto t0 = std::chrono::steady_clock::now();
  auto log = [t0](std::string_view line) {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    fmt::print(stderr, "[{:7.1f} s] {}\n", s, line);
    std::fflush(stderr);
  };
  const SpecimenSpec spec = load_specimen(scenario);
  std::string out = out_dir;
  if (out.empty()) {
    std::string stem = std::filesystem::path(scenario).stem().string();
    if (stem.empty()) stem = "scenario";
    out = "runs/" + stem + "_specimen";
  }
  WorldSettings ws;
  ws.threads = threads > 0 ? threads : 0;
  World world(ws);
  const BuiltSpecimen built = build_specimen(spec, world, log, ws.threads);
  write_specimen_outputs(world, built, spec, out);
  fmt::print("{}", format_report(built.report));
  fmt::print("wrote {}/specimen.vtu, specimen.xyzr, specimen.json, specimen.toml{}\n", out,
             built.brick ? ", brick.json" : "");
  std::fflush(stdout);
  return 0;
}

CLI::App* add_generate_subcommand(CLI::App& app) {
  struct Options {
    std::string scenario;
    std::string out;
    int threads = -1;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "generate", "build a scenario's [specimen] alone and write it (ParaView, x y z r, report; "
                  "docs/specimens.md)");
  cmd->add_option("scenario", o->scenario, "scenario file (TOML) with a [specimen] table")
      ->required();
  cmd->add_option("--out", o->out, "output folder (default: runs/<scenario stem>_specimen)");
  cmd->add_option("--threads", o->threads, "OpenMP threads (0 = the OpenMP default)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([o]() {
    int rc = 0;
    try {
      rc = run_generate_command(o->scenario, o->out, o->threads);
    } catch (const InputError& e) {
      fmt::print(stderr, "centridem: error: {}\n", e.what());
      rc = 2;
    } catch (const InstabilityError& e) {
      fmt::print(stderr, "centridem: unstable: {}\n", e.what());
      rc = 3;
    } catch (const std::exception& e) {
      fmt::print(stderr, "centridem: error: {}\n", e.what());
      rc = 1;
    }
    if (rc != 0) {
      std::fflush(stdout);
      std::fflush(stderr);
      std::exit(rc);
    }
  });
  return cmd;
}

} // namespace centridem
