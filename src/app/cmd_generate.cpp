#include "app/cmd_generate.hpp"

#include "app/cli.hpp"

#include "base/errors.hpp"
#include "engine/world.hpp"
#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "io/particle_file.hpp"
#include "io/specimen_config.hpp"
#include "io/vtk.hpp"
#include "procedures/foundation.hpp"
#include "procedures/gsd.hpp"
#include "procedures/slope_config.hpp"
#include "procedures/slope_geometry.hpp"
#include "procedures/specimen.hpp"

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <toml++/toml.h>

namespace centridem {

namespace fs = std::filesystem;

namespace {

std::string default_out(const std::string& scenario, const char* suffix) {
  std::string stem = fs::path(scenario).stem().string();
  if (stem.empty()) stem = "scenario";
  return "runs/" + stem + suffix;
}

// A slope scenario has a [slope] table (read without checking the rest: the
// scenario's own reader does that).
bool is_slope_scenario(const std::string& path) {
  try {
    return toml::parse_file(path).contains("slope");
  } catch (const toml::parse_error&) {
    return false; // the specimen reader reports the syntax error with its position
  }
}

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream o(p, std::ios::binary);
  o << text;
  if (!o) throw InputError("--out", "\"" + p.parent_path().string() + "\"", "cannot be written");
}

// The slope's foundation, prepared (and cached) exactly as `slope` does before its trials.
int generate_foundation(const GenerateOptions& o,
                        const std::function<void(std::string_view)>& log) {
  SlopeScenario sc = load_slope_scenario(o.scenario, o.set);
  cli::print_warnings(sc.specimen.warnings);
  if (o.scale != 0) apply_scale(sc, o.scale);
  const SlopeGeometry geometry(sc.slope);
  const fs::path out = o.out_dir.empty() ? default_out(o.scenario, "_foundation") : o.out_dir;
  if (o.check) {
    check_output_folder(out.string(), "--out");
    check_output_folder(o.cache_dir, "--cache");
    fmt::print("{}", resolved_slope_toml(sc));
    fmt::print(stderr, "centridem generate: {} checked; nothing generated (--check)\n", o.scenario);
    return 0;
  }
  make_directories(out.string());
  const int threads = o.threads > 0 ? o.threads : 0;
  log(fmt::format("slope foundation: {} (s = {:g}; DEM box {:.2f} x {:.2f} x {:.2f} mm)",
                  sc.name.empty() ? "benched slope" : sc.name, sc.slope.size_reduction_factor,
                  1e3 * geometry.length(), 1e3 * geometry.breadth(), 1e3 * geometry.height()));
  WorldSettings ws;
  ws.threads = threads;
  ws.local_damping = sc.trial.local_damping;
  World world(ws);
  FoundationResult f;
  std::string cache_file;
  if (sc.preparation.enabled) {
    const PreparedFoundationFile pf = ensure_prepared_foundation(sc, o.cache_dir, log, threads);
    read_checkpoint(world, pf.path);
    f = pf.result;
    cache_file = pf.path;
    log(fmt::format("prepared foundation {} ({})", pf.made_now ? "made" : "from the cache",
                    pf.path));
  } else {
    build_foundation(world, sc, geometry, o.cache_dir, 1.0, f, log, threads);
    log("no [preparation] table: the foundation as generated (not compacted; the trial settles it "
        "at its g-level)");
  }
  const PorosityProfile profile = foundation_porosity_profile(
      world, Box{{0, 0, 0}, {geometry.length(), geometry.breadth(), geometry.height()}});
  write_particles_vtu(world, (out / "foundation.vtu").string());
  write_particle_file(world, (out / "foundation.xyzr").string());
  nlohmann::json j = {{"scenario", fs::absolute(o.scenario).lexically_normal().string()},
                      {"size_reduction_factor", sc.slope.size_reduction_factor},
                      {"design_height_m", geometry.height()},
                      {"particles", world.particles().size()},
                      {"foundation", to_json(f)},
                      {"porosity_profile", to_json(profile)}};
  if (!cache_file.empty()) j["cache_file"] = cache_file;
  write_text(out / "foundation.json", j.dump(2) + "\n");
  write_text(out / "scenario.toml", resolved_slope_toml(sc));

  fmt::print("foundation: {} particles in {:.2f} x {:.2f} x {:.2f} mm\n", world.particles().size(),
             1e3 * geometry.length(), 1e3 * geometry.breadth(), 1e3 * geometry.height());
  if (f.prepared)
    fmt::print("prepared: generated {}, {} above the design removed; porosity by thirds "
               "{:.4f} / {:.4f} / {:.4f} (spread {:.4f}); coordination {:.2f}\n",
               f.generated_particles, f.trimmed, f.layer_porosity[0], f.layer_porosity[1],
               f.layer_porosity[2],
               std::max({f.layer_porosity[0], f.layer_porosity[1], f.layer_porosity[2]}) -
                   std::min({f.layer_porosity[0], f.layer_porosity[1], f.layer_porosity[2]}),
               f.coordination_number);
  fmt::print("porosity against height (layers of {:.3f} mm, {:.3f} mm left out at the walls):\n",
             1e3 * profile.layer_m, 1e3 * profile.margin_m);
  for (std::size_t k = profile.porosity.size(); k-- > 0;)
    fmt::print("  z {:6.3f} - {:6.3f} mm  porosity {:.4f}\n", 1e3 * profile.z_bottom_m[k],
               1e3 * (profile.z_bottom_m[k] + profile.layer_m), profile.porosity[k]);
  fmt::print("wrote {}/foundation.vtu, foundation.xyzr, foundation.json, scenario.toml\n",
             out.string());
  std::fflush(stdout);
  return 0;
}

} // namespace

int run_generate_command(const GenerateOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  auto log = [t0](std::string_view line) {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    fmt::print(stderr, "[{:7.1f} s] {}\n", s, line);
    std::fflush(stderr);
  };
  if (is_slope_scenario(o.scenario)) return generate_foundation(o, log);
  if (o.scale != 0)
    throw InputError("--scale", fmt::format("{:g}", o.scale),
                     "only with a slope scenario (a [slope] table)");
  const SpecimenSpec spec = load_specimen(o.scenario, o.set);
  cli::print_warnings(spec.warnings);
  const std::string out = o.out_dir.empty() ? default_out(o.scenario, "_specimen") : o.out_dir;
  if (o.check) {
    check_output_folder(out, "--out");
    check_specimen_size(spec, resolve_gradation(spec));
    fmt::print("{}", resolved_specimen_toml(spec));
    fmt::print(stderr, "centridem generate: {} checked; nothing generated (--check)\n", o.scenario);
    return 0;
  }
  WorldSettings ws;
  ws.threads = o.threads > 0 ? o.threads : 0;
  World world(ws);
  const BuiltSpecimen built = build_specimen(spec, world, log, ws.threads);
  write_specimen_outputs(world, built, spec, out);
  fmt::print("{}", format_report(built.report));
  fmt::print("wrote {}/specimen.vtu, specimen.xyzr, specimen.json, specimen.toml{}\n", out,
             built.brick ? ", brick.json" : "");
  if (toml::parse_file(o.scenario).contains("preparation"))
    fmt::print("note: [preparation] is applied by `shear` (the box compacted by its servo at each "
               "normal pressure) and `slope`; this is the specimen before it\n");
  std::fflush(stdout);
  return 0;
}

CLI::App* add_generate_subcommand(CLI::App& app) {
  auto o = std::make_shared<GenerateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "generate", "build a scenario's [specimen] alone, or a slope scenario's prepared foundation, "
                  "and write it (ParaView, x y z r, report; docs/specimens.md)");
  cmd->add_option("scenario", o->scenario, "scenario file (TOML) with a [specimen] table")
      ->required();
  cmd->add_option("--out", o->out_dir,
                  "output folder (default: runs/<scenario stem>_specimen, or _foundation)");
  cli::add_threads_option(*cmd, o->threads, "OpenMP threads (0 = the OpenMP default)");
  cli::add_set_option(*cmd, o->set);
  cmd->add_option("--scale", o->scale,
                  "slope scenarios: another size reduction factor (as `slope --scale`)")
      ->check(cli::positive_number(1));
  cmd->add_option("--cache", o->cache_dir,
                  "slope scenarios: folder of cached bricks and prepared foundations (default "
                  "runs/cache)");
  cli::add_check_flag(*cmd, o->check);
  cmd->callback([o]() { cli::run_subcommand([o] { return run_generate_command(*o); }); });
  return cmd;
}

} // namespace centridem
