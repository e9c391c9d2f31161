#include "app/cmd_render.hpp"

#include "app/cli.hpp"
#include "base/errors.hpp"
#include "io/csv.hpp"
#include "io/picture.hpp"
#include "io/plot.hpp"
#include "io/vtk_read.hpp"
#include "procedures/slope_config.hpp"
#include "procedures/slope_geometry.hpp"
#include "procedures/slope_trial.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <memory>
#include <optional>

namespace centridem {

namespace fs = std::filesystem;

namespace {

struct Frame {
  double time_s = 0;
  std::string vtu;   // relative to the trial folder
  std::string title; // the original picture's title (trials), else made here
  std::string png;   // the name to write
};

// A table of numbers with a header (frames.csv, checks.csv, measurements.csv).
struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::size_t column(const std::string& name, const std::string& file) const {
    for (std::size_t k = 0; k < header.size(); ++k)
      if (header[k] == name) return k;
    throw InputError(file, "(no column " + name + ")", "a file written by centridem");
  }
  std::vector<double> numbers(const std::string& name, const std::string& file) const {
    const std::size_t c = column(name, file);
    std::vector<double> v;
    for (std::size_t r = 0; r < rows.size(); ++r) {
      if (c >= rows[r].size()) throw InputError(file, fmt::format("row {}", r + 2), "too short");
      v.push_back(rows[r][c].empty()
                      ? NAN
                      : parse_finite_number(rows[r][c], fmt::format("{}:{}", file, r + 2)));
    }
    return v;
  }
};

Table read_table(const fs::path& p) {
  std::ifstream in(p);
  if (!in) throw InputError(p.string(), "(unreadable)", "a file written by centridem");
  Table t;
  std::string line;
  if (std::getline(in, line))
    for (auto f : split_commas(line)) t.header.emplace_back(f);
  while (std::getline(in, line)) {
    if (trim_blanks(line).empty()) continue;
    std::vector<std::string> row;
    for (auto f : split_commas(line)) row.emplace_back(f);
    t.rows.push_back(std::move(row));
  }
  return t;
}

struct Source {
  fs::path dir;                          // the trial or run folder
  std::optional<SlopeScenario> scenario; // slope trials: the campaign's scenario
  std::vector<Frame> frames;
  bool trial = false;
};

// A slope trial folder: frames.csv (or, from versions before it, slope.pvd).
Source trial_source(const fs::path& dir) {
  Source s;
  s.dir = dir;
  s.trial = true;
  const fs::path scenario = dir.parent_path() / "scenario.toml";
  if (!fs::exists(scenario))
    throw InputError(dir.string(), "(no ../scenario.toml)",
                     "a slope trial folder inside its campaign folder (the campaign's "
                     "scenario.toml gives the slope's outline)");
  s.scenario = load_slope_scenario(scenario.string());
  if (fs::exists(dir / "frames.csv")) {
    const std::string file = (dir / "frames.csv").string();
    const Table t = read_table(dir / "frames.csv");
    const std::size_t kf = t.column("frame", file), kt = t.column("time_after_cut_s", file),
                      kp = t.column("picture", file), ki = t.column("title", file);
    for (std::size_t r = 0; r < t.rows.size(); ++r) {
      Frame f;
      f.time_s = parse_finite_number(t.rows[r].at(kt), fmt::format("{}:{}", file, r + 2));
      f.vtu = fmt::format("frames/particles_{:04d}.vtu", std::stoi(t.rows[r].at(kf)));
      f.title = t.rows[r].at(ki);
      f.png = fs::path(t.rows[r].at(kp)).filename().string();
      s.frames.push_back(f);
    }
  } else if (fs::exists(dir / "slope.pvd")) {
    for (const auto& [t, file] : read_pvd((dir / "slope.pvd").string()))
      s.frames.push_back({t, file, "", ""});
  } else {
    throw InputError(dir.string(), "(no frames.csv or slope.pvd)",
                     "a slope trial run with output.vtk = true (its ParaView frames)");
  }
  return s;
}

Source run_source(const fs::path& dir) {
  Source s;
  s.dir = dir;
  for (const auto& [t, file] : read_pvd((dir / "particles.pvd").string()))
    s.frames.push_back({t, file, "", ""});
  return s;
}

// The folders to render under `dir`.
std::vector<Source> sources(const fs::path& dir) {
  if (!fs::is_directory(dir))
    throw InputError("RUN_DIR", "\"" + dir.string() + "\"", "an existing run folder");
  if (fs::exists(dir / "frames.csv") || fs::exists(dir / "slope.pvd")) return {trial_source(dir)};
  if (fs::exists(dir / "particles.pvd")) return {run_source(dir)};
  std::vector<fs::path> trials;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_directory() &&
        (fs::exists(e.path() / "frames.csv") || fs::exists(e.path() / "slope.pvd")))
      trials.push_back(e.path());
  std::sort(trials.begin(), trials.end());
  if (trials.empty())
    throw InputError("RUN_DIR", "\"" + dir.string() + "\"",
                     "a slope trial folder (frames.csv), a slope campaign folder (trial_<g>g/ "
                     "inside) or a `run` folder (particles.pvd)");
  std::vector<Source> out;
  for (const fs::path& t : trials) out.push_back(trial_source(t));
  return out;
}

// The value of the colour field at every particle of a frame [SI].
std::vector<double> field_values(const VtuArrays& a, const std::string& field) {
  std::vector<double> v(a.points);
  if (field == "sliding") {
    const auto it = a.arrays.find("sliding");
    if (it == a.arrays.end() || it->second.size() != a.points) return v; // none in this frame
    return it->second;
  }
  const std::vector<double>& x = a.get(field == "velocity" ? "velocity" : "displacement", 3);
  for (std::size_t i = 0; i < a.points; ++i)
    v[i] = std::hypot(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
  return v;
}

// log10 of each value; NaN (a gap in the line) where it is not positive.
std::vector<double> log10_values(std::vector<double> v) {
  for (double& x : v) x = x > 0 ? std::log10(x) : NAN;
  return v;
}

void plot_checks(const fs::path& dir, const fs::path& out) {
  if (!fs::exists(dir / "checks.csv")) return;
  const std::string file = (dir / "checks.csv").string();
  const Table t = read_table(dir / "checks.csv");
  if (t.rows.empty()) return;
  const auto time = t.numbers("time_s", file);
  LinePlot mass, speed, ratio;
  mass.title = "moving mass";
  mass.x_label = speed.x_label = ratio.x_label = "time after the cut (s)";
  mass.y_label = "particles";
  mass.add("largest connected group above the threshold", time, t.numbers("mass_particles", file));
  mass.add("all above the threshold", time, t.numbers("above_threshold", file)).dashed_line();
  speed.title = "mean speed of the largest group";
  speed.y_label = "speed (mm/s)";
  auto s = t.numbers("mass_mean_speed_m_s", file);
  for (double& x : s) x *= 1e3;
  speed.add("", time, s);
  ratio.title = "slope's mean unbalanced-force ratio";
  ratio.y_label = "log10 ratio";
  ratio.add("", time, log10_values(t.numbers("unbalanced_force_ratio", file)));
  render_panels((out / "checks.png").string(), {mass, speed, ratio}, 3, 600, 450);
}

void plot_measurements(const fs::path& dir, const fs::path& out) {
  if (!fs::exists(dir / "measurements.csv")) return;
  const std::string file = (dir / "measurements.csv").string();
  const Table t = read_table(dir / "measurements.csv");
  if (t.rows.empty()) return;
  const auto time = t.numbers("time_s", file);
  LinePlot ratio, energy, coordination;
  ratio.x_label = energy.x_label = coordination.x_label = "time (s)";
  ratio.title = "mean unbalanced-force ratio";
  ratio.y_label = "log10 ratio";
  ratio.add("", time, log10_values(t.numbers("ratio", file)));
  energy.title = "kinetic energy";
  energy.y_label = "log10 energy (J)";
  energy.add("", time, log10_values(t.numbers("kinetic_energy_J", file)));
  coordination.title = "coordination number";
  coordination.y_label = "contacts per particle";
  coordination.add("", time, t.numbers("coordination_number", file));
  render_panels((out / "measurements.png").string(), {ratio, energy, coordination}, 3, 600, 450);
}

} // namespace

int run_render_command(const RenderOptions& o) {
  if (o.field != "displacement" && o.field != "velocity" && o.field != "sliding")
    throw InputError("--field", "\"" + o.field + "\"", "displacement, velocity or sliding");
  if (!o.range.empty() &&
      (o.range.size() != 2 || !(o.range[0] < o.range[1]) || (!o.linear && !(o.range[0] > 0))))
    throw InputError("--range", fmt::format("{}", fmt::join(o.range, ",")),
                     "two numbers LO,HI with LO < HI (SI: m, m/s), LO > 0 unless --linear");
  if (!o.section.empty() && (o.section.size() != 2 || !(o.section[1] > 0)))
    throw InputError("--section", fmt::format("{}", fmt::join(o.section, ",")),
                     "two numbers Y_MID,HALF_THICKNESS in m, the half thickness > 0");
  const std::vector<Source> all = sources(fs::path(o.run_dir));
  for (const Source& s : all) {
    const fs::path out = o.out_dir.empty() ? s.dir / ("render_" + o.field)
                         : all.size() == 1 ? fs::path(o.out_dir)
                                           : fs::path(o.out_dir) / s.dir.filename();
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec || !fs::is_directory(out))
      throw InputError("--out", "\"" + out.string() + "\"", "a folder that can be created");

    // The frames' values, read once; the default range needs them all.
    std::vector<VtuArrays> frames;
    for (const Frame& f : s.frames) frames.push_back(read_vtu((s.dir / f.vtu).string()));
    SideViewInput base;
    base.log_scale = !o.linear && o.field != "sliding";
    if (o.field == "displacement") {
      base.vmin = s.scenario ? s.scenario->output.colour_min_m : 1.2e-4;
      base.vmax = s.scenario ? s.scenario->output.colour_max_m : 5e-3;
    } else if (o.field == "velocity") {
      double peak = 0;
      for (const VtuArrays& a : frames)
        for (double v : field_values(a, "velocity")) peak = std::max(peak, v);
      // Up to the next 1, 2 or 5 x a power of ten: round labels at the ends.
      double top = peak > 0 ? std::pow(10.0, std::floor(std::log10(peak))) : 1.0;
      for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * top >= peak) {
          top *= m;
          break;
        }
      base.vmax = top;
      base.vmin = base.log_scale ? 1e-3 * base.vmax : 0.0;
      base.value_label = "speed (mm/s)";
    } else {
      base.vmin = 0, base.vmax = 1;
      base.value_label = "sliding mass (1 = in it)";
      base.value_display_factor = 1;
    }
    if (!o.range.empty()) base.vmin = o.range[0], base.vmax = o.range[1];
    if (!o.section.empty())
      base.slice = true, base.slice_y_mid = o.section[0], base.slice_half_thickness = o.section[1];
    base.width_px = o.width_px > 0 ? o.width_px
                    : s.scenario   ? s.scenario->output.picture_width_px
                                   : 1200;
    if (s.scenario)
      frame_slope_picture(SlopeGeometry(s.scenario->slope), base); // as the trial framed them
    else
      base.outline = {};
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const VtuArrays& a = frames[k];
      SideViewInput in = base;
      const std::vector<double>& x = a.get("Points", 3);
      in.x.resize(a.points), in.y.resize(a.points), in.z.resize(a.points);
      for (std::size_t i = 0; i < a.points; ++i)
        in.x[i] = x[3 * i], in.y[i] = x[3 * i + 1], in.z[i] = x[3 * i + 2];
      in.radius = a.get("radius", 1);
      in.value = field_values(a, o.field);
      in.title =
          !s.frames[k].title.empty()
              ? s.frames[k].title
              : fmt::format("{} — t = {:.5f} s", s.dir.filename().string(), s.frames[k].time_s);
      if (!in.window && k == 0) base.window = side_view_window(in), in.window = base.window;
      const std::string png =
          s.frames[k].png.empty() ? fmt::format("frame_{:04d}.png", k) : s.frames[k].png;
      render_side_view(in, (out / png).string());
    }
    if (s.trial)
      plot_checks(s.dir, out);
    else
      plot_measurements(s.dir, out);
    fmt::print("{}: {} pictures ({} field){} in {}\n", s.dir.string(), frames.size(), o.field,
               s.trial ? ", checks.png" : ", measurements.png", out.string());
  }
  std::fflush(stdout);
  return 0;
}

CLI::App* add_render_subcommand(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* cmd = app.add_subcommand(
      "render", "pictures from a run's saved ParaView frames, after the run: side views coloured "
                "by displacement, velocity or the sliding mass, and a plot of its measurements "
                "against time (docs/slope.md)");
  cmd->add_option("run_dir", o->run_dir,
                  "a slope trial folder, a slope campaign folder or a `run` folder")
      ->required();
  cmd->add_option("--field", o->field, "colour by: displacement (default), velocity, sliding")
      ->check(CLI::IsMember({"displacement", "velocity", "sliding"}));
  cmd->add_option("--range", o->range,
                  "colour range LO,HI in SI (m, or m/s for velocity; default: the scenario's "
                  "displacement range, or 1e-3 to 1 x the peak speed)")
      ->delimiter(',')
      ->expected(2);
  cmd->add_flag("--linear", o->linear, "a linear colour scale (default log10)");
  cmd->add_option("--section", o->section,
                  "draw only the particles with |y - Y_MID| < HALF (m), as Y_MID,HALF")
      ->delimiter(',')
      ->expected(2);
  cmd->add_option("--width", o->width_px, "picture width in pixels (default: the scenario's)")
      ->check(cli::whole_number(200, 10000));
  cmd->add_option("--out", o->out_dir, "output folder (default: RUN_DIR/render_<field>)");
  cmd->callback([o]() { cli::run_subcommand([o] { return run_render_command(*o); }); });
  return cmd;
}

} // namespace centridem
