#include "app/cmd_slope.hpp"

#include "app/cli.hpp"
#include "app/jobs.hpp"
#include "base/errors.hpp"
#include "base/interrupt.hpp"
#include "io/output.hpp"
#include "io/plot.hpp"
#include "procedures/foundation.hpp"
#include "procedures/slope_config.hpp"
#include "procedures/slope_stability.hpp"
#include "procedures/slope_trial.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

namespace centridem {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;
using cli::format_duration;
using cli::seconds_since;

namespace {

std::string g_label(double g) {
  return fmt::format("{:g}", g);
}

json read_json(const fs::path& p) {
  std::ifstream in(p);
  if (!in) throw std::runtime_error("cannot read " + p.string());
  return json::parse(in);
}

// What the run folder remembers besides the scenario: the effective campaign
// (after command-line overrides) and the settings that must not change on
// --resume.
struct Campaign {
  CampaignSpec spec;
  bool auto_bracket = false; // search: bracket from the limit-equilibrium estimate, widened
  int threads = 1;
  std::string cache_dir;
};

json campaign_json(const Campaign& c) {
  const char* kind = c.spec.kind == CampaignKind::list     ? "list"
                     : c.spec.kind == CampaignKind::search ? "search"
                                                           : "schedule";
  return {{"kind", kind},
          {"g_levels", c.spec.g_levels},
          {"stable_g", c.spec.stable_g},
          {"failed_g", c.spec.failed_g},
          {"tolerance_g", c.spec.tolerance_g},
          {"step_g", c.spec.step_g},
          {"max_g", c.spec.max_g},
          {"max_slides", c.spec.max_slides},
          {"jobs", c.spec.jobs},
          {"auto_bracket", c.auto_bracket},
          {"threads", c.threads},
          {"cache_dir", c.cache_dir}};
}

Campaign campaign_from(const json& j, const std::string& path) {
  try {
    Campaign c;
    const std::string kind = j.at("kind");
    c.spec.kind = kind == "list"     ? CampaignKind::list
                  : kind == "search" ? CampaignKind::search
                                     : CampaignKind::schedule;
    c.spec.g_levels = j.at("g_levels").get<std::vector<double>>();
    c.spec.stable_g = j.at("stable_g");
    c.spec.failed_g = j.at("failed_g");
    c.spec.tolerance_g = j.at("tolerance_g");
    c.spec.step_g = j.at("step_g");
    c.spec.max_g = j.at("max_g");
    c.spec.max_slides = j.at("max_slides");
    c.spec.jobs = j.at("jobs");
    c.auto_bracket = j.value("auto_bracket", false);
    c.threads = j.at("threads");
    c.cache_dir = j.at("cache_dir");
    return c;
  } catch (const json::exception& e) {
    throw InputError(fmt::format("{}: unreadable campaign record ({})", path, e.what()));
  }
}

// The g-levels of a stepped schedule: the listed ones, then + step_g to max_g.
std::vector<double> schedule_levels(const CampaignSpec& c) {
  std::vector<double> g = c.g_levels;
  for (double next = g.back() + c.step_g; next <= c.max_g + 1e-9; next += c.step_g)
    g.push_back(next);
  return g;
}

struct TrialOutcome {
  double g = 0;
  std::string dir; // relative to the run folder
  json result;     // result.json; null when the trial did not finish
  bool failed() const { return !result.is_null() && result.value("failed", false); }
  bool done() const { return !result.is_null(); }
};

class SlopeCampaignRunner {
public:
  SlopeCampaignRunner(const SlopeScenario& sc, const Campaign& c, fs::path out,
                      double progress_interval_s)
      : sc_(sc), c_(c), out_(std::move(out)), progress_(progress_interval_s) {}

  // Runs (or picks up the results of) trials at these g-levels, in parallel.
  std::vector<TrialOutcome> run_levels(const std::vector<double>& gs) {
    std::vector<int> rc = run_jobs(
        gs.size(), c_.spec.jobs,
        [&](std::size_t k) {
          SlopeTrialPlan plan;
          plan.g_levels = {gs[k]};
          run_one(plan, trial_dir(gs[k]), g_label(gs[k]) + " g");
        },
        [&](std::size_t k) { return "trial at " + g_label(gs[k]) + " g"; });
    record_codes(rc);
    std::vector<TrialOutcome> out;
    for (double g : gs) out.push_back(outcome(g, trial_dir(g)));
    return out;
  }

  TrialOutcome run_schedule(const std::vector<double>& levels) {
    SlopeTrialPlan plan;
    plan.g_levels = levels;
    plan.max_slides = c_.spec.max_slides;
    std::vector<int> rc = run_jobs(
        1, 1, [&](std::size_t) { run_one(plan, "schedule", "schedule"); },
        [](std::size_t) { return std::string("schedule"); });
    record_codes(rc);
    return outcome(levels.front(), "schedule");
  }

  int worst_code() const { return worst_; }

private:
  static std::string trial_dir(double g) { return "trial_" + g_label(g) + "g"; }

  void record_codes(const std::vector<int>& rc) {
    for (int code : rc)
      if (code > 0 && (worst_ == 0 || code > 128)) worst_ = code; // interruptions win
  }

  TrialOutcome outcome(double g, const std::string& dir) const {
    TrialOutcome t;
    t.g = g;
    t.dir = dir;
    const fs::path p = out_ / dir / "result.json";
    if (fs::exists(p)) t.result = read_json(p);
    return t;
  }

  void run_one(const SlopeTrialPlan& plan, const std::string& dir, const std::string& tag) const {
    const fs::path d = out_ / dir;
    if (fs::exists(d / "result.json")) return; // finished earlier (resume)
    make_directories(d.string());
    std::FILE* log = std::fopen((d / "log.txt").string().c_str(), "a");
    const auto t0 = Clock::now();
    SlopeTrialOptions o;
    o.dir = d.string();
    o.cache_dir = c_.cache_dir;
    o.progress_interval_s = progress_;
    o.threads = c_.threads;
    o.log = [&](std::string_view line) {
      const std::string s = fmt::format("[{:8.1f} s] {}: {}\n", seconds_since(t0), tag, line);
      std::fputs(s.c_str(), stderr);
      std::fflush(stderr);
      if (log) {
        std::fputs(s.c_str(), log);
        std::fflush(log);
      }
    };
    try {
      run_slope_trial(sc_, plan, o);
    } catch (...) {
      if (log) std::fclose(log);
      throw;
    }
    if (log) std::fclose(log);
  }

  const SlopeScenario& sc_;
  Campaign c_;
  fs::path out_;
  double progress_;
  int worst_ = 0;
};

// "1,2" from a JSON array of bench numbers.
std::string bench_list(const json& a) {
  std::string s;
  for (const auto& b : a) {
    if (!s.empty()) s += ',';
    s += b.dump();
  }
  return s;
}

// The critical g of a campaign in words (summary.md and the last line).
std::string critical_in_words(const json& c) {
  if (!c.is_object()) return "not bracketed: no trial failed";
  auto g = [&](const char* k) { return c.at(k).get<double>(); };
  if (c.contains("failed_g")) {
    if (c.at("stable_g").is_null())
      return fmt::format("at or below {:g} g: the lowest level tried already fails", g("failed_g"));
    std::string s =
        fmt::format("between {:g} g (stable) and {:g} g (failed)", g("stable_g"), g("failed_g"));
    if (c.contains("estimate_g")) s += fmt::format(", estimate {:g} g", g("estimate_g"));
    return s;
  }
  if (c.contains("below_g"))
    return fmt::format("below {:g} g: {}", g("below_g"), c.value("note", ""));
  if (c.contains("above_g"))
    return fmt::format("above {:g} g: {}", g("above_g"), c.value("note", ""));
  if (c.contains("first_slide_g")) {
    std::string all;
    for (const json& v : c.at("slides_g"))
      all += fmt::format("{}{:g}", all.empty() ? "" : ", ", v.get<double>());
    return fmt::format("first slide at {:g} g (slides at {} g)", g("first_slide_g"), all);
  }
  return c.dump();
}

// The command that started the campaign, as typed (options in a fixed order).
std::string command_line(const SlopeCommandOptions& o) {
  auto q = [](const std::string& v) {
    return v.find_first_of(" '\"{}[]=*?$") == std::string::npos ? v : "'" + v + "'";
  };
  if (!o.resume_dir.empty()) return "centridem slope --resume " + q(o.resume_dir);
  std::string c = "centridem slope " + q(o.scenario);
  if (o.scale != 0) c += fmt::format(" --scale {:g}", o.scale);
  for (double g : o.g_levels) c += fmt::format(" --g {:g}", g);
  if (!o.search.empty()) {
    c += " --search";
    for (double g : o.search) c += fmt::format(" {:g}", g);
  }
  if (o.search_auto) c += " --search-auto";
  if (!o.schedule.empty()) {
    c += " --schedule";
    for (double g : o.schedule) c += fmt::format(" {:g}", g);
  }
  if (o.tolerance_g != 0) c += fmt::format(" --tolerance {:g}", o.tolerance_g);
  for (const std::string& kv : o.set) c += " --set " + q(kv);
  if (o.jobs > 0) c += fmt::format(" --jobs {}", o.jobs);
  if (o.threads >= 0) c += fmt::format(" --threads {}", o.threads);
  if (!o.out_dir.empty()) c += " --out " + q(o.out_dir);
  if (!o.cache_dir.empty()) c += " --cache " + q(o.cache_dir);
  return c;
}

json trial_row(const TrialOutcome& t) {
  json row = {{"g_level", t.g}, {"dir", t.dir}};
  if (!t.done()) {
    row["state"] = "not finished";
    return row;
  }
  const json& r = t.result;
  const json& lv = r.at("levels");
  row["foundation_particles"] = r["foundation"]["particles"];
  row["slope_particles"] = r["slope_particles"];
  row["wall_seconds"] = r["wall_seconds"];
  row["particle_steps_per_s"] = r["particle_steps_per_s"];
  row["total_steps"] = r["total_steps"];
  row["pictures"] = r["pictures"];
  json levels = json::array();
  for (const json& l : lv)
    levels.push_back({{"g_level", l["g_level"]},
                      {"state", l["state"]},
                      {"time_limit", l["time_limit"]},
                      {"level_time_s", l["level_time_s"]},
                      {"onset_time_s", l["onset_time_s"]},
                      {"start_zone", l["start_zone"]},
                      {"particles", l["particles"]},
                      {"volume_share", l["volume_share"]},
                      {"benches_crossed", l["benches_crossed"]},
                      {"source_benches", l["source_benches"]},
                      {"runout_model_m", l["runout_model_m"]}});
  row["levels"] = levels;
  row["state"] = t.failed() ? "failed" : (lv.empty() ? "?" : lv.back()["state"]);
  return row;
}

// One line of the summary table per level.
std::string md_row(double g, const json& l, const std::string& picture) {
  auto str = [](const json& v) {
    if (v.is_null()) return std::string("–");
    if (v.is_string()) return v.get<std::string>();
    return v.dump();
  };
  const std::string benches = bench_list(l["benches_crossed"]);
  const bool failed = l["state"] == "failed";
  return fmt::format("| {:g} | {}{} | {} | {} | {} | {} | {} | {} |\n", g, str(l["state"]),
                     l.value("time_limit", false) ? " (time limit)" : "",
                     failed ? fmt::format("{:.4f}", l["onset_time_s"].get<double>()) : "–",
                     failed ? str(l["start_zone"]) : "–", failed ? str(l["particles"]) : "–",
                     failed ? fmt::format("{:.1f}", 100 * l["volume_share"].get<double>()) : "–",
                     failed ? (benches.empty() ? "–" : benches) : "–",
                     failed ? fmt::format("{:.1f}", 1e3 * l["runout_model_m"].get<double>())
                            : "–") +
         (picture.empty() ? "" : "");
}

void write_plot(const SlopeScenario& sc, const std::vector<std::pair<double, json>>& levels,
                const std::string& title_extra, const fs::path& png) {
  LinePlot p;
  p.title =
      (sc.name.empty() ? std::string("benched slope") : sc.name) + ": g-levels tried" + title_extra;
  p.x_label = "g-level n";
  p.y_label = "sliding mass (% of the slope's volume)";
  std::vector<double> gs, gf, gu, ys, yf, yu;
  for (const auto& [g, l] : levels) {
    const double share = 100 * l.value("volume_share", 0.0);
    if (l["state"] == "failed")
      gf.push_back(g), yf.push_back(share);
    else if (l["state"] == "stable")
      gs.push_back(g), ys.push_back(share);
    else
      gu.push_back(g), yu.push_back(share);
  }
  if (!gs.empty())
    p.add("stable", gs, ys).markers_only(Marker::circle).with_colour({0.17, 0.63, 0.17});
  if (!gf.empty())
    p.add("failed", gf, yf).markers_only(Marker::cross).with_colour({0.84, 0.15, 0.16});
  if (!gu.empty())
    p.add("undecided (time limit)", gu, yu)
        .markers_only(Marker::diamond)
        .with_colour({0.5, 0.5, 0.5});
  double gmin = 1e300, gmax = -1e300;
  for (const auto& [g, l] : levels) gmin = std::min(gmin, g), gmax = std::max(gmax, g);
  const double pad = std::max(2.0, 0.1 * (gmax - gmin));
  p.x_range = AxisRange{std::max(0.0, gmin - pad), gmax + pad};
  p.y_range = AxisRange{0, 100};
  p.legend = LegendPlace::upper_left;
  p.render(png.string(), 900, 600);
}

} // namespace

int run_slope_command(const SlopeCommandOptions& opt) {
  const auto t0 = Clock::now();
  install_stop_handlers();
  SlopeScenario sc;
  Campaign camp;
  fs::path out;
  if (!opt.resume_dir.empty()) {
    out = opt.resume_dir;
    if (!opt.scenario.empty() || !opt.g_levels.empty() || !opt.search.empty() ||
        !opt.schedule.empty() || !opt.set.empty() || !opt.out_dir.empty() || opt.check ||
        opt.scale != 0 || opt.search_auto)
      throw InputError("--resume", opt.resume_dir,
                       "continues a run folder as it was started: give no scenario, --out, "
                       "--g, --search, --search-auto, --schedule, --set, --scale or --check "
                       "with it");
    if (!fs::exists(out / "scenario.toml") || !fs::exists(out / "campaign.json"))
      throw InputError("--resume", opt.resume_dir,
                       "not a slope run folder (scenario.toml and campaign.json missing)");
    sc = load_slope_scenario((out / "scenario.toml").string());
    camp = campaign_from(read_json(out / "campaign.json"), (out / "campaign.json").string());
    if (opt.jobs > 0) camp.spec.jobs = opt.jobs; // the machine may have changed
    fmt::print(stderr, "centridem slope: resuming {}\n", out.string());
  } else {
    if (opt.scenario.empty())
      throw InputError("scenario", "(missing)", "a scenario file, or --resume RUN_DIR");
    sc = load_slope_scenario(opt.scenario, opt.set);
    cli::print_warnings(sc.specimen.warnings);
    if (opt.scale != 0) apply_scale(sc, opt.scale);
    camp.spec = sc.campaign;
    if ((!opt.g_levels.empty()) + (!opt.search.empty()) + (!opt.schedule.empty()) +
            opt.search_auto >
        1)
      throw InputError("--g / --search / --search-auto / --schedule", "more than one given",
                       "one of them");
    if (opt.search_auto) {
      if (!sc.limit_equilibrium.enabled)
        throw InputError("--search-auto", "given",
                         "a scenario with a [limit_equilibrium] table (c and phi of the soil): "
                         "the bracket starts from its estimate");
      camp.spec.kind = CampaignKind::search;
      camp.spec.stable_g = camp.spec.failed_g = 0; // set from the estimate below
      camp.auto_bracket = true;
    }
    if (!opt.schedule.empty()) {
      const auto& q = opt.schedule;
      if (q.size() != 3 || !(q[0] > 0) || !(q[1] > 0) || !(q[2] >= q[0]) || !std::isfinite(q[2]) ||
          q[2] > 1e4)
        throw InputError("--schedule", fmt::format("{}", fmt::join(q, " ")),
                         "three g-levels START STEP MAX with 0 < START <= MAX <= 10000, STEP > 0");
      camp.spec.kind = CampaignKind::schedule;
      camp.spec.g_levels = {q[0]};
      camp.spec.step_g = q[1];
      camp.spec.max_g = q[2];
      if (sc.campaign.kind != CampaignKind::schedule) camp.spec.max_slides = 3;
    }
    if (!opt.g_levels.empty()) {
      camp.spec.kind = CampaignKind::list;
      camp.spec.g_levels.clear();
      for (double g : opt.g_levels) {
        if (!(g > 0) || !std::isfinite(g) || g > 1e4)
          throw InputError("--g", fmt::format("{:g}", g), "a g-level in (0, 10000]");
        camp.spec.g_levels.push_back(g);
      }
    }
    if (!opt.search.empty()) {
      if (opt.search.size() != 2 || !(opt.search[0] > 0) || !(opt.search[1] > opt.search[0]) ||
          !(opt.search[1] <= 1e4))
        throw InputError("--search", fmt::format("{}", fmt::join(opt.search, " ")),
                         "two g-levels STABLE FAILED with 0 < STABLE < FAILED <= 10000");
      camp.spec.kind = CampaignKind::search;
      camp.spec.stable_g = opt.search[0];
      camp.spec.failed_g = opt.search[1];
    }
    if (opt.tolerance_g > 0) camp.spec.tolerance_g = opt.tolerance_g;
    if (opt.jobs > 0) camp.spec.jobs = opt.jobs;
    camp.threads = opt.threads >= 0 ? opt.threads : sc.trial.threads;
    std::string o = opt.out_dir;
    if (o.empty()) {
      std::string stem = fs::path(opt.scenario).stem().string();
      if (stem.empty()) stem = "scenario";
      o = "runs/" + stem + "_slope";
    }
    out = o;
    camp.cache_dir = opt.cache_dir.empty()
                         ? (fs::absolute(out).parent_path() / "cache").lexically_normal().string()
                         : fs::absolute(opt.cache_dir).string();
    if (opt.check) {
      check_output_folder(out.string(), "--out");
      check_output_folder(camp.cache_dir, "--cache");
      fmt::print("{}", resolved_slope_toml(sc));
      fmt::print("# campaign: {}\n", campaign_json(camp).dump());
      fmt::print(stderr, "centridem slope: {} checked; nothing run (--check)\n", opt.scenario);
      return 0;
    }
    make_directories(out.string());
    if (fs::exists(out / "campaign.json"))
      throw InputError("--out", out.string(),
                       "already holds a slope run: continue it with `centridem slope --resume " +
                           out.string() + "`, or choose another folder");
    replace_text_file((out / "scenario.toml").string(), resolved_slope_toml(sc));
    replace_text_file((out / "campaign.json").string(), campaign_json(camp).dump(2) + "\n");
  }
  if (opt.threads >= 0) camp.threads = opt.threads;

  const SlopeGeometry geometry(sc.slope);
  SlopeCampaignRunner runner(sc, camp, out, opt.progress_interval_s);
  const CampaignSpec& cs = camp.spec;
  fmt::print(stderr,
             "centridem slope: {} (s = {:g}; DEM box {:.2f} x {:.2f} x {:.2f} mm), {} job(s), {} "
             "thread(s) per trial, output {}\n",
             sc.name.empty() ? "benched slope" : sc.name, sc.slope.size_reduction_factor,
             1e3 * geometry.length(), 1e3 * geometry.breadth(), 1e3 * geometry.height(), cs.jobs,
             camp.threads == 0 ? std::string("default") : std::to_string(camp.threads),
             out.string());

  std::optional<FoundationResult> foundation;
  if (sc.preparation.enabled) {
    // The prepared foundation once, before any trial (they read it from the
    // cache), in a child process (OpenMP threads must not exist in a process
    // that forks trials) with every core the trials will use: its result does
    // not depend on the thread count.
    foundation = cached_foundation_result(sc, camp.cache_dir);
    if (!foundation) {
      const int threads = std::max(1, cs.jobs) * std::max(1, camp.threads);
      const auto t_prep = Clock::now();
      const std::vector<int> rc = run_jobs(
          1, 2,
          [&](std::size_t) {
            ensure_prepared_foundation(
                sc, camp.cache_dir, [](std::string_view l) { fmt::print(stderr, "{}\n", l); },
                threads);
          },
          [](std::size_t) { return std::string("foundation"); });
      if (rc.at(0) != 0) return rc[0];
      foundation = cached_foundation_result(sc, camp.cache_dir);
      if (!foundation) throw std::runtime_error("the prepared foundation was not cached");
      fmt::print(stderr, "prepared foundation made in {:.0f} s\n", seconds_since(t_prep));
    }
    fmt::print(stderr,
               "prepared foundation: {} particles, porosity by thirds {:.4f} / {:.4f} / {:.4f}, "
               "coordination {:.2f} ({})\n",
               foundation->particles, foundation->layer_porosity[0], foundation->layer_porosity[1],
               foundation->layer_porosity[2], foundation->coordination_number,
               prepared_foundation_path(sc, camp.cache_dir));
  }
  // The limit-equilibrium estimate (Bishop), and an automatic search bracket from it.
  json limit_equilibrium = nullptr;
  if (sc.limit_equilibrium.enabled) {
    const double rho = limit_equilibrium_bulk_density(sc, foundation ? &*foundation : nullptr);
    const SlopeLimitEquilibrium le = slope_limit_equilibrium(sc, geometry, rho);
    limit_equilibrium = to_json(le, sc);
    fmt::print(stderr,
               "limit equilibrium (Bishop's simplified method): c = {:.3g} kPa, phi = {:.3g} deg, "
               "bulk density {:.0f} kg/m^3: {} {:.1f} g\n",
               1e-3 * le.cohesion_Pa, le.friction_angle_deg, rho,
               le.critical.bracketed ? "critical g" : "critical g not bracketed in 1-1000 g:",
               le.critical.g_level);
    CampaignSpec& cs_mut = camp.spec;
    if (camp.auto_bracket && cs_mut.stable_g == 0 && cs_mut.failed_g == 0) {
      // The bracket: the estimate +- 20 %, on multiples of 5 g.
      const double n = le.critical.g_level;
      cs_mut.stable_g = std::max(5.0, 5.0 * std::floor(0.8 * n / 5.0));
      cs_mut.failed_g = std::max(cs_mut.stable_g + 5.0, 5.0 * std::ceil(1.2 * n / 5.0));
      replace_text_file((out / "campaign.json").string(), campaign_json(camp).dump(2) + "\n");
      fmt::print(stderr, "search bracket from the estimate: [{:g}, {:g}] g\n", cs_mut.stable_g,
                 cs_mut.failed_g);
    }
  }

  std::vector<TrialOutcome> trials;
  json critical = nullptr;
  std::string title_extra;
  if (cs.kind == CampaignKind::list) {
    fmt::print(stderr, "trials at {} g\n", fmt::join(cs.g_levels, ", "));
    trials = runner.run_levels(cs.g_levels);
  } else if (cs.kind == CampaignKind::search) {
    // Bracketing search: confirm both ends, then split the bracket into
    // jobs + 1 parts per round (bisection with one job).
    double lo = cs.stable_g, hi = cs.failed_g;
    fmt::print(stderr, "critical-g search in [{:g}, {:g}] g to {:g} g\n", lo, hi, cs.tolerance_g);
    std::vector<TrialOutcome> ends = runner.run_levels({lo, hi});
    trials = ends;
    bool ok = runner.worst_code() == 0;
    // A bracket from the estimate widens itself (at most 4 times): a failing
    // lower end moves the bracket down, a stable upper end moves it up.
    for (int widen = 0; camp.auto_bracket && ok && widen < 4; ++widen) {
      const double width = hi - lo;
      const bool down = ends[0].failed() && lo > 1.0;
      if (!down && !(!ends[1].failed() && hi < 1e4)) break;
      if (down) { // the failing lower end becomes the upper one
        ends[1] = ends[0];
        hi = lo;
        lo = std::max(1.0, lo - width);
      } else { // the stable upper end becomes the lower one
        ends[0] = ends[1];
        lo = hi;
        hi = std::min(1e4, hi + width);
      }
      fmt::print(stderr, "bracket widened to [{:g}, {:g}] g\n", lo, hi);
      const std::vector<TrialOutcome> more = runner.run_levels({down ? lo : hi});
      ok = runner.worst_code() == 0;
      trials.insert(trials.end(), more.begin(), more.end());
      ends[down ? 0 : 1] = more.at(0);
    }
    if (ok && ends[0].failed()) {
      critical = {{"below_g", lo}, {"note", "the slope already fails at the lower end"}};
      ok = false;
    } else if (ok && !ends[1].failed()) {
      critical = {{"above_g", hi}, {"note", "the slope does not fail at the upper end"}};
      ok = false;
    }
    while (ok && hi - lo > cs.tolerance_g + 1e-9) {
      const int parts = std::max(2, cs.jobs + 1);
      std::vector<double> gs;
      for (int k = 1; k < parts; ++k) {
        // Levels rounded to 0.01 g, so folder names stay short.
        const double g = std::round((lo + (hi - lo) * k / parts) * 100) / 100;
        if (g > lo && g < hi) gs.push_back(g);
      }
      if (gs.empty()) break;
      std::vector<TrialOutcome> round = runner.run_levels(gs);
      if (runner.worst_code() != 0) {
        ok = false;
        break;
      }
      for (const TrialOutcome& t : round) {
        trials.push_back(t);
        if (t.failed())
          hi = std::min(hi, t.g);
        else
          lo = std::max(lo, t.g);
      }
      // A non-monotonic answer (stable above a failure) narrows to the lowest failure.
      for (const TrialOutcome& t : trials)
        if (!t.failed() && t.g < hi) lo = std::max(lo, t.g);
      fmt::print(stderr, "critical-g bracket now [{:g}, {:g}] g\n", lo, hi);
    }
    if (ok) critical = {{"stable_g", lo}, {"failed_g", hi}, {"estimate_g", 0.5 * (lo + hi)}};
    std::sort(trials.begin(), trials.end(),
              [](const TrialOutcome& a, const TrialOutcome& b) { return a.g < b.g; });
  } else {
    const std::vector<double> levels = schedule_levels(cs);
    fmt::print(stderr, "stepped schedule: {} g (stop after {} slide(s))\n", fmt::join(levels, ", "),
               cs.max_slides);
    trials = {runner.run_schedule(levels)};
  }

  // Summary.
  json rows = json::array();
  std::vector<std::pair<double, json>> plotted;
  std::string md = fmt::format("# {} — slope campaign\n\nScenario: `{}` (s = {:g}). Command: "
                               "`{}`; folder `{}`.\n\n",
                               sc.name.empty() ? "benched slope" : sc.name, sc.source_path,
                               sc.slope.size_reduction_factor, command_line(opt), out.string());
  md += "| g-level | state | onset (s) | starts at | particles sliding | volume % | benches "
        "crossed | runout (model mm) |\n|---|---|---|---|---|---|---|---|\n";
  std::vector<double> slide_g;
  for (const TrialOutcome& t : trials) {
    rows.push_back(trial_row(t));
    if (!t.done()) {
      md += fmt::format("| {:g} | not finished | | | | | | |\n", t.g);
      continue;
    }
    for (const json& l : t.result["levels"]) {
      const double g = l["g_level"];
      plotted.emplace_back(g, l);
      md += md_row(g, l, "");
      if (l["state"] == "failed") slide_g.push_back(g);
    }
  }
  if (cs.kind == CampaignKind::list) {
    double lowest_failed = INFINITY, highest_stable = -INFINITY;
    for (const auto& [g, l] : plotted)
      if (l["state"] == "failed") lowest_failed = std::min(lowest_failed, g);
    for (const auto& [g, l] : plotted)
      if (l["state"] != "failed" && g < lowest_failed) highest_stable = std::max(highest_stable, g);
    if (std::isfinite(lowest_failed))
      critical = {
          {"stable_g", std::isfinite(highest_stable) ? json(highest_stable) : json(nullptr)},
          {"failed_g", lowest_failed}};
  }
  if (cs.kind == CampaignKind::schedule && !slide_g.empty())
    critical = {{"first_slide_g", slide_g.front()}, {"slides_g", slide_g}};
  if (critical.is_object() && critical.contains("failed_g"))
    title_extra =
        critical["stable_g"].is_null()
            ? fmt::format(" (fails at {:g} g)", critical["failed_g"].get<double>())
            : fmt::format(" (critical between {:g} and {:g} g)", critical["stable_g"].get<double>(),
                          critical["failed_g"].get<double>());
  else if (critical.is_object() && critical.contains("first_slide_g"))
    title_extra = fmt::format(" (first slide at {:g} g)", critical["first_slide_g"].get<double>());
  if (!plotted.empty()) write_plot(sc, plotted, title_extra, out / "g_levels.png");
  md += "\nCritical g: " + critical_in_words(critical) + ".\n";
  if (foundation)
    md += fmt::format("\nPrepared foundation: {} particles (generated {}, trimmed {}), porosity "
                      "by thirds (bottom, middle, top) {:.4f} / {:.4f} / {:.4f}, coordination "
                      "number {:.2f}.\n",
                      foundation->particles, foundation->generated_particles, foundation->trimmed,
                      foundation->layer_porosity[0], foundation->layer_porosity[1],
                      foundation->layer_porosity[2], foundation->coordination_number);
  if (limit_equilibrium.is_object())
    md += fmt::format(
        "\nLimit equilibrium (Bishop's simplified method, circular slips): critical "
        "g {:.1f}{} with c = {:.3g} kPa, phi = {:.3g} deg, bulk density {:.0f} "
        "kg/m^3{}.\n",
        limit_equilibrium["critical_g"].get<double>(),
        limit_equilibrium["bracketed"].get<bool>() ? "" : " (not bracketed)",
        1e-3 * limit_equilibrium["cohesion_Pa"].get<double>(),
        limit_equilibrium["friction_angle_deg"].get<double>(),
        limit_equilibrium["bulk_density_kg_m3"].get<double>(),
        sc.limit_equilibrium.source.empty() ? "" : " (" + sc.limit_equilibrium.source + ")");
  {
    std::vector<std::string> per_trial;
    for (const TrialOutcome& t : trials)
      if (t.done())
        per_trial.push_back(fmt::format("{}: {}", t.g > 0 ? fmt::format("{:g} g", t.g) : "schedule",
                                        format_duration(t.result["wall_seconds"].get<double>())));
    md += fmt::format("\nWall time: {} for this command ({} trial(s) at once{}{}).\n",
                      format_duration(seconds_since(t0)), cs.jobs,
                      per_trial.empty() ? "" : "; each trial's own: ",
                      fmt::format("{}", fmt::join(per_trial, ", ")));
  }
  md += "\nPictures: `<trial>/pictures/frame_NNNN.png` (the frames' times after the cut in "
        "`<trial>/frames.csv`); ParaView: `<trial>/slope.pvd` (particles, with the sliding mass), "
        "`slope_contacts.pvd` (force chains), `slope_walls.pvd`; the g-level plot: "
        "`g_levels.png`; more pictures from the saved frames: `centridem render <trial>`.\n";

  json summary;
  summary["scenario"] = sc.source_path;
  summary["name"] = sc.name;
  summary["campaign"] = campaign_json(camp);
  summary["geometry"] = to_json(geometry);
  summary["soil_contact_attraction_force_N"] = sc.soil().attraction_force_N;
  summary["trials"] = rows;
  summary["critical_g"] = critical;
  summary["limit_equilibrium"] = limit_equilibrium;
  summary["prepared_foundation"] = foundation ? to_json(*foundation) : json(nullptr);
  summary["wall_seconds_this_process"] = seconds_since(t0);
  replace_text_file((out / "summary.json").string(), summary.dump(2) + "\n");
  replace_text_file((out / "summary.md").string(), md);

  fmt::print("{:>8} {:>10} {:>10} {:>14} {:>9} {:>8} {:>8} {:>10}\n", "g-level", "state", "onset_s",
             "start", "sliding", "vol_%", "benches", "wall");
  for (const TrialOutcome& t : trials) {
    if (!t.done()) {
      fmt::print("{:>8g} {:>10}\n", t.g, "unfinished");
      continue;
    }
    for (const json& l : t.result["levels"]) {
      const bool failed = l["state"] == "failed";
      const std::string benches = bench_list(l["benches_crossed"]);
      fmt::print("{:>8g} {:>10} {:>10} {:>14} {:>9} {:>8} {:>8} {:>10}\n",
                 l["g_level"].get<double>(), l["state"].get<std::string>(),
                 failed ? fmt::format("{:.4f}", l["onset_time_s"].get<double>()) : "-",
                 failed ? l["start_zone"].get<std::string>() : "-",
                 failed ? l["particles"].dump() : "-",
                 failed ? fmt::format("{:.1f}", 100 * l["volume_share"].get<double>()) : "-",
                 failed ? benches : "-", format_duration(t.result["wall_seconds"].get<double>()));
    }
  }
  fmt::print("critical g: {}\n", critical_in_words(critical));
  fmt::print("wrote {}: summary.md, summary.json, g_levels.png; pictures in <trial>/pictures/, "
             "ParaView series <trial>/slope.pvd ({})\n",
             out.string(), format_duration(seconds_since(t0)));
  std::fflush(stdout);
  const int worst = runner.worst_code();
  if (worst > 128)
    fmt::print(stderr,
               "centridem slope: interrupted; continue with `centridem slope --resume {}`\n",
               out.string());
  if (stop_signal() && worst == 0) return 128 + stop_signal();
  return worst;
}

CLI::App* add_slope_subcommand(CLI::App& app) {
  auto o = std::make_shared<SlopeCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "slope", "benched slope in the centrifuge: trials at g-levels, a critical-g search or a "
               "stepped g schedule (docs/slope.md)");
  cmd->add_option("scenario", o->scenario,
                  "scenario file (TOML) with [specimen], [contact.ball_ball], [slope] and "
                  "[campaign]");
  cmd->add_option("--out", o->out_dir, "output folder (default: runs/<scenario stem>_slope)");
  cmd->add_option("--resume", o->resume_dir,
                  "continue the run in this folder from its trials' last checkpoints");
  cmd->add_option("--g", o->g_levels,
                  "run independent trials at these g-levels instead of the campaign "
                  "(repeatable)");
  cmd->add_option("--search", o->search,
                  "bracketing search for the critical g between STABLE and FAILED")
      ->expected(2);
  cmd->add_flag("--search-auto", o->search_auto,
                "critical-g search whose bracket starts from the limit-equilibrium estimate "
                "(needs [limit_equilibrium]); it widens itself when an end is wrong");
  cmd->add_option("--schedule", o->schedule,
                  "one model, g raised from START by STEP up to MAX, each level held until "
                  "equilibrium or a slide (the centrifuge test's own loading)")
      ->expected(3);
  cli::add_set_option(*cmd, o->set);
  cmd->add_option("--scale", o->scale,
                  "run the slope at this size reduction factor s instead of slope's (smaller: "
                  "fewer particles, faster; the specimen's region follows; stresses and the "
                  "soil's F0 stay those of the scenario's model)")
      ->check(cli::positive_number(1));
  cmd->add_option("--tolerance", o->tolerance_g, "search: stop when the bracket is this narrow [g]")
      ->check(cli::positive_number(1e4));
  cli::add_jobs_option(*cmd, o->jobs,
                       "trials at once, as child processes (default: campaign.jobs)");
  cli::add_threads_option(*cmd, o->threads,
                          "OpenMP threads per trial (default: trial.threads; 0 = the OpenMP "
                          "default)");
  cmd->add_option("--cache", o->cache_dir,
                  "folder of cached bricks (default: cache/ beside the output folder)");
  cmd->add_option("--progress", o->progress_interval_s, "seconds between progress lines")
      ->check(cli::positive_number());
  cli::add_check_flag(*cmd, o->check);
  cmd->callback([o]() {
    cli::run_subcommand([o] { return run_slope_command(*o); },
                        [o] {
                          fmt::print(stderr,
                                     "centridem slope: continue with `centridem slope --resume "
                                     "{}`\n",
                                     o->resume_dir.empty()
                                         ? (o->out_dir.empty() ? "RUN_DIR" : o->out_dir)
                                         : o->resume_dir);
                        });
  });
  return cmd;
}

} // namespace centridem
