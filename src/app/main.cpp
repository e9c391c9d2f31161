// centridem: command line. Exit codes: 0 success, 2 bad input, 3 the run went
// unstable, 128 + signal stopped by SIGINT / SIGTERM after a checkpoint, 1 any
// other failure.
#include "app/cli.hpp"
#include "app/cmd_calibrate.hpp"
#include "app/cmd_generate.hpp"
#include "app/cmd_render.hpp"
#include "app/cmd_shear.hpp"
#include "app/cmd_slope.hpp"
#include "base/errors.hpp"
#include "base/interrupt.hpp"
#include "io/output.hpp"
#include "io/scenario.hpp"
#include "procedures/bench.hpp"
#include "procedures/staged_run.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fmt/format.h>
#include <map>

using namespace centridem;

namespace {

int run_bench_command(const BenchOptions& o) {
  for (int t : o.threads) {
    const BenchResult r = run_bench(o, t);
    fmt::print(
        "law: {}\nworkload: {}\nthreads: {}\nparticles: {}\nsteps: {}\nwall_seconds: {:.3f}\n"
        "contacts_per_particle: {:.3f}\nball_ball_contacts_per_particle: {:.3f}\n"
        "neighbour_entries_per_particle: {:.3f}\n"
        "bytes_per_particle: {}\nskin_m: {:.4g}\nneighbour_rebuilds: {}\n"
        "particle_steps_per_s: {:.4g}\n"
        "time_share_neighbour_search: {:.3f}\ntime_share_contact_pass: {:.3f}\n"
        "time_share_integration: {:.3f}\nwait_share_contact_pass: {:.4f}\n"
        "wait_share_integration: {:.4f}\nopenmp_wait: {}\ncpu: {}\nsimd: {}\n\n",
        to_string(o.law), to_string(o.workload), r.threads, r.particles, r.steps, r.wall_seconds,
        r.contacts_per_particle, r.ball_ball_contacts_per_particle, r.neighbours_per_particle,
        r.bytes_per_particle, r.skin_m, r.rebuilds, r.particle_steps_per_s,
        r.share_neighbour_search, r.share_contact_pass, r.share_integration,
        r.share_contact_pass_wait, r.share_integration_wait, cli::openmp_wait_in_use(),
        cli::cpu_model(), cli::simd_in_use());
    std::fflush(stdout);
  }
  return 0;
}

struct RunCommand {
  std::string scenario;
  std::string out;
  std::string resume;           // run folder to continue
  int threads = -1;             // -1: as the scenario says
  std::vector<std::string> set; // --set KEY=VALUE
  bool check = false;           // --check: print the resolved scenario, run nothing
};

int run_run_command(const RunCommand& c) {
  install_stop_handlers();
  RunOptions o;
  o.output_dir = c.out;
  if (c.threads >= 0) o.threads = c.threads;
  if (!c.resume.empty()) {
    if (!c.scenario.empty())
      throw InputError("scenario", c.scenario,
                       "not with --resume: the run continues with the scenario it was started "
                       "with (scenario.resolved.toml in its folder)");
    if (!c.set.empty() || c.check)
      throw InputError(c.check ? "--check" : "--set", c.check ? "given" : c.set.front(),
                       "not with --resume: the run continues with the scenario it was started "
                       "with (scenario.resolved.toml in its folder)");
    resume_run(c.resume, o); // refuses --out and --threads, naming them
    return 0;
  }
  if (c.scenario.empty())
    throw InputError("scenario", "(missing)", "a scenario file, or --resume RUN_DIR");
  const Scenario sc = load_scenario(c.scenario, c.set);
  cli::print_warnings(sc.warnings);
  if (c.check) {
    if (!c.out.empty()) check_output_folder(c.out, "--out");
    fmt::print("{}", resolved_toml(sc));
    fmt::print(stderr, "centridem run: {} checked; nothing run (--check)\n", c.scenario);
    return 0;
  }
  run_scenario(sc, o);
  return 0;
}

} // namespace

int main(int argc, char** argv) {
  cli::choose_openmp_wait(argv);
  CLI::App app{"centridem: 3D DEM for geotechnical centrifuge modelling"};
  app.require_subcommand(1);
  app.set_version_flag("--version", cli::version_string());

  BenchOptions bench;
  auto* cmd_bench = app.add_subcommand("bench", "throughput benchmark on the shared packing");
  cmd_bench->add_option("--packing", bench.packing, "packing file (x y z r per line, SI)")
      ->capture_default_str();
  cmd_bench->add_option("--steps", bench.steps, "timed steps")
      ->capture_default_str()
      ->check(cli::whole_number(1, 1'000'000'000));
  cmd_bench->add_option("--warmup", bench.warmup_steps, "untimed steps first")
      ->capture_default_str()
      ->check(cli::whole_number(0, 1'000'000'000));
  cmd_bench->add_option("--threads", bench.threads, "thread counts to run, one run each")
      ->capture_default_str()
      ->check(cli::whole_number(1, cli::kMaxThreads));
  cmd_bench
      ->add_option("--law", bench.law,
                   "contact law: paper (Table 1's ARRLM, E*-based) or peers (the peer "
                   "codes' kn = 5e4 N/m rolling law, bench/peers)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, BenchLaw>{{"paper", BenchLaw::paper}, {"peers", BenchLaw::peers}},
          CLI::ignore_case))
      ->default_str("paper");
  cmd_bench
      ->add_option("--workload", bench.workload,
                   "packed (the packing at rest in its box) or flowing (its left half "
                   "released at 600 g: a collapsing column; use about 1e5 --steps)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, BenchWorkload>{{"packed", BenchWorkload::packed},
                                               {"flowing", BenchWorkload::flowing}},
          CLI::ignore_case))
      ->default_str("packed");
  cmd_bench
      ->add_option("--skin", bench.skin_m,
                   "Verlet skin [m] (bench/peers' inputs use 5e-5); without it, the engine's "
                   "default: half the smallest radius")
      ->check(cli::positive_number(0.01));

  RunCommand run;
  add_generate_subcommand(app);  // runs itself from its callback
  add_shear_subcommand(app);     // likewise
  add_slope_subcommand(app);     // likewise
  add_render_subcommand(app);    // likewise
  add_calibrate_subcommand(app); // likewise

  auto* cmd_run = app.add_subcommand(
      "run", "run a staged scenario: particles, walls, gravity, stages of cycling "
             "(docs/scenario.md)");
  cmd_run->add_option("scenario", run.scenario, "scenario file (TOML)");
  cmd_run->add_option("--out", run.out,
                      "run folder (default: simulation.output_dir, else runs/<scenario stem>)");
  cmd_run->add_option("--resume", run.resume,
                      "continue the run in this folder from its last checkpoint (no scenario, "
                      "--out or --threads with it)");
  cli::add_threads_option(*cmd_run, run.threads,
                          "OpenMP threads, overrides simulation.threads (0 = the OpenMP default)");
  cli::add_set_option(*cmd_run, run.set);
  cli::add_check_flag(*cmd_run, run.check);

  // Exceptions map to exit codes in one place (cli::run_subcommand), as for
  // generate, shear and slope.
  cmd_bench->callback(
      [&bench] { cli::run_subcommand([&bench] { return run_bench_command(bench); }); });
  cmd_run->callback([&run] { cli::run_subcommand([&run] { return run_run_command(run); }); });

  cli::set_error_messages(app);
  if (const int rc = cli::check_subcommand(app, argc, argv); rc != 0) return rc;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }

  return 0;
}
