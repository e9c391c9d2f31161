// The benched-slope trial driver (procedures/slope_trial; docs/slope.md
// "Trial") on a tiny slope (s = 0.015, ~1,300 particles of 0.2-0.3 mm, the
// paper's higher-first-bench geometry): the stages happen in order with the
// documented side effects, a frictionless soil fails and an adhesive one at
// low g stands, and a trial stopped (as by SIGINT) twice - in the foundation
// stage and after the failure onset - and resumed from its checkpoints ends
// bit for bit where an uninterrupted one does (issue 6, items 1 and 3).
#include "base/errors.hpp"
#include "base/interrupt.hpp"
#include "procedures/slope_config.hpp"
#include "procedures/slope_trial.hpp"
#include "vtk_test_util.hpp"

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <unistd.h>

using namespace centridem;
namespace fs = std::filesystem;

namespace {

const std::string kTiny = R"(
[specimen]
gradation = { bins = [{ d_min_m = 0.2e-3, d_max_m = 0.3e-3, volume_fraction = 1.0 }] }
porosity = 0.5
density_kg_m3 = 2633.0
seed = 3
brick = { size_m = [2.2575e-3, 1.8e-3, 2.7e-3] }

[contact.ball_ball]
model = "arrlinear"
effective_modulus_Pa = 300e6
stiffness_ratio = 1.5
friction = 0.5
rolling_friction = 0.16
attraction_force_N = 1.2e-4

[slope]
name = "tiny"
size_reduction_factor = 0.015
benches = [{ height_m = 0.075, width_m = 0.03 }, { height_m = 0.075 }]
breadth_m = 0.12

[trial]
check_interval_steps = 500
max_time_s = 0.03
after_failure_time_s = 0.004
checkpoint_interval_min = 0
CUT

[campaign]
g_levels = [20]

[output]
frame_interval_steps = 4000
vtk = false
picture_width_px = 400
)";

std::string replace_all(std::string s, const std::string& what, const std::string& with) {
  for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + with.size()))
    s.replace(p, what.size(), with);
  return s;
}

// The paper's humid sand (Table 1, F0 / s); `weak`: at the cut every
// contact, old and new, loses friction, rolling resistance and adhesion.
SlopeScenario tiny(bool weak) {
  const std::string none = "{ friction = 0.0, rolling_friction = 0.0, attraction_force_N = 0.0 }";
  return parse_slope_scenario(
      replace_all(kTiny, "CUT", weak ? "at_cut = " + none + "\nafter_cut = " + none : ""),
      "tiny.toml", ".");
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class SlopeTrialTest : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           fmt::format("centridem_slope_trial_{}_{}", ::getpid(),
                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    set_stop_signal(0);
  }
  void TearDown() override {
    set_stop_signal(0);
    fs::remove_all(dir_);
  }
  SlopeTrialOptions options(const std::string& sub, std::vector<std::string>* lines = nullptr) {
    SlopeTrialOptions o;
    o.dir = (dir_ / sub).string();
    o.cache_dir = (dir_ / "cache").string();
    o.threads = 1;
    if (lines) o.log = [lines](std::string_view l) { lines->emplace_back(l); };
    return o;
  }
  fs::path dir_;
};

TEST_F(SlopeTrialTest, AdhesiveSlopeAtLowGStandsAndFrictionlessOneFails) {
  SlopeTrialPlan plan;
  plan.g_levels = {20};
  std::vector<std::string> log;
  const SlopeTrialResult a = run_slope_trial(tiny(false), plan, options("a", &log));
  ASSERT_EQ(a.levels.size(), 1u);
  EXPECT_EQ(a.levels[0].report.state, SlopeState::stable);
  EXPECT_FALSE(a.levels[0].time_limit);
  EXPECT_EQ(a.first_failure(), nullptr);
  // Stages: foundation at equilibrium, then the cut removed the excavation
  // (about a third of a uniform specimen: the section's excavated fraction).
  EXPECT_TRUE(a.foundation.converged);
  EXPECT_LT(a.foundation.ratio, 1e-4);
  EXPECT_EQ(a.excavated + a.slope_particles, a.foundation.particles);
  const SlopeGeometry g(tiny(false).slope);
  EXPECT_NEAR(static_cast<double>(a.excavated) / static_cast<double>(a.foundation.particles),
              g.excavated_fraction(), 0.05);
  // Files of a finished trial; the checkpoint is gone, the brick is cached.
  const fs::path d = dir_ / "a";
  EXPECT_TRUE(fs::exists(d / "result.json"));
  EXPECT_TRUE(fs::exists(d / "checks.csv"));
  EXPECT_TRUE(fs::exists(d / "final_state.csv"));
  EXPECT_TRUE(fs::exists(d / "pictures" / "frame_0000.png"));
  EXPECT_FALSE(fs::exists(d / "checkpoint.bin"));
  EXPECT_FALSE(a.foundation.brick_from_cache);
  EXPECT_TRUE(fs::exists(a.foundation.brick_file));

  // trial.min_time_s: at rest early is not yet stable; the same slope is
  // watched on until the minimum time and only then called stable.
  const double t_rest = a.levels[0].report.time_s;
  SlopeScenario watched = tiny(false);
  watched.trial.min_time_s = 3 * t_rest;
  const SlopeTrialResult w = run_slope_trial(watched, plan, options("w"));
  ASSERT_EQ(w.levels.size(), 1u);
  EXPECT_EQ(w.levels[0].report.state, SlopeState::stable);
  EXPECT_FALSE(w.levels[0].time_limit);
  EXPECT_GE(w.levels[0].report.time_s, 3 * t_rest - 1e-12);
  const double interval = t_rest / a.levels[0].report.checks; // checks at k x interval
  EXPECT_LT(w.levels[0].report.time_s, 3 * t_rest + interval + 1e-12)
      << "stops at the first check after the minimum time";

  // No friction, no rolling resistance, no adhesion after the cut: it slides.
  const SlopeTrialResult b = run_slope_trial(tiny(true), plan, options("b"));
  ASSERT_EQ(b.levels.size(), 1u);
  const FailureReport& r = b.levels[0].report;
  EXPECT_EQ(r.state, SlopeState::failed);
  ASSERT_TRUE(r.onset_time_s.has_value());
  EXPECT_GT(r.particles, 100u);
  EXPECT_GT(r.volume_share, 0.05);
  EXPECT_GT(r.runout_m, 0.0);
  EXPECT_NE(b.first_failure(), nullptr);
  // The second trial reused the first one's brick (same specimen recipe).
  EXPECT_TRUE(b.foundation.brick_from_cache);
  EXPECT_EQ(b.foundation.brick_file, a.foundation.brick_file);
}

// Stopped twice (as SIGINT would: the flag, then a checkpoint and
// Interrupted), resumed twice in fresh Worlds: the same end bit for bit.
TEST_F(SlopeTrialTest, InterruptedAndResumedTrialEndsBitForBitLikeAnUninterruptedOne) {
  const SlopeScenario sc = tiny(true);
  SlopeTrialPlan plan;
  plan.g_levels = {20};
  const SlopeTrialResult whole = run_slope_trial(sc, plan, options("whole"));
  ASSERT_EQ(whole.levels.at(0).report.state, SlopeState::failed);

  std::vector<std::string> log;
  SlopeTrialOptions o = options("stopped", &log);
  auto stop_when = [&](const std::string& needle) {
    o.log = [&log, needle](std::string_view l) {
      log.emplace_back(l);
      if (l.find(needle) != std::string_view::npos) set_stop_signal(SIGINT);
    };
  };
  stop_when("fitted into the chamber walls"); // during the foundation stage
  try {
    run_slope_trial(sc, plan, o);
    FAIL() << "not interrupted";
  } catch (const Interrupted& e) {
    EXPECT_EQ(e.signal(), SIGINT);
    EXPECT_NE(std::string(e.what()).find("checkpoint"), std::string::npos);
  }
  EXPECT_TRUE(fs::exists(dir_ / "stopped" / "checkpoint.bin"));
  EXPECT_FALSE(fs::exists(dir_ / "stopped" / "result.json"));

  set_stop_signal(0);
  stop_when("FAILED"); // after the onset, in the middle of the level
  try {
    run_slope_trial(sc, plan, o);
    FAIL() << "not interrupted";
  } catch (const Interrupted&) {
  }
  set_stop_signal(0);
  o.log = nullptr;
  const SlopeTrialResult resumed = run_slope_trial(sc, plan, o);
  EXPECT_TRUE(resumed.resumed);

  EXPECT_EQ(resumed.total_steps, whole.total_steps);
  EXPECT_EQ(slurp(dir_ / "stopped" / "final_state.csv"), slurp(dir_ / "whole" / "final_state.csv"));
  EXPECT_EQ(slurp(dir_ / "stopped" / "checks.csv"), slurp(dir_ / "whole" / "checks.csv"));
  nlohmann::json a = to_json(whole), b = to_json(resumed);
  for (auto* j : {&a, &b}) {
    for (const char* k : {"wall_seconds", "particle_steps_per_s", "resumed"}) j->erase(k);
    (*j)["foundation"].erase("brick_from_cache"); // the first trial made the cached brick
  }
  EXPECT_EQ(a.dump(), b.dump());
}

TEST_F(SlopeTrialTest, SteppedScheduleRaisesGOnOneModelUntilItSlides) {
  // The adhesive sand stands at 1 g (F0 ~ 500 grain weights) and slides at
  // 3000 g (F0 ~ 0.2 grain weights; its 70-degree faces need cohesion).
  const SlopeScenario sc = tiny(false);
  SlopeTrialPlan plan;
  plan.g_levels = {1, 3000};
  plan.max_slides = 1;
  const SlopeTrialResult r = run_slope_trial(sc, plan, options("schedule"));
  ASSERT_FALSE(r.levels.empty());
  EXPECT_DOUBLE_EQ(r.levels.front().g_level, 1.0);
  EXPECT_EQ(r.levels.front().report.state, SlopeState::stable);
  const LevelResult* f = r.first_failure();
  ASSERT_NE(f, nullptr);
  EXPECT_GT(f->g_level, 1.0);
  // Stops at the first slide (max_slides = 1); each level follows the last.
  EXPECT_EQ(&r.levels.back(), f);
  for (std::size_t k = 1; k < r.levels.size(); ++k)
    EXPECT_EQ(r.levels[k].first_step, r.levels[k - 1].first_step + r.levels[k - 1].steps);
  EXPECT_EQ(r.foundation.particles, r.excavated + r.slope_particles);
}

// One time axis (issue 19): every frame's time since the cut is the same
// number in frames.csv, the log, the picture's title and the three ParaView
// series; the first frame is the cut (t = 0); the last frame flags the
// sliding mass the report describes.
TEST_F(SlopeTrialTest, OneTimeAxisInTheLogThePicturesAndTheParaViewSeries) {
  SlopeScenario sc = tiny(true);
  sc.output.vtk = true;
  SlopeTrialPlan plan;
  plan.g_levels = {20};
  std::vector<std::string> log;
  const SlopeTrialResult r = run_slope_trial(sc, plan, options("axis", &log));
  ASSERT_EQ(r.levels.at(0).report.state, SlopeState::failed);
  const fs::path d = dir_ / "axis";

  auto pvd = [&](const char* name) {
    const vtktest::VtkFile f = vtktest::read_vtk(d / name);
    std::vector<std::pair<double, std::string>> out;
    for (const auto& e : f.doc->child("Collection")->children)
      out.emplace_back(std::stod(e->attr.at("timestep")), e->attr.at("file"));
    return out;
  };
  const auto particles = pvd("slope.pvd"), contacts = pvd("slope_contacts.pvd"),
             walls = pvd("slope_walls.pvd");
  std::istringstream csv(slurp(d / "frames.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "frame,time_after_cut_s,step,g_level,picture,title");
  std::size_t k = 0;
  for (; std::getline(csv, line); ++k) {
    SCOPED_TRACE(line);
    std::vector<std::string> c;
    std::stringstream ls(line);
    for (std::string cell; std::getline(ls, cell, ',');) c.push_back(cell);
    ASSERT_EQ(c.size(), 6u);
    EXPECT_EQ(std::stoul(c[0]), k);
    const double t = std::stod(c[1]);
    if (k == 0) EXPECT_EQ(t, 0.0) << "the first frame is the cut";
    ASSERT_LT(k, particles.size());
    EXPECT_EQ(particles[k].first, t);
    EXPECT_EQ(contacts[k].first, t);
    EXPECT_EQ(walls[k].first, t);
    EXPECT_EQ(particles[k].second, fmt::format("frames/particles_{:04d}.vtu", k));
    EXPECT_TRUE(fs::exists(d / c[4])) << c[4];
    const std::string shown = fmt::format("t = {:.5f} s after the cut", t);
    EXPECT_NE(c[5].find(shown), std::string::npos) << "picture title: " << c[5];
    const std::string logged = fmt::format("frame {}: {}, step {}", k, shown, c[2]);
    EXPECT_TRUE(std::any_of(log.begin(), log.end(),
                            [&](const std::string& l) { return l.find(logged) != l.npos; }))
        << "no log line with: " << logged;
  }
  EXPECT_EQ(k, particles.size());
  EXPECT_GE(k, 3u);

  // The last frame: the sliding mass flagged, as many particles as reported.
  const vtktest::VtkFile last = vtktest::read_vtk(d / particles.back().second);
  const auto a = vtktest::arrays(last);
  double flagged = 0;
  for (double v : a.at("sliding")) flagged += v;
  EXPECT_EQ(flagged, static_cast<double>(r.levels[0].report.particles));
  EXPECT_GT(flagged, 100.0);
  // The first (at the cut): nothing slides yet.
  const auto first = vtktest::arrays(vtktest::read_vtk(d / particles.front().second));
  for (double v : first.at("sliding")) ASSERT_EQ(v, 0.0);
}

} // namespace
