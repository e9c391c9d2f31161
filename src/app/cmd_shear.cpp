#include "app/cmd_shear.hpp"

#include "app/cli.hpp"
#include "app/jobs.hpp"

#include "base/errors.hpp"
#include "base/interrupt.hpp"
#include "engine/world.hpp"
#include "io/csv.hpp"
#include "io/output.hpp"
#include "io/plot.hpp"
#include "procedures/direct_shear.hpp"
#include "procedures/shear_config.hpp"
#include "procedures/specimen.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>

namespace centridem {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using cli::format_duration;
using cli::seconds_since;

namespace {

std::string kpa_label(double sigma_Pa) {
  return fmt::format("{:g}", sigma_Pa / 1000.0);
}
std::string run_stem(double sigma_Pa) {
  return shear_run_stem(sigma_Pa);
}

double angle_deg(double tau, double sigma) {
  return std::atan2(tau, sigma) * 180.0 / std::numbers::pi;
}

void write_text(const fs::path& path, const std::string& text) {
  write_text_file(path.string(), text);
}

fs::path checkpoint_path(const fs::path& out, double sigma_Pa) {
  return out / (run_stem(sigma_Pa) + ".checkpoint.bin");
}

// One pressure: builds the specimen into a fresh World (or reads the run's
// checkpoint), runs the test, writes shear_<kPa>kPa.csv and
// shear_<kPa>kPa.json (the result with its curve, read back by the parent;
// its presence marks the run finished).
void run_one(const ShearScenario& sc, double sigma, int threads, const fs::path& out,
             bool write_specimen, double progress_interval_s) {
  const auto t0 = Clock::now();
  const std::string tag = kpa_label(sigma) + " kPa";
  auto log = [&](std::string_view line) {
    fmt::print(stderr, "[{:7.1f} s] {}: {}\n", seconds_since(t0), tag, line);
    std::fflush(stderr);
  };
  if (fs::exists(out / (run_stem(sigma) + ".json"))) {
    log("finished earlier; read from " + (out / (run_stem(sigma) + ".json")).string());
    return;
  }
  WorldSettings ws;
  ws.local_damping = sc.local_damping;
  ws.threads = threads;
  World world(ws);
  const DirectShearSpec spec = sc.run_spec(sigma);
  auto last_consolidation_line = Clock::now();
  const DirectShearCheckpoints ck{
      checkpoint_path(out, sigma).string(),
      {sc.checkpoint_interval_min, 0},
      [&](const ConsolidationState& c) {
        if (seconds_since(last_consolidation_line) < progress_interval_s) return;
        last_consolidation_line = Clock::now();
        log(fmt::format("consolidating: step {}, sigma {:.1f} kPa (target {:g}), unbalanced-force "
                        "ratio {:.3g} (target {:.3g})",
                        c.steps, c.normal_stress_Pa / 1000, sigma / 1000, c.unbalanced_force_ratio,
                        spec.consolidation_ratio));
      }};
  if (fs::exists(ck.path)) {
    log("resuming from " + ck.path);
  } else {
    const BuiltSpecimen built = build_specimen(sc.specimen, world, log, threads);
    if (write_specimen)
      write_specimen_outputs(world, built, sc.specimen, (out / "specimen").string());
    world.set_local_damping(sc.local_damping);
    world.set_ball_ball_defaults(sc.ball_ball);
    world.set_body_field(BodyField::scaled_gravity(sc.g_level, 1.0));
    log(fmt::format("{} particles; consolidating to {:g} kPa", world.particles().size(),
                    sigma / 1000));
  }

  // Baseline of the rate: set at the first progress call, after any resumed
  // checkpoint has been read (the steps before it were not run by this process).
  auto last = Clock::now();
  long last_steps = -1;
  std::optional<std::pair<Clock::time_point, double>> first; // wall time, displacement
  // The curve so far, rewritten with every progress line: a long run can be
  // watched (and plotted) while it goes on.
  auto write_csv = [&](const std::vector<ShearPoint>& curve) {
    std::string csv = "step,time_s,shear_displacement_m,shear_strain,shear_stress_Pa,"
                      "normal_stress_Pa,vertical_displacement_m,porosity\n";
    for (const ShearPoint& p : curve)
      csv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", p.step, p.time_s,
                         p.shear_displacement_m, p.shear_strain, p.shear_stress_Pa,
                         p.normal_stress_Pa, p.vertical_displacement_m, p.porosity);
    const fs::path tmp = out / (run_stem(sigma) + ".csv.tmp");
    write_text(tmp, csv);
    fs::rename(tmp, out / (run_stem(sigma) + ".csv"));
  };
  const ShearProgress progress = [&](const ShearPoint& p, const DirectShearResult& r) {
    const auto now = Clock::now();
    if (last_steps < 0) {
      last = now;
      last_steps = world.step_count();
    }
    if (!first) {
      first = {now, p.shear_displacement_m};
      if (r.curve.size() == 1)
        log(fmt::format("consolidated in {} steps (sigma {:.1f} kPa, height {:.3f} mm, porosity "
                        "{:.3f}, coordination {:.2f}, affine modulus {:.1f} MPa); shearing",
                        r.consolidation_steps, r.consolidated_normal_stress_Pa / 1000,
                        r.consolidated_height_m * 1e3, r.consolidated_porosity,
                        r.consolidated_coordination_number,
                        r.consolidated_affine_modulus_Pa / 1e6));
      if (r.unload_reload.done)
        log(fmt::format("unload-reload {:.1f} -> {:.1f} -> {:.1f} kPa in {} steps: constrained "
                        "modulus {:.1f} MPa unloading, {:.1f} MPa reloading",
                        r.unload_reload.loaded_normal_stress_Pa / 1000,
                        r.unload_reload.unloaded_normal_stress_Pa / 1000,
                        r.unload_reload.reloaded_normal_stress_Pa / 1000, r.unload_reload.steps,
                        r.unload_reload.unloading_modulus_Pa() / 1e6,
                        r.unload_reload.reloading_modulus_Pa() / 1e6));
    }
    const double dt = std::chrono::duration<double>(now - last).count();
    if (dt < progress_interval_s) return;
    const double rate = static_cast<double>(world.particles().size()) *
                        static_cast<double>(world.step_count() - last_steps) / dt;
    const double done = p.shear_displacement_m - first->second;
    const double eta = done > 0 ? std::chrono::duration<double>(now - first->first).count() / done *
                                      (spec.max_shear_displacement_m - p.shear_displacement_m)
                                : -1;
    log(fmt::format("shear {:.3f} / {:.3f} mm, tau {:.1f} kPa, sigma {:.1f} kPa, {:.3g} "
                    "particle-steps/s, ETA {}",
                    p.shear_displacement_m * 1e3, spec.max_shear_displacement_m * 1e3,
                    p.shear_stress_Pa / 1000, p.normal_stress_Pa / 1000, rate,
                    format_duration(eta)));
    last = now;
    last_steps = world.step_count();
    write_csv(r.curve);
  };
  const DirectShearResult r = run_direct_shear(world, spec, progress, ck);

  nlohmann::json curve = nlohmann::json::array();
  for (const ShearPoint& p : r.curve)
    curve.push_back({p.shear_strain, p.shear_stress_Pa, p.vertical_displacement_m});
  write_csv(r.curve);
  nlohmann::json j = {{"normal_stress_target_Pa", r.target_normal_stress_Pa},
                      {"particles", world.particles().size()},
                      {"consolidation_steps", r.consolidation_steps},
                      {"consolidated_height_m", r.consolidated_height_m},
                      {"consolidated_normal_stress_Pa", r.consolidated_normal_stress_Pa},
                      {"consolidated_porosity", r.consolidated_porosity},
                      {"consolidated_coordination_number", r.consolidated_coordination_number},
                      {"consolidated_affine_modulus_Pa", r.consolidated_affine_modulus_Pa},
                      {"settling_steps", r.settling_steps},
                      {"shear_steps", r.curve.empty() ? 0L
                                                      : r.curve.back().step - r.curve.front().step +
                                                            spec.record_interval_steps},
                      {"peak_shear_stress_Pa", r.peak_shear_stress_Pa},
                      {"peak_strain", r.peak_strain},
                      {"residual_shear_stress_Pa", r.residual_shear_stress_Pa},
                      {"peak_friction_angle_deg", angle_deg(r.peak_shear_stress_Pa, sigma)},
                      {"residual_friction_angle_deg", angle_deg(r.residual_shear_stress_Pa, sigma)},
                      {"worst_normal_stress_deviation", r.worst_normal_stress_deviation},
                      {"particles_lost", r.particles_lost},
                      {"wall_seconds", r.wall_seconds},
                      {"particle_steps_per_s", r.particle_steps_per_s},
                      {"resumed", r.resumed},
                      {"curve_strain_tau_dz", curve}};
  if (r.unload_reload.done) {
    const UnloadReload& u = r.unload_reload;
    j["unload_reload"] = {{"loaded_height_m", u.loaded_height_m},
                          {"loaded_normal_stress_Pa", u.loaded_normal_stress_Pa},
                          {"unloaded_height_m", u.unloaded_height_m},
                          {"unloaded_normal_stress_Pa", u.unloaded_normal_stress_Pa},
                          {"reloaded_height_m", u.reloaded_height_m},
                          {"reloaded_normal_stress_Pa", u.reloaded_normal_stress_Pa},
                          {"steps", u.steps},
                          {"unloading_modulus_Pa", u.unloading_modulus_Pa()},
                          {"reloading_modulus_Pa", u.reloading_modulus_Pa()}};
  }
  const fs::path tmp = out / (run_stem(sigma) + ".json.tmp");
  write_text(tmp, j.dump(1) + "\n");
  fs::rename(tmp, out / (run_stem(sigma) + ".json")); // the run is finished once this exists
  log(fmt::format(
      "done: peak {:.1f} kPa ({:.1f} deg) at strain {:.3f}, residual {:.1f} kPa "
      "({:.1f} deg), worst sigma deviation {:.1f} %, {} lost, {}",
      r.peak_shear_stress_Pa / 1000, angle_deg(r.peak_shear_stress_Pa, sigma), r.peak_strain,
      r.residual_shear_stress_Pa / 1000, angle_deg(r.residual_shear_stress_Pa, sigma),
      100 * r.worst_normal_stress_deviation, r.particles_lost, format_duration(seconds_since(t0))));
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("missing run result " + path.string());
  return nlohmann::json::parse(in);
}

// The curve so far of an unfinished run, from the shear_<kPa>kPa.csv that the
// run rewrites with every progress line: strain, shear stress [Pa], vertical
// displacement [m] per row. Empty when there is no CSV yet. A CSV whose header
// is not the one run_one writes is an error naming the file.
struct PartialCurve {
  std::vector<std::array<double, 3>> strain_tau_dz;
  double shear_displacement_m = 0;
};
PartialCurve read_partial_curve(const fs::path& csv) {
  PartialCurve c;
  std::ifstream in(csv);
  if (!in) return c;
  std::string line;
  std::getline(in, line);
  const std::string header = "step,time_s,shear_displacement_m,shear_strain,shear_stress_Pa,"
                             "normal_stress_Pa,vertical_displacement_m,porosity";
  if (line != header)
    throw InputError(csv.string() + " line 1", "\"" + line + "\"", "the header \"" + header + "\"");
  long n = 1;
  while (std::getline(in, line)) {
    ++n;
    if (trim_blanks(line).empty()) continue;
    const std::vector<std::string_view> f = split_commas(line);
    if (f.size() != 8)
      throw InputError(fmt::format("{} line {}", csv.string(), n), "\"" + line + "\"",
                       fmt::format("8 comma-separated numbers, found {}", f.size()));
    std::array<double, 8> v{};
    for (std::size_t k = 0; k < v.size(); ++k)
      v[k] = parse_finite_number(f[k], fmt::format("{} line {} column {}", csv.string(), n, k + 1));
    c.strain_tau_dz.push_back({v[3], v[4], v[6]});
    c.shear_displacement_m = v[2];
  }
  return c;
}

void write_plots(const ShearScenario& sc, const std::vector<double>& sigmas,
                 const std::vector<nlohmann::json>& runs,
                 const std::vector<std::pair<double, PartialCurve>>& unfinished,
                 const fs::path& out, const MohrCoulombFit& peak, const MohrCoulombFit& residual) {
  const bool by_height = sc.test.strain == StrainDefinition::height;
  const std::string strain_label =
      by_height ? "shear strain = δ / H (%)" : "shear strain = δ / L (%)";
  LinePlot tau, dz;
  tau.title = "Shear stress";
  tau.x_label = strain_label;
  tau.y_label = "shear stress τ (kPa)";
  dz.title = "Vertical displacement (+ dilation)";
  dz.x_label = strain_label;
  dz.y_label = "vertical displacement (mm)";
  for (std::size_t k = 0; k < runs.size(); ++k) {
    std::vector<double> x, y, v;
    for (const auto& p : runs[k]["curve_strain_tau_dz"]) {
      x.push_back(100 * p[0].get<double>());
      y.push_back(p[1].get<double>() / 1000);
      v.push_back(p[2].get<double>() * 1000);
    }
    const std::string name = "σn = " + kpa_label(sigmas[k]) + " kPa";
    tau.add(name, x, y).with_colour(palette_colour(k));
    dz.add(name, x, v).with_colour(palette_colour(k));
  }
  for (std::size_t k = 0; k < unfinished.size(); ++k) {
    const auto& [sigma, c] = unfinished[k];
    if (c.strain_tau_dz.empty()) continue;
    std::vector<double> x, y, v;
    for (const auto& p : c.strain_tau_dz) {
      x.push_back(100 * p[0]);
      y.push_back(p[1] / 1000);
      v.push_back(p[2] * 1000);
    }
    const std::string name = fmt::format("σn = {} kPa (unfinished, δ = {:.2f} mm)",
                                         kpa_label(sigma), c.shear_displacement_m * 1000);
    const std::size_t colour = runs.size() + k;
    tau.add(name, x, y).dashed_line().with_colour(palette_colour(colour));
    dz.add(name, x, v).dashed_line().with_colour(palette_colour(colour));
  }
  render_panels((out / "shear_curves.png").string(), {tau, dz}, 2);
  if (runs.empty()) return; // no peak yet to put on the Mohr-Coulomb plane

  LinePlot mc;
  mc.title = "Mohr-Coulomb envelopes";
  mc.x_label = "normal stress σn (kPa)";
  mc.y_label = "shear stress τ (kPa)";
  std::vector<double> s, tp, tr;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    s.push_back(sigmas[k] / 1000);
    tp.push_back(runs[k]["peak_shear_stress_Pa"].get<double>() / 1000);
    tr.push_back(runs[k]["residual_shear_stress_Pa"].get<double>() / 1000);
  }
  const double smax = *std::max_element(s.begin(), s.end()) * 1.1;
  mc.add("peak", s, tp).markers_only(Marker::circle).with_colour(palette_colour(0));
  mc.add("residual", s, tr).markers_only(Marker::square).with_colour(palette_colour(1));
  if (runs.size() >= 2) {
    auto line = [&](const MohrCoulombFit& f) {
      const double t = std::tan(f.friction_angle_deg * std::numbers::pi / 180);
      return std::vector<double>{f.cohesion_Pa / 1000, f.cohesion_Pa / 1000 + t * smax};
    };
    mc.add(fmt::format("peak fit: c = {:.1f} kPa, φ = {:.1f}°", peak.cohesion_Pa / 1000,
                       peak.friction_angle_deg),
           {0, smax}, line(peak))
        .with_colour(palette_colour(0));
    mc.add(fmt::format("residual fit: c = {:.1f} kPa, φ = {:.1f}°", residual.cohesion_Pa / 1000,
                       residual.friction_angle_deg),
           {0, smax}, line(residual))
        .dashed_line()
        .with_colour(palette_colour(1));
  }
  mc.x_range = AxisRange{0, smax};
  mc.legend = LegendPlace::upper_left;
  mc.render((out / "mohr_coulomb.png").string(), 800, 600);
}

} // namespace

std::string shear_run_stem(double normal_stress_Pa) {
  return "shear_" + kpa_label(normal_stress_Pa) + "kPa";
}

int run_shear_command(const ShearCommandOptions& o) {
  const auto t0 = Clock::now();
  install_stop_handlers();
  if (o.jobs < 1) throw InputError("--jobs", std::to_string(o.jobs), "must be >= 1");
  ShearScenario sc;
  std::vector<double> sigmas;
  fs::path out;
  int jobs_wanted = o.jobs, threads_wanted = o.threads; // --resume: the started run's
  const bool report_only = !o.report_dir.empty();
  if (report_only && !o.resume_dir.empty())
    throw InputError("--report", o.report_dir, "either --report or --resume, not both");
  if (!o.resume_dir.empty() || report_only) {
    const std::string flag = report_only ? "--report" : "--resume";
    out = report_only ? o.report_dir : o.resume_dir;
    if (!o.scenario.empty() || !o.out_dir.empty() || !o.pressures_kPa.empty() || !o.set.empty() ||
        o.check)
      throw InputError(flag, out.string(),
                       "works on a run folder as it was started: give no scenario, --out, "
                       "--pressure, --set or --check with it");
    if (!fs::exists(out / "scenario.toml") || !fs::exists(out / "pressures.json"))
      throw InputError(flag, out.string(),
                       "not a shear run folder (scenario.toml and pressures.json missing)");
    sc = load_shear_scenario((out / "scenario.toml").string());
    try {
      const nlohmann::json started = read_json(out / "pressures.json");
      sigmas = started.at("normal_stresses_Pa").get<std::vector<double>>();
      // A resume runs as the run was started unless the command line says otherwise (folders
      // written before these two keys existed resume with the defaults).
      if (!o.jobs_given && started.contains("jobs"))
        jobs_wanted = std::max(1, started.at("jobs").get<int>());
      if (o.threads < 0 && started.contains("threads_per_run"))
        threads_wanted = std::max(0, started.at("threads_per_run").get<int>());
    } catch (const nlohmann::json::exception& e) {
      throw InputError(flag, (out / "pressures.json").string(),
                       std::string("a pressures.json written by centridem shear (") + e.what() +
                           ")");
    }
    for (double s : sigmas) validate(sc.run_spec(s));
    if (!report_only) fmt::print(stderr, "centridem shear: resuming {}\n", out.string());
  } else {
    if (o.scenario.empty())
      throw InputError("scenario", "(missing)", "a scenario file, or --resume RUN_DIR");
    sc = load_shear_scenario(o.scenario, o.set);
    cli::print_warnings(sc.specimen.warnings);
    sigmas = sc.normal_stresses_Pa;
    if (!o.pressures_kPa.empty()) {
      sigmas.clear();
      for (double p : o.pressures_kPa) {
        if (!(p > 0) || !(p <= 1e6))
          throw InputError("--pressure", fmt::format("{:g}", p), "a normal stress in (0, 1e6] kPa");
        sigmas.push_back(p * 1000);
        validate(sc.run_spec(sigmas.back()));
      }
    }
    // Each pressure's files are named by its label (shear_<kPa>kPa.*): two
    // runs with one label would write over each other.
    for (std::size_t i = 0; i < sigmas.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (kpa_label(sigmas[i]) == kpa_label(sigmas[j]))
          throw InputError(o.pressures_kPa.empty() ? "shear.normal_stresses_Pa" : "--pressure",
                           kpa_label(sigmas[i]) + " kPa (given twice)",
                           "each normal pressure once, as files are named by it (shear_" +
                               kpa_label(sigmas[i]) + "kPa.*)");
    std::string out_s = o.out_dir;
    if (out_s.empty()) {
      std::string stem = fs::path(o.scenario).stem().string();
      if (stem.empty()) stem = "scenario";
      out_s = "runs/" + stem + "_shear";
    }
    out = out_s;
    if (o.check) {
      check_output_folder(out.string(), "--out");
      fmt::print("{}", resolved_shear_toml(sc));
      fmt::print(stderr, "centridem shear: {} checked, {} pressure(s); nothing run (--check)\n",
                 o.scenario, sigmas.size());
      return 0;
    }
    make_directories(out.string());
    for (double s : sigmas)
      if (fs::exists(checkpoint_path(out, s)))
        throw InputError("--out", out.string(),
                         "holds an unfinished shear run (" + checkpoint_path(out, s).string() +
                             "): continue it with `centridem shear --resume " + out.string() +
                             "`, or choose another folder");
    for (double s : sigmas) fs::remove(out / (run_stem(s) + ".json")); // stale results
    write_text(out / "scenario.toml", resolved_shear_toml(sc));
    write_text(out / "pressures.json",
               nlohmann::json{{"normal_stresses_Pa", sigmas},
                              {"jobs", o.jobs},
                              {"threads_per_run", o.threads >= 0 ? o.threads : sc.threads}}
                       .dump(1) +
                   "\n");
  }
  const int threads = threads_wanted >= 0 ? threads_wanted : sc.threads;
  const int jobs = std::min<int>(jobs_wanted, static_cast<int>(sigmas.size()));
  if (!report_only)
    fmt::print(
        stderr,
        "centridem shear: {} pressure(s) [{}] kPa, {} job(s), {} thread(s) per run, "
        "output {}\n",
        sigmas.size(),
        [&] {
          std::string l;
          for (double s : sigmas) l += (l.empty() ? "" : ", ") + kpa_label(s);
          return l;
        }(),
        jobs, threads == 0 ? std::string("default") : std::to_string(threads), out.string());
  std::fflush(stderr);

  int failed_rc = 0;
  if (!report_only) {
    const std::vector<int> codes = run_jobs(
        sigmas.size(), jobs,
        [&](std::size_t k) { run_one(sc, sigmas[k], threads, out, k == 0, o.progress_interval_s); },
        [&](std::size_t k) { return "the " + kpa_label(sigmas[k]) + " kPa run"; });
    for (int code : codes)
      if (code > 0 && failed_rc == 0) failed_rc = code;
  }
  if (stop_signal() && failed_rc == 0) failed_rc = 128 + stop_signal();
  const bool interrupted = failed_rc > 128;

  // Collect, by rising normal stress whatever order the runs went in (the
  // summary, the table and the plot legends read upwards).
  std::vector<double> by_pressure = sigmas;
  std::sort(by_pressure.begin(), by_pressure.end());
  std::vector<double> done_sigmas;
  std::vector<nlohmann::json> runs;
  std::vector<std::pair<double, PartialCurve>> unfinished; // curves so far, plotted dashed
  for (double s : by_pressure) {
    const fs::path p = out / (run_stem(s) + ".json");
    if (!fs::exists(p)) {
      unfinished.emplace_back(s, read_partial_curve(out / (run_stem(s) + ".csv")));
      continue;
    }
    done_sigmas.push_back(s);
    runs.push_back(read_json(p));
  }
  const bool any_curve = std::any_of(unfinished.begin(), unfinished.end(),
                                     [](const auto& u) { return !u.second.strain_tau_dz.empty(); });
  if (runs.empty() && !(report_only && any_curve)) {
    if (report_only)
      throw InputError("--report", out.string(), "holds no finished run and no curve yet");
    if (interrupted) {
      if (o.resume_hint)
        fmt::print(stderr,
                   "centridem shear: interrupted; continue with `centridem shear --resume {}`\n",
                   out.string());
      return failed_rc;
    }
    if (failed_rc == 3) throw InstabilityError("every run failed (see the messages above)");
    throw std::runtime_error("no run finished (see the messages above)");
  }
  std::vector<double> tp, tr;
  for (const auto& r : runs) {
    tp.push_back(r["peak_shear_stress_Pa"].get<double>());
    tr.push_back(r["residual_shear_stress_Pa"].get<double>());
  }
  const MohrCoulombFit peak = fit_mohr_coulomb(done_sigmas, tp);
  const MohrCoulombFit residual = fit_mohr_coulomb(done_sigmas, tr);
  write_plots(sc, done_sigmas, runs, unfinished, out, peak, residual);

  nlohmann::json summary;
  summary["scenario"] = report_only ? (out / "scenario.toml").string() : o.scenario;
  summary["box_m"] = {sc.test.box.length_m, sc.test.box.width_m, sc.test.box.height_m};
  summary["strain"] = sc.test.strain == StrainDefinition::height ? "height" : "length";
  summary["shear_rate_m_per_s"] = sc.test.shear_rate_m_per_s;
  summary["max_shear_displacement_m"] = sc.test.max_shear_displacement_m;
  summary["jobs"] = jobs;
  summary["threads_per_run"] = threads;
  summary["wall_seconds"] = seconds_since(t0);
  nlohmann::json list = nlohmann::json::array();
  for (const auto& r : runs) {
    nlohmann::json e = r;
    e.erase("curve_strain_tau_dz");
    e["curve_csv"] = run_stem(r["normal_stress_target_Pa"].get<double>()) + ".csv";
    list.push_back(e);
  }
  summary["runs"] = list;
  auto fit_json = [&](const MohrCoulombFit& f) -> nlohmann::json {
    if (runs.size() < 2) return nullptr;
    return {{"cohesion_Pa", f.cohesion_Pa},
            {"friction_angle_deg", f.friction_angle_deg},
            {"r_squared", f.r_squared}};
  };
  summary["mohr_coulomb"] = {{"peak", fit_json(peak)}, {"residual", fit_json(residual)}};
  summary["unfinished_Pa"] = [&] {
    std::vector<double> u;
    for (const auto& [s, c] : unfinished) u.push_back(s);
    return u;
  }();
  summary["unfinished_shear_displacement_m"] = [&] {
    std::vector<double> u;
    for (const auto& [s, c] : unfinished) u.push_back(c.shear_displacement_m);
    return u;
  }();
  write_text(out / "summary.json", summary.dump(2) + "\n");

  if (!runs.empty())
    fmt::print("{:>8} {:>10} {:>9} {:>10} {:>10} {:>9} {:>8} {:>5}\n", "sigma", "peak", "phi_peak",
               "strain_pk", "residual", "phi_res", "sig_dev", "lost");
  for (const auto& r : runs)
    fmt::print(
        "{:>5g} kPa {:>6.1f} kPa {:>7.1f}° {:>10.3f} {:>6.1f} kPa {:>7.1f}° {:>7.1f}% {:>5}\n",
        r["normal_stress_target_Pa"].get<double>() / 1000,
        r["peak_shear_stress_Pa"].get<double>() / 1000, r["peak_friction_angle_deg"].get<double>(),
        r["peak_strain"].get<double>(), r["residual_shear_stress_Pa"].get<double>() / 1000,
        r["residual_friction_angle_deg"].get<double>(),
        100 * r["worst_normal_stress_deviation"].get<double>(), r["particles_lost"].get<long>());
  if (runs.size() >= 2)
    fmt::print("Mohr-Coulomb peak: c = {:.2f} kPa, phi = {:.2f} deg (R^2 {:.3f}); residual: c = "
               "{:.2f} kPa, phi = {:.2f} deg (R^2 {:.3f})\n",
               peak.cohesion_Pa / 1000, peak.friction_angle_deg, peak.r_squared,
               residual.cohesion_Pa / 1000, residual.friction_angle_deg, residual.r_squared);
  for (const auto& [s, c] : unfinished)
    if (c.strain_tau_dz.empty())
      fmt::print("{:>5g} kPa not sheared yet\n", s / 1000);
    else
      fmt::print("{:>5g} kPa unfinished: {:.3f} of {:.3f} mm sheared so far\n", s / 1000,
                 c.shear_displacement_m * 1000, sc.test.max_shear_displacement_m * 1000);
  fmt::print("wrote {}/summary.json, shear_curves.png{}, shear_<kPa>kPa.csv, "
             "scenario.toml ({})\n",
             out.string(), runs.empty() ? "" : ", mohr_coulomb.png",
             format_duration(seconds_since(t0)));
  std::fflush(stdout);
  if (interrupted) {
    if (o.resume_hint)
      fmt::print(stderr,
                 "centridem shear: interrupted with {} of {} runs finished; continue with "
                 "`centridem shear --resume {}`\n",
                 runs.size(), sigmas.size(), out.string());
    return failed_rc;
  }
  if (failed_rc != 0) {
    fmt::print(stderr, "centridem shear: {} of {} runs failed\n", sigmas.size() - runs.size(),
               sigmas.size());
    return failed_rc;
  }
  return 0;
}

CLI::App* add_shear_subcommand(CLI::App& app) {
  auto o = std::make_shared<ShearCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "shear", "numerical direct shear tests, one per normal pressure (docs/shear.md)");
  cmd->add_option("scenario", o->scenario,
                  "scenario file (TOML) with [specimen], [contact.ball_ball] and [shear]");
  cmd->add_option("--out", o->out_dir, "output folder (default: runs/<scenario stem>_shear)");
  cmd->add_option(
      "--resume", o->resume_dir,
      "continue the runs in this folder from their last checkpoints (with the --jobs and "
      "--threads they were started with, unless given again)");
  cmd->add_option("--report", o->report_dir,
                  "run nothing: rewrite the summary and plots of this run folder from what it "
                  "holds now (unfinished runs' curves so far drawn dashed, not in the fits)");
  cli::add_jobs_option(*cmd, o->jobs, "pressures run at once, as child processes (default 1)");
  cmd->add_option(
      "--pressure", o->pressures_kPa,
      "run only this normal pressure [kPa] (repeatable; default: shear.normal_stresses_Pa)");
  cmd->add_option("--progress", o->progress_interval_s, "seconds between progress lines")
      ->check(cli::positive_number());
  cli::add_threads_option(*cmd, o->threads,
                          "OpenMP threads per run (default: shear.threads; 0 = the OpenMP "
                          "default)");
  cli::add_set_option(*cmd, o->set);
  cli::add_check_flag(*cmd, o->check);
  cmd->callback([o, cmd]() {
    o->jobs_given = cmd->count("--jobs") > 0;
    cli::run_subcommand([o] { return run_shear_command(*o); },
                        [o] {
                          fmt::print(stderr,
                                     "centridem shear: continue with `centridem shear --resume "
                                     "{}`\n",
                                     o->resume_dir.empty()
                                         ? (o->out_dir.empty() ? "RUN_DIR" : o->out_dir)
                                         : o->resume_dir);
                        });
  });
  return cmd;
}

} // namespace centridem
