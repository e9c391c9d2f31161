#include "app/cmd_calibrate.hpp"

#include "app/calibrate_evaluation.hpp"
#include "app/cli.hpp"
#include "app/cmd_shear.hpp"

#include "base/errors.hpp"
#include "base/interrupt.hpp"
#include "io/csv.hpp"
#include "io/output.hpp"
#include "io/plot.hpp"
#include "io/toml_read.hpp"
#include "procedures/calibration.hpp"
#include "procedures/calibration_config.hpp"
#include "procedures/direct_shear.hpp"
#include "procedures/shear_config.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>

namespace centridem {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using cli::format_duration;
using cli::seconds_since;

namespace {

// Every file the calibration writes is replaced whole (a temporary file
// renamed over it), so a stopped run never leaves half a file.
void write_text(const fs::path& path, const std::string& text) {
  replace_text_file(path.string(), text);
}

std::string read_text(const fs::path& path, const std::string& flag) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(flag, path.parent_path().string(),
                     "a calibration folder written by centridem calibrate (" + path.string() +
                         " missing)");
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string values_text(const CalibrationStage& st, const std::vector<double>& v) {
  std::string s;
  for (std::size_t k = 0; k < st.parameters.size() && k < v.size(); ++k) {
    std::string key = st.parameters[k].key;
    if (const auto dot = key.rfind('.'); dot != std::string::npos) key = key.substr(dot + 1);
    s += fmt::format("{}{} = {:.4g}", k ? ", " : "", key, v[k]);
  }
  return s;
}

// ---- pictures ---------------------------------------------------------------

void plot_misfit(const CalibrationStage& st, const std::vector<Evaluation>& h,
                 const fs::path& png) {
  LinePlot p;
  p.title = "Calibration, stage " + st.name + ": misfit of each evaluation";
  p.x_label = "evaluation";
  p.y_label = "misfit (" + st.misfit_unit() + ")";
  std::vector<double> x, y, bx, by;
  double best = std::numeric_limits<double>::infinity();
  for (const Evaluation& e : h) {
    if (!std::isfinite(e.misfit)) continue;
    x.push_back(e.index);
    y.push_back(e.misfit);
    best = std::min(best, e.misfit);
    bx.push_back(e.index);
    by.push_back(best);
  }
  if (x.empty()) return;
  p.add("each evaluation", x, y).markers_only(Marker::circle).with_colour(palette_colour(0));
  p.add("best so far", bx, by).with_colour(palette_colour(1));
  if (st.optimiser.tolerance > 0)
    p.add(fmt::format("tolerance {:g}", st.optimiser.tolerance), {x.front(), x.back()},
          {st.optimiser.tolerance, st.optimiser.tolerance})
        .dashed_line()
        .with_colour(palette_colour(2));
  p.y_range =
      AxisRange{0, std::max(*std::max_element(y.begin(), y.end()), st.optimiser.tolerance) * 1.05};
  p.render(png.string(), 900, 550);
}

void plot_curves(const CalibrationStage& st, const fs::path& run, const Evaluation& best,
                 const fs::path& png) {
  const std::string title = fmt::format("Stage {}: best evaluation {} ({})", st.name, best.index,
                                        values_text(st, best.values));
  if (st.kind == CalibrationTargetKind::curves) {
    LinePlot tau, dz;
    tau.title = title;
    tau.x_label = "shear strain (%)";
    tau.y_label = "shear stress τ (kPa)";
    dz.title = "Vertical displacement (+ dilation)";
    dz.x_label = tau.x_label;
    dz.y_label = "vertical displacement (mm)";
    bool any_dz = false;
    for (std::size_t k = 0; k < st.curves.size(); ++k) {
      const MeasuredCurve& m = st.curves[k];
      const SimulatedCurve s = evaluation_curve(st, run, m.normal_stress_Pa);
      auto pct = [](std::vector<double> v) {
        for (double& x : v) x *= 100;
        return v;
      };
      auto scaled = [](std::vector<double> v, double f) {
        for (double& x : v) x *= f;
        return v;
      };
      tau.add("measured " + kpa_text(m.normal_stress_Pa) + " kPa", pct(m.strain),
              scaled(m.shear_stress_Pa, 1e-3))
          .markers_only(Marker::circle)
          .with_colour(palette_colour(k));
      tau.add("simulated " + kpa_text(m.normal_stress_Pa) + " kPa", pct(s.strain),
              scaled(s.shear_stress_Pa, 1e-3))
          .with_colour(palette_colour(k));
      if (!m.vertical_displacement_m.empty()) {
        any_dz = true;
        dz.add("measured " + kpa_text(m.normal_stress_Pa) + " kPa", pct(m.strain),
               scaled(m.vertical_displacement_m, 1e3))
            .markers_only(Marker::circle)
            .with_colour(palette_colour(k));
      }
      dz.add("simulated " + kpa_text(m.normal_stress_Pa) + " kPa", pct(s.strain),
             scaled(s.vertical_displacement_m, 1e3))
          .with_colour(palette_colour(k));
    }
    (void)any_dz;
    render_panels(png.string(), {tau, dz}, 2, 800, 550);
    return;
  }
  // Peak targets: the Mohr-Coulomb plane, target and simulated.
  LinePlot mc;
  mc.title = title;
  mc.x_label = "normal stress σn (kPa)";
  mc.y_label = "peak shear stress τ (kPa)";
  std::vector<double> s, tp;
  for (double sig : st.normal_stresses_Pa) {
    const SimulatedCurve c = evaluation_curve(st, run, sig);
    s.push_back(sig / 1e3);
    tp.push_back(*std::max_element(c.shear_stress_Pa.begin(), c.shear_stress_Pa.end()) / 1e3);
  }
  const double smax = s.back() * 1.1;
  mc.add("simulated peaks", s, tp).markers_only(Marker::circle).with_colour(palette_colour(0));
  if (st.kind == CalibrationTargetKind::mohr_coulomb) {
    const double t = std::tan(st.mohr_coulomb.friction_angle_deg * std::acos(-1.0) / 180);
    const double c = st.mohr_coulomb.cohesion_Pa / 1e3;
    mc.add(fmt::format("target: c = {:g} kPa, φ = {:g}°", c, st.mohr_coulomb.friction_angle_deg),
           {0, smax}, {c, c + t * smax})
        .dashed_line()
        .with_colour(palette_colour(1));
    std::vector<double> sp;
    for (double x : s) sp.push_back(x * 1e3);
    std::vector<double> tpp;
    for (double x : tp) tpp.push_back(x * 1e3);
    const MohrCoulombFit f = fit_mohr_coulomb(sp, tpp);
    const double tf = std::tan(f.friction_angle_deg * std::acos(-1.0) / 180);
    mc.add(fmt::format("simulated fit: c = {:.2f} kPa, φ = {:.2f}°", f.cohesion_Pa / 1e3,
                       f.friction_angle_deg),
           {0, smax}, {f.cohesion_Pa / 1e3, f.cohesion_Pa / 1e3 + tf * smax})
        .with_colour(palette_colour(0));
  } else {
    std::vector<double> m;
    for (double v : st.peak_shear_stress_Pa) m.push_back(v / 1e3);
    mc.add("measured peaks", s, m).markers_only(Marker::square).with_colour(palette_colour(1));
  }
  mc.x_range = AxisRange{0, smax};
  mc.legend = LegendPlace::upper_left;
  mc.render(png.string(), 900, 600);
}

} // namespace

int run_calibrate_command(const CalibrateCommandOptions& o) {
  const auto t0 = Clock::now();
  install_stop_handlers();
  CalibrationScenario cal;
  fs::path out;
  if (!o.resume_dir.empty()) {
    out = o.resume_dir;
    if (!o.scenario.empty() || !o.out_dir.empty() || !o.set.empty() || o.check)
      throw InputError("--resume", out.string(),
                       "works on a calibration folder as it was started: give no scenario, "
                       "--out, --set or --check with it");
    const std::string text = read_text(out / "calibration.toml", "--resume");
    nlohmann::json where;
    try {
      where = nlohmann::json::parse(read_text(out / "calibration.json", "--resume"));
      cal = parse_calibration(text, where.at("source").get<std::string>(),
                              where.at("base_dir").get<std::string>());
    } catch (const nlohmann::json::exception& e) {
      throw InputError("--resume", (out / "calibration.json").string(),
                       std::string("a calibration.json written by centridem calibrate (") +
                           e.what() + ")");
    }
    fmt::print(stderr, "centridem calibrate: resuming {}\n", out.string());
  } else {
    if (o.scenario.empty())
      throw InputError("scenario", "(missing)", "a calibration scenario file, or --resume DIR");
    cal = load_calibration(o.scenario, o.set);
    std::string out_s = o.out_dir;
    if (out_s.empty()) {
      std::string stem = fs::path(o.scenario).stem().string();
      if (stem.empty()) stem = "scenario";
      out_s = "runs/" + stem + "_calibrate";
    }
    out = out_s;
    if (o.check) {
      check_output_folder(out.string(), "--out");
      for (const CalibrationStage& st : cal.stages) {
        fmt::print(
            "stage {}: {} parameter(s), target {}, {} pressure(s) [{}] kPa, budget {}, "
            "tolerance {:g} {}\n",
            st.name, st.parameters.size(),
            st.kind == CalibrationTargetKind::curves         ? "measured curves"
            : st.kind == CalibrationTargetKind::mohr_coulomb ? "Mohr-Coulomb envelope"
                                                             : "peak shear stresses",
            st.normal_stresses_Pa.size(),
            [&] {
              std::string l;
              for (double s : st.normal_stresses_Pa) l += (l.empty() ? "" : ", ") + kpa_text(s);
              return l;
            }(),
            st.optimiser.budget, st.optimiser.tolerance, st.misfit_unit());
        for (const CalibrationParameter& p : st.parameters)
          fmt::print("  {} in [{:g}, {:g}] from {:g}{}\n", p.key, p.min, p.max, p.start,
                     p.log_scale ? " (log scale)" : "");
      }
      std::fflush(stdout);
      fmt::print(stderr, "centridem calibrate: {} checked, {} stage(s); nothing run (--check)\n",
                 o.scenario, cal.stages.size());
      return 0;
    }
    if (fs::exists(out / "calibration.toml"))
      throw InputError("--out", out.string(),
                       "holds a calibration already: continue it with `centridem calibrate "
                       "--resume " +
                           out.string() + "`, or choose another folder");
    make_directories(out.string());
    write_text(out / "calibration.toml", cal.text);
    write_text(
        out / "calibration.json",
        nlohmann::json{
            {"source", cal.source},
            {"base_dir",
             fs::absolute(cal.base_dir.empty() ? "." : cal.base_dir).lexically_normal().string()}}
                .dump(1) +
            "\n");
  }

  std::vector<std::string> earlier; // fitted values of the stages done, KEY = VALUE
  nlohmann::json stages_json = nlohmann::json::array();
  for (const CalibrationStage& st : cal.stages) {
    const auto ts = Clock::now();
    const fs::path dir = out / st.name;
    make_directories(dir.string());
    const fs::path history_csv = dir / "history.csv";
    const std::vector<Evaluation> recorded = read_history(history_csv, st);
    if (recorded.empty()) write_text(history_csv, history_header(st) + "\n");
    fmt::print(stderr,
               "centridem calibrate: stage {} ({} parameter(s), {} pressure(s), budget {}, "
               "tolerance {:g} {}){}\n",
               st.name, st.parameters.size(), st.normal_stresses_Pa.size(), st.optimiser.budget,
               st.optimiser.tolerance, st.misfit_unit(),
               recorded.empty() ? "" : fmt::format("; {} evaluation(s) recorded", recorded.size()));
    std::fflush(stderr);

    double new_seconds = 0;
    int new_count = 0;
    const Evaluator evaluate = [&](int index, const std::vector<double>& values) {
      const auto te = Clock::now();
      const std::string name = fmt::format("eval_{:03d}", index);
      const fs::path run = dir / name;
      // One shear run (of the evaluation, or of one replicate): started,
      // or continued where a stopped calibration left it.
      auto shear = [&](const fs::path& folder, const fs::path& input,
                       const std::vector<std::string>& replicate) {
        ShearCommandOptions so;
        so.jobs = o.jobs;
        so.threads = o.threads;
        so.progress_interval_s = 60;
        so.resume_hint = false; // the calibration's own --resume is what continues it
        if (fs::exists(folder / "pressures.json")) {
          so.resume_dir = folder.string(); // stopped half way
        } else {
          fs::remove_all(folder);
          const ShearScenario sc = stage_scenario(cal, st, earlier, values, replicate);
          write_text(input, resolved_shear_toml(sc));
          so.scenario = input.string();
          so.out_dir = folder.string();
        }
        const int rc = run_shear_command(so);
        if (rc > 128 || stop_signal())
          throw Interrupted(rc > 128 ? rc - 128 : stop_signal(),
                            "calibration stopped in evaluation " + std::to_string(index));
        if (rc != 0)
          throw std::runtime_error(fmt::format("evaluation {} ({}): a shear run failed (exit {})",
                                               index, folder.string(), rc));
      };
      if (st.replicates.empty()) {
        shear(run, dir / (name + ".toml"), {});
      } else {
        make_directories(run.string());
        for (std::size_t k = 0; k < st.replicates.size(); ++k) {
          const fs::path folder = run / replicate_folder(k);
          if (fs::exists(folder / "summary.json")) continue; // finished before a stop
          shear(folder, run / (replicate_folder(k) + ".toml"), st.replicates[k]);
        }
        write_replicate_means(st, run);
      }
      Evaluation e;
      compare_with_target(st, run, e);
      e.wall_seconds = seconds_since(te);
      e.folder = fs::relative(run, out).generic_string();
      new_seconds += e.wall_seconds;
      ++new_count;
      return e;
    };
    std::vector<Evaluation> so_far;
    const EvaluationDone done = [&](const Evaluation& e, bool replayed) {
      so_far.push_back(e);
      if (!replayed) {
        std::ofstream h(history_csv, std::ios::app);
        h << history_line(e) << "\n";
        if (!h) throw std::runtime_error("cannot append to " + history_csv.string());
      }
      const auto best = std::min_element(
          so_far.begin(), so_far.end(),
          [](const Evaluation& a, const Evaluation& b) { return a.misfit < b.misfit; });
      const double per = new_count > 0 ? new_seconds / new_count : -1;
      fmt::print(stderr,
                 "[{:7.1f} s] calibrate {} {}/{}: {} -> misfit {:.4g} {} (best {:.4g} at {}){}; "
                 "ETA {}\n",
                 seconds_since(t0), st.name, e.index, st.optimiser.budget,
                 values_text(st, e.values), e.misfit, st.misfit_unit(), best->misfit, best->index,
                 replayed ? ", recorded" : fmt::format(", {}", format_duration(e.wall_seconds)),
                 per > 0 ? "<= " + format_duration(per * (st.optimiser.budget - e.index)) : "?");
      std::fflush(stderr);
      plot_misfit(st, so_far, dir / "misfit.png");
    };
    const OptimiserResult r = run_optimiser(st.parameters, st.optimiser, evaluate, recorded, done);
    const Evaluation& best = r.history[r.best];
    plot_curves(st, out / best.folder, best, dir / "curves.png");
    nlohmann::json fitted = nlohmann::json::object();
    for (std::size_t k = 0; k < st.parameters.size(); ++k) {
      fitted[st.parameters[k].key] = best.values[k];
      earlier.push_back(parameter_override(st.parameters[k], best.values[k]));
    }
    nlohmann::json parts = nlohmann::json::object();
    const std::vector<std::string> names = part_names(st);
    for (std::size_t k = 0; k < names.size() && k < best.parts.size(); ++k)
      parts[names[k]] = best.parts[k];
    stages_json.push_back({{"name", st.name},
                           {"fitted", fitted},
                           {"misfit", best.misfit},
                           {"misfit_unit", st.misfit_unit()},
                           {"misfit_parts", parts},
                           {"best_evaluation", best.index},
                           {"best_folder", best.folder},
                           {"evaluations", r.history.size()},
                           {"stop_reason", r.stop_reason},
                           {"restarts", r.restarts},
                           {"wall_seconds_this_process", seconds_since(ts)}});
    fmt::print("stage {}: {} -> misfit {:.4g} {} at evaluation {} of {} ({})\n", st.name,
               values_text(st, best.values), best.misfit, st.misfit_unit(), best.index,
               r.history.size(), r.stop_reason);
    std::fflush(stdout);
  }

  // The fitted material: the last stage's scenario at every fitted value.
  const CalibrationStage& last = cal.stages.back();
  const ShearScenario fitted = stage_scenario(cal, last, earlier, {});
  write_text(out / "fitted.toml", resolved_shear_toml(fitted));
  std::string flags;
  for (const std::string& f : earlier) {
    std::string compact;
    for (char ch : f)
      if (ch != ' ') compact += ch;
    flags += "--set '" + compact + "'\n";
  }
  write_text(out / "fitted_set.txt", flags);
  nlohmann::json summary = {{"scenario", cal.source},
                            {"stages", stages_json},
                            {"fitted_overrides", earlier},
                            {"wall_seconds_this_process", seconds_since(t0)}};
  write_text(out / "summary.json", summary.dump(2) + "\n");
  fmt::print(
      "wrote {0}/summary.json, fitted.toml (the fitted shear scenario), fitted_set.txt "
      "(--set flags for shear or slope), <stage>/history.csv, misfit.png, curves.png ({1})\n",
      out.string(), format_duration(seconds_since(t0)));
  return 0;
}

CLI::App* add_calibrate_subcommand(CLI::App& app) {
  auto o = std::make_shared<CalibrateCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate", "fit contact parameters to measured direct shear results (docs/calibrate.md)");
  cmd->add_option("scenario", o->scenario,
                  "calibration scenario (TOML): a shear scenario with a [calibrate] table");
  cmd->add_option("--out", o->out_dir, "output folder (default: runs/<scenario stem>_calibrate)");
  cmd->add_option("--resume", o->resume_dir,
                  "continue the calibration in this folder; finished evaluations are not rerun");
  cli::add_jobs_option(*cmd, o->jobs,
                       "pressures of one evaluation run at once, as child processes (default 1)");
  cli::add_threads_option(*cmd, o->threads,
                          "OpenMP threads per run (default: shear.threads; 0 = the OpenMP "
                          "default)");
  cli::add_set_option(*cmd, o->set);
  cli::add_check_flag(*cmd, o->check);
  cmd->callback([o]() {
    cli::run_subcommand([o] { return run_calibrate_command(*o); },
                        [o] {
                          std::string dir = o->resume_dir.empty() ? o->out_dir : o->resume_dir;
                          if (dir.empty() && !o->scenario.empty())
                            dir = "runs/" + fs::path(o->scenario).stem().string() + "_calibrate";
                          fmt::print(stderr,
                                     "centridem calibrate: continue with `centridem calibrate "
                                     "--resume {}`\n",
                                     dir.empty() ? "RUN_DIR" : dir);
                        });
  });
  return cmd;
}

} // namespace centridem
