// Calibration (`centridem calibrate`, docs/calibrate.md) without simulations:
// the misfits against hand-computed values, the optimiser loop on analytic
// functions with known minima (found, within its budget, stopped at the
// tolerance), its resume from a recorded history without repeating an
// evaluation, and every class of bad input named with its file, line or key.
#include "base/errors.hpp"
#include "procedures/calibration.hpp"
#include "procedures/calibration_config.hpp"

#include "cli_test_util.hpp"
#include "scenario_fixtures.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <string>

using namespace centridem;
using centridem::testutil::TempDir;
namespace fs = std::filesystem;

namespace {

// ---- misfits ------------------------------------------------------------------

MeasuredCurve measured_three_points() {
  MeasuredCurve m;
  m.normal_stress_Pa = 50e3;
  m.strain = {0.01, 0.02, 0.03, 0.05}; // the last beyond the simulated 0.04: left out
  m.shear_stress_Pa = {10e3, 20e3, 30e3, 25e3};
  return m;
}

SimulatedCurve simulated_three_points() {
  SimulatedCurve s;
  s.normal_stress_Pa = 50e3;
  s.strain = {0.0, 0.02, 0.04};
  s.shear_stress_Pa = {0.0, 24e3, 28e3};
  s.vertical_displacement_m = {0.0, 2e-6, 4e-6};
  return s;
}

TEST(CalibrationMisfit, CurveAgainstHandComputedValues) {
  // Interpolated at 0.01, 0.02, 0.03: 12, 24, 26 kPa against 10, 20, 30:
  // differences 2, 4, -4 kPa, RMS sqrt(36 / 3) = sqrt(12) kPa. Peaks 28 and 30:
  // -2 kPa. With peak weight 1: sqrt(12 + 4) = 4 kPa.
  const MeasuredCurve m = measured_three_points();
  const SimulatedCurve s = simulated_three_points();
  const CurveMisfit plain = curve_misfit(m, s, {});
  EXPECT_EQ(plain.points, 3u);
  EXPECT_NEAR(plain.rms_shear_stress_Pa, std::sqrt(12.0) * 1e3, 1e-9);
  EXPECT_NEAR(plain.peak_difference_Pa, -2e3, 1e-9);
  EXPECT_NEAR(plain.total_Pa, std::sqrt(12.0) * 1e3, 1e-9);
  const CurveMisfit peak = curve_misfit(m, s, {1.0, 0.0});
  EXPECT_NEAR(peak.total_Pa, 4e3, 1e-9);

  // Dilation: simulated 1, 2, 3 µm at the three strains against 1, 1, 1 µm
  // measured: RMS sqrt(5 / 3) µm; at 1000 kPa/mm that is 1.29099 kPa, and the
  // total sqrt(12 + 4 + 5/3) kPa.
  MeasuredCurve md = m;
  md.vertical_displacement_m = {1e-6, 1e-6, 1e-6, 1e-6};
  const CurveMisfit dil = curve_misfit(md, s, {1.0, 1000.0});
  EXPECT_NEAR(dil.rms_vertical_displacement_m, std::sqrt(5.0 / 3.0) * 1e-6, 1e-15);
  EXPECT_NEAR(dil.total_Pa, std::sqrt(12.0 + 4.0 + 5.0 / 3.0) * 1e3, 1e-6);

  // Consolidated height: simulated 2.995 mm against 2.998 measured, -3 um; at
  // 1 kPa/um that is 3 kPa, and the total sqrt(12 + 4 + 9) = 5 kPa. Not
  // measured (0): no term, whatever the weight.
  MeasuredCurve mh = m;
  mh.consolidated_height_m = 2.998e-3;
  SimulatedCurve sh = s;
  sh.consolidated_height_m = 2.995e-3;
  const CurveMisfit height = curve_misfit(mh, sh, {1.0, 0.0, 1.0});
  EXPECT_NEAR(height.height_difference_m, -3e-6, 1e-15);
  EXPECT_NEAR(height.total_Pa, 5e3, 1e-6);
  EXPECT_NEAR(curve_misfit(m, sh, {1.0, 0.0, 1.0}).total_Pa, 4e3, 1e-9);

  // Unload-reload moduli: simulated 42 and 45 MPa against 40 and 50 measured,
  // +5 % and -10 %; at 0.5 kPa/% that is 2.5 and 5 kPa, and the total
  // sqrt(12 + 4 + 6.25 + 25) kPa. A measured modulus the run did not give
  // (no loop: 0) counts as -100 %, 50 kPa; none measured: no term.
  MeasuredCurve mm = m;
  mm.unloading_modulus_Pa = 40e6;
  mm.reloading_modulus_Pa = 50e6;
  SimulatedCurve sm = s;
  sm.unloading_modulus_Pa = 42e6;
  sm.reloading_modulus_Pa = 45e6;
  const CurveWeights wm{1.0, 0.0, 0.0, 0.5};
  const CurveMisfit moduli = curve_misfit(mm, sm, wm);
  EXPECT_NEAR(moduli.unloading_modulus_difference, 0.05, 1e-12);
  EXPECT_NEAR(moduli.reloading_modulus_difference, -0.10, 1e-12);
  EXPECT_NEAR(moduli.total_Pa, std::sqrt(12.0 + 4.0 + 6.25 + 25.0) * 1e3, 1e-6);
  MeasuredCurve mu = m;
  mu.unloading_modulus_Pa = 40e6;
  EXPECT_NEAR(curve_misfit(mu, s, wm).total_Pa, std::sqrt(12.0 + 4.0 + 2500.0) * 1e3, 1e-6);
  EXPECT_NEAR(curve_misfit(m, sm, wm).total_Pa, 4e3, 1e-9);
  // The affine modulus, weighed as the loop's: 88 MPa simulated against 80 measured is +10 %,
  // 5 kPa at 0.5 kPa/%: sqrt(12 + 4 + 25) kPa.
  MeasuredCurve ma = m;
  ma.affine_modulus_Pa = 80e6;
  SimulatedCurve sa = s;
  sa.affine_modulus_Pa = 88e6;
  const CurveMisfit affine = curve_misfit(ma, sa, wm);
  EXPECT_NEAR(affine.affine_modulus_difference, 0.10, 1e-12);
  EXPECT_NEAR(affine.total_Pa, std::sqrt(12.0 + 4.0 + 25.0) * 1e3, 1e-6);

  // Two pressures with totals 3 and 4 kPa: sqrt((9 + 16) / 2) kPa.
  CurveMisfit a, b;
  a.total_Pa = 3e3;
  b.total_Pa = 4e3;
  EXPECT_NEAR(overall_misfit({a, b}), std::sqrt(12.5) * 1e3, 1e-9);

  // A simulation that never reached a measured strain compares nothing.
  SimulatedCurve short_run = s;
  short_run.strain = {0.0, 0.001, 0.002};
  EXPECT_TRUE(std::isinf(curve_misfit(m, short_run, {}).total_Pa));
}

// Replicates: two linear curves on offset strain grids; their mean on the
// first one's strains that both reach is the mean of the two lines there.
TEST(CalibrationMisfit, MeanOfReplicatesIsTheMeanCurveOnTheCommonStrains) {
  SimulatedCurve a, b;
  a.normal_stress_Pa = b.normal_stress_Pa = 50e3;
  a.strain = {0.0, 0.01, 0.02, 0.03, 0.04}; // tau = 1e6 e, dz = 1e-4 e
  for (double e : a.strain) {
    a.shear_stress_Pa.push_back(1e6 * e);
    a.vertical_displacement_m.push_back(1e-4 * e);
  }
  b.strain = {0.005, 0.015, 0.025, 0.035}; // tau = 2e6 e + 1e3, dz = -1e-4 e
  for (double e : b.strain) {
    b.shear_stress_Pa.push_back(2e6 * e + 1e3);
    b.vertical_displacement_m.push_back(-1e-4 * e);
  }
  a.consolidated_height_m = 3.0e-3;
  b.consolidated_height_m = 3.2e-3;
  a.unloading_modulus_Pa = 40e6;
  b.unloading_modulus_Pa = 50e6;
  a.reloading_modulus_Pa = 30e6;
  b.reloading_modulus_Pa = 36e6;
  a.affine_modulus_Pa = 80e6;
  b.affine_modulus_Pa = 90e6;
  const SimulatedCurve m = mean_of_replicates({a, b});
  // a's strains inside b's range [0.005, 0.035]: 0.01, 0.02, 0.03.
  ASSERT_EQ(m.strain.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const double e = 0.01 * static_cast<double>(k + 1);
    EXPECT_DOUBLE_EQ(m.strain[k], e);
    EXPECT_NEAR(m.shear_stress_Pa[k], (1e6 * e + 2e6 * e + 1e3) / 2, 1e-6);
    EXPECT_NEAR(m.vertical_displacement_m[k], 0.0, 1e-18);
  }
  EXPECT_NEAR(m.consolidated_height_m, 3.1e-3, 1e-18);
  EXPECT_NEAR(m.unloading_modulus_Pa, 45e6, 1e-6);
  EXPECT_NEAR(m.reloading_modulus_Pa, 33e6, 1e-6);
  EXPECT_NEAR(m.affine_modulus_Pa, 85e6, 1e-6);
  EXPECT_DOUBLE_EQ(m.normal_stress_Pa, 50e3);

  // One replicate is itself; none, or two at different pressures, are refused;
  // no common strain range gives no curve (an infinite misfit).
  EXPECT_EQ(mean_of_replicates({a}).strain, a.strain);
  EXPECT_THROW(mean_of_replicates({}), std::invalid_argument);
  SimulatedCurve c = b;
  c.normal_stress_Pa = 150e3;
  EXPECT_THROW(mean_of_replicates({a, c}), std::invalid_argument);
  SimulatedCurve late = b;
  late.strain = {0.05, 0.06, 0.07, 0.08};
  EXPECT_TRUE(mean_of_replicates({a, late}).strain.empty());
}

TEST(CalibrationMisfit, MohrCoulombAndPeakTargets) {
  const MohrCoulombMisfit mc = mohr_coulomb_misfit({35.0, 5e3}, 35.6, 5.8e3);
  EXPECT_NEAR(mc.friction_angle_difference_deg, 0.6, 1e-12);
  EXPECT_NEAR(mc.cohesion_difference_Pa, 800.0, 1e-9);
  EXPECT_NEAR(mc.total, 1.0, 1e-12); // sqrt(0.6^2 + 0.8^2)
  EXPECT_NEAR(peak_stress_misfit({10e3, 20e3}, {13e3, 16e3}), std::sqrt(12.5) * 1e3, 1e-9);
}

TEST(CalibrationMisfit, UnitScalesRoundTripAndLogIsGeometric) {
  const CalibrationParameter lin{"a", 0.02, 0.5, 0.08, false};
  const CalibrationParameter log{"b", 1e8, 1e10, 1e9, true};
  EXPECT_NEAR(to_unit(lin, 0.08), 0.125, 1e-12);
  EXPECT_NEAR(to_unit(log, 1e9), 0.5, 1e-12); // the geometric middle
  EXPECT_NEAR(from_unit(log, 0.5), 1e9, 1e-3);
  EXPECT_NEAR(from_unit(lin, to_unit(lin, 0.3)), 0.3, 1e-12);
}

// ---- the optimiser loop -----------------------------------------------------

// The recovery problem with an analytic stand-in for the simulation:
// E* in [1e8, 1e9] (log), rolling friction in [0.02, 0.5], true values 3e8 and
// 0.16, started 50 % off (4.5e8 and 0.08). A smooth bowl whose minimum, 0, is
// at the true values.
std::vector<CalibrationParameter> recovery_parameters() {
  return {{"contact.ball_ball.effective_modulus_Pa", 1e8, 1e9, 4.5e8, true},
          {"contact.ball_ball.rolling_friction", 0.02, 0.5, 0.08, false}};
}
double bowl(const std::vector<double>& v) {
  const double a = std::log(v[0] / 3e8) / 0.1, b = (v[1] - 0.16) / 0.01;
  return a * a + b * b;
}
Evaluation evaluate_bowl(int, const std::vector<double>& v) {
  Evaluation e;
  e.misfit = bowl(v);
  return e;
}

TEST(CalibrationOptimiser, FindsTheKnownMinimumFromFiftyPercentOff) {
  OptimiserSettings s;
  s.budget = 60;
  s.unit_step_tolerance = 1e-6;
  const OptimiserResult r = run_optimiser(recovery_parameters(), s, evaluate_bowl);
  ASSERT_FALSE(r.history.empty());
  EXPECT_DOUBLE_EQ(r.history.front().values[0], 4.5e8); // starts at the start
  EXPECT_DOUBLE_EQ(r.history.front().values[1], 0.08);
  EXPECT_LE(r.history.size(), 60u);
  const Evaluation& best = r.history[r.best];
  EXPECT_NEAR(best.values[0], 3e8, 0.01 * 3e8);
  EXPECT_NEAR(best.values[1], 0.16, 0.01 * 0.16);
  for (std::size_t k = 0; k < r.history.size(); ++k) {
    EXPECT_EQ(r.history[k].index, static_cast<int>(k) + 1);
    EXPECT_GE(r.history[k].values[0], 1e8); // inside the bounds
    EXPECT_LE(r.history[k].values[0], 1e9);
    EXPECT_GE(r.history[k].values[1], 0.02);
    EXPECT_LE(r.history[k].values[1], 0.5);
  }
}

TEST(CalibrationOptimiser, StopsAtTheToleranceOrTheBudget) {
  OptimiserSettings s;
  s.budget = 60;
  s.tolerance = 0.05;
  const OptimiserResult tol = run_optimiser(recovery_parameters(), s, evaluate_bowl);
  EXPECT_LE(tol.history[tol.best].misfit, 0.05);
  EXPECT_EQ(tol.best, tol.history.size() - 1); // stopped at the first point that met it
  EXPECT_NE(tol.stop_reason.find("tolerance"), std::string::npos) << tol.stop_reason;

  s.tolerance = 0;
  s.budget = 7;
  int calls = 0;
  const OptimiserResult budget =
      run_optimiser(recovery_parameters(), s, [&](int i, const std::vector<double>& v) {
        ++calls;
        return evaluate_bowl(i, v);
      });
  EXPECT_EQ(calls, 7);
  EXPECT_EQ(budget.history.size(), 7u);
  EXPECT_NE(budget.stop_reason.find("budget"), std::string::npos) << budget.stop_reason;
}

// Restarts: on the bowl BOBYQA converges well inside a budget of 60; allowed
// two restarts it starts again from the best point so far (its first new
// evaluation is that point) with its first step, twice, and says so; a resume
// replays the same points.
TEST(CalibrationOptimiser, RestartsFromTheBestPointWhenItConvergesWithBudgetLeft) {
  OptimiserSettings s;
  s.budget = 60;
  const OptimiserResult once = run_optimiser(recovery_parameters(), s, evaluate_bowl);
  ASSERT_LT(once.history.size(), 30u) << once.stop_reason;
  EXPECT_EQ(once.restarts, 0);
  s.restarts = 2;
  const OptimiserResult r = run_optimiser(recovery_parameters(), s, evaluate_bowl);
  EXPECT_EQ(r.restarts, 2);
  EXPECT_NE(r.stop_reason.find("after 2 restart(s)"), std::string::npos) << r.stop_reason;
  ASSERT_GT(r.history.size(), once.history.size());
  EXPECT_LE(r.history.size(), 60u);
  // The first run is the same; the next evaluation is its best point again.
  const std::size_t k = once.history.size();
  for (std::size_t i = 0; i < k; ++i) EXPECT_EQ(r.history[i].values, once.history[i].values);
  EXPECT_EQ(r.history[k].values, once.history[once.best].values);
  EXPECT_LE(r.history[r.best].misfit, once.history[once.best].misfit);
  // Resumed from its first 20 evaluations (past the first restart): the same
  // points, and the evaluator called only for the rest.
  const std::vector<Evaluation> recorded(r.history.begin(), r.history.begin() + 20);
  int calls = 0;
  const OptimiserResult resumed = run_optimiser(
      recovery_parameters(), s,
      [&](int i, const std::vector<double>& v) {
        ++calls;
        return evaluate_bowl(i, v);
      },
      recorded);
  ASSERT_EQ(resumed.history.size(), r.history.size());
  for (std::size_t i = 0; i < r.history.size(); ++i)
    EXPECT_EQ(resumed.history[i].values, r.history[i].values) << i;
  EXPECT_EQ(calls, static_cast<int>(r.history.size()) - 20);
}

TEST(CalibrationOptimiser, OneParameterIsALineSearch) {
  OptimiserSettings s;
  s.budget = 40;
  s.unit_step_tolerance = 1e-6;
  const std::vector<CalibrationParameter> p = {{"contact.ball_ball.friction", 0.1, 0.9, 0.2}};
  const OptimiserResult r = run_optimiser(p, s, [](int, const std::vector<double>& v) {
    Evaluation e;
    e.misfit = (v[0] - 0.6) * (v[0] - 0.6);
    return e;
  });
  EXPECT_NEAR(r.history[r.best].values[0], 0.6, 0.006);
}

// A stopped calibration resumes without repeating an evaluation: stopped by an
// exception in the 9th evaluation (as Ctrl-C stops a shear run), then run again
// with the 8 recorded ones, it calls the evaluator only for the 9th onwards and
// ends exactly where an uninterrupted run ends.
TEST(CalibrationOptimiser, StoppedThenResumedRepeatsNoEvaluation) {
  OptimiserSettings s;
  s.budget = 25;
  const OptimiserResult whole = run_optimiser(recovery_parameters(), s, evaluate_bowl);

  std::vector<Evaluation> recorded;
  EXPECT_THROW(run_optimiser(
                   recovery_parameters(), s,
                   [](int index, const std::vector<double>& v) {
                     if (index == 9) throw Interrupted(2, "stopped in evaluation 9");
                     return evaluate_bowl(index, v);
                   },
                   {}, [&](const Evaluation& e, bool) { recorded.push_back(e); }),
               Interrupted);
  ASSERT_EQ(recorded.size(), 8u);

  std::vector<int> evaluated;
  int replayed = 0;
  const OptimiserResult resumed = run_optimiser(
      recovery_parameters(), s,
      [&](int index, const std::vector<double>& v) {
        evaluated.push_back(index);
        return evaluate_bowl(index, v);
      },
      recorded, [&](const Evaluation&, bool r) { replayed += r ? 1 : 0; });
  EXPECT_EQ(replayed, 8);
  ASSERT_FALSE(evaluated.empty());
  EXPECT_EQ(evaluated.front(), 9);
  EXPECT_EQ(evaluated.size() + 8, resumed.history.size());
  ASSERT_EQ(resumed.history.size(), whole.history.size());
  for (std::size_t k = 0; k < whole.history.size(); ++k) {
    EXPECT_EQ(resumed.history[k].values, whole.history[k].values) << "evaluation " << k + 1;
    EXPECT_EQ(resumed.history[k].misfit, whole.history[k].misfit) << "evaluation " << k + 1;
  }
}

TEST(CalibrationOptimiser, AHistoryOfAnotherCalibrationIsRefused) {
  OptimiserSettings s;
  s.budget = 6;
  OptimiserResult r = run_optimiser(recovery_parameters(), s, evaluate_bowl);
  r.history[2].values[1] *= 1.01;
  try {
    run_optimiser(recovery_parameters(), s, evaluate_bowl, r.history);
    FAIL() << "a changed history was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("evaluation 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("changed"), std::string::npos) << e.what();
  }
}

// ---- the [calibrate] table and the measured curves ------------------------

// The CI shear box at two pressures with a [calibrate] table of one stage;
// `stage` replaces the stage's body.
std::string scenario_with(const std::string& stage) {
  std::string s = testutil::kSmallShearBox;
  const std::string from = "normal_stresses_Pa = [100e3]";
  s.replace(s.find(from), from.size(), "normal_stresses_Pa = [50e3, 150e3]");
  return s + "\n[calibrate]\n[[calibrate.stage]]\nname = \"dry\"\n" + stage;
}

const std::string kGoodParameters =
    "parameters = [{ key = \"contact.ball_ball.rolling_friction\", min = 0.02, max = 0.5, "
    "start = 0.08 }]\n";

class CalibrationConfig : public ::testing::Test {
protected:
  TempDir dir_{"centridem_calibration_config"};
  void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  CalibrationScenario parse(const std::string& stage) {
    return parse_calibration(scenario_with(stage), "cal.toml", dir_.path().string());
  }
  std::string error_of(const std::string& stage) {
    try {
      parse(stage);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
  void SetUp() override {
    write("both.csv", "normal_stress_kPa,shear_displacement_mm,shear_stress_kPa\n"
                      "50,0.0,0\n50,0.03,20\n50,0.06,30\n"
                      "150,0.0,0\n150,0.03,60\n150,0.06,90\n");
  }
};

TEST_F(CalibrationConfig, ReadsCurvesAndConvertsDisplacementToStrain) {
  const CalibrationScenario c = parse("target = { curves = [\"both.csv\"] }\n" + kGoodParameters);
  ASSERT_EQ(c.stages.size(), 1u);
  const CalibrationStage& st = c.stages[0];
  ASSERT_EQ(st.curves.size(), 2u);
  EXPECT_DOUBLE_EQ(st.curves[0].normal_stress_Pa, 50e3);
  EXPECT_DOUBLE_EQ(st.curves[1].normal_stress_Pa, 150e3);
  // 0.06 mm over the 3 mm height (strain = "height" by default).
  EXPECT_NEAR(st.curves[1].strain.back(), 0.02, 1e-15);
  EXPECT_DOUBLE_EQ(st.curves[1].shear_stress_Pa.back(), 90e3);
  ASSERT_EQ(st.parameters.size(), 1u);
  EXPECT_EQ(st.parameters[0].key, "contact.ball_ball.rolling_friction");
  EXPECT_EQ(st.optimiser.budget, 30);

  // The parameter reaches the stage's scenario.
  const ShearScenario sc = stage_scenario(c, st, {}, {0.3});
  EXPECT_DOUBLE_EQ(sc.ball_ball.rolling_friction, 0.3);
}

// Each replicate's overrides reach its scenario, last; bad lists are named.
TEST_F(CalibrationConfig, ReplicatesOverrideEachReplicatesScenario) {
  const std::string target = "target = { curves = [\"both.csv\"] }\n" + kGoodParameters;
  const CalibrationScenario c =
      parse(target + "replicates = [\"specimen.seed = 21\", [\"specimen.seed = 22\", "
                     "\"specimen.porosity = 0.42\"]]\n");
  const CalibrationStage& st = c.stages[0];
  ASSERT_EQ(st.replicates.size(), 2u);
  const ShearScenario a = stage_scenario(c, st, {}, {0.3}, st.replicates[0]);
  const ShearScenario b = stage_scenario(c, st, {}, {0.3}, st.replicates[1]);
  EXPECT_EQ(a.specimen.seed, 21u);
  EXPECT_EQ(b.specimen.seed, 22u);
  EXPECT_DOUBLE_EQ(b.specimen.porosity, 0.42);
  EXPECT_DOUBLE_EQ(b.ball_ball.rolling_friction, 0.3); // the fitted value still reaches it
  EXPECT_TRUE(parse(target).stages[0].replicates.empty());
  for (const char* bad : {"replicates = []\n",
                          "replicates = [\"specimen.seed = 1\", "
                          "\"specimen.seed = 1\"]\n",
                          "replicates = [3]\n", "replicates = 4\n", "replicates = [[]]\n"}) {
    const std::string e = error_of(target + bad);
    EXPECT_NE(e.find("calibrate.stage[1].replicates"), std::string::npos) << bad << e;
    EXPECT_NE(e.find("KEY = VALUE"), std::string::npos) << bad << e;
  }
  // An override the scenario refuses is named with its replicate.
  const std::string e = error_of(target + "replicates = [\"specimen.seed = -2\"]\n");
  EXPECT_NE(e.find("calibrate.stage[1].replicates[1]"), std::string::npos) << e;
  EXPECT_NE(e.find("specimen.seed"), std::string::npos) << e;
}

TEST_F(CalibrationConfig, BadMeasuredDataIsNamedWithFileAndLine) {
  write("unsorted.csv", "normal_stress_kPa,shear_strain,shear_stress_kPa\n"
                        "50,0.0,0\n50,0.02,20\n50,0.01,30\n150,0,0\n");
  std::string e = error_of("target = { curves = [\"unsorted.csv\"] }\n" + kGoodParameters);
  EXPECT_NE(e.find("unsorted.csv line 4"), std::string::npos) << e;
  EXPECT_NE(e.find("rising"), std::string::npos) << e;

  write("only50.csv", "shear_strain,shear_stress_kPa\n0,0\n0.01,20\n");
  e = error_of("target = { curves = [{ file = \"only50.csv\", normal_stress_kPa = 50 }] }\n" +
               kGoodParameters);
  EXPECT_NE(e.find("none at 150 kPa"), std::string::npos) << e;
  EXPECT_NE(e.find("calibrate.stage[1].target"), std::string::npos) << e;

  write("nan.csv", "normal_stress_kPa,shear_strain,shear_stress_kPa\n50,0,0\n50,0.01,abc\n");
  e = error_of("target = { curves = [\"nan.csv\"] }\n" + kGoodParameters);
  EXPECT_NE(e.find("nan.csv line 3 column 3"), std::string::npos) << e;

  write("column.csv", "normal_stress_kPa,strain,shear_stress_kPa\n50,0,0\n");
  e = error_of("target = { curves = [\"column.csv\"] }\n" + kGoodParameters);
  EXPECT_NE(e.find("column.csv line 1 (header)"), std::string::npos) << e;
  EXPECT_NE(e.find("\"strain\""), std::string::npos) << e;

  write("at75.csv", "normal_stress_kPa,shear_strain,shear_stress_kPa\n75,0,0\n75,0.01,5\n");
  e = error_of("target = { curves = [\"both.csv\", \"at75.csv\"] }\n" + kGoodParameters);
  EXPECT_NE(e.find("a curve at 75 kPa"), std::string::npos) << e;

  e = error_of("target = { curves = [\"missing.csv\"] }\n" + kGoodParameters);
  EXPECT_NE(e.find("missing.csv"), std::string::npos) << e;
}

TEST_F(CalibrationConfig, BadParametersAreNamedByKey) {
  const std::string target = "target = { curves = [\"both.csv\"] }\n";
  std::string e = error_of(target + "parameters = [{ key = \"contact.ball_ball.friction\", "
                                    "min = 0.1, start = 0.3 }]\n");
  EXPECT_NE(e.find("calibrate.stage[1].parameters[1].max"), std::string::npos) << e;

  e = error_of(target + "parameters = [{ key = \"contact.ball_ball.friction\", min = 0.1, "
                        "max = 0.5, start = 0.7 }]\n");
  EXPECT_NE(e.find("calibrate.stage[1].parameters[1].start"), std::string::npos) << e;
  EXPECT_NE(e.find("inside the bounds [0.1, 0.5]"), std::string::npos) << e;

  e = error_of(target + "parameters = [{ key = \"contact.ball_ball.frcition\", min = 0.1, "
                        "max = 0.5, start = 0.3 }]\n");
  EXPECT_NE(e.find("calibrate.stage[1].parameters[1].key"), std::string::npos) << e;
  EXPECT_NE(e.find("friction"), std::string::npos) << e; // the did-you-mean

  e = error_of(target + "parameters = [{ key = \"contact.ball_ball.friction\", min = 0, "
                        "max = 0.5, start = 0.3, scale = \"log\" }]\n");
  EXPECT_NE(e.find("parameters[1].scale"), std::string::npos) << e;

  e = error_of(target + "parameters = []\n");
  EXPECT_NE(e.find("calibrate.stage[1].parameters"), std::string::npos) << e;

  e = error_of(target + kGoodParameters + "budget = 0\n");
  EXPECT_NE(e.find("calibrate.stage[1].budget"), std::string::npos) << e;

  e = error_of("target = { friction_angle_deg = 95, cohesion_kPa = 2 }\n" + kGoodParameters);
  EXPECT_NE(e.find("friction_angle_deg"), std::string::npos) << e;

  e = error_of("target = { peak_shear_stress_kPa = [30] }\n" + kGoodParameters);
  EXPECT_NE(e.find("one per normal stress"), std::string::npos) << e;

  // Consolidated heights: one per pressure, inside the box, with their weight.
  const std::string curves = "target = { curves = [\"both.csv\"], consolidated_height_mm = ";
  const CalibrationScenario h =
      parse(curves + "[2.9, 2.8] }\nheight_weight_kPa_per_um = 1\n" + kGoodParameters);
  EXPECT_DOUBLE_EQ(h.stages[0].curves[1].consolidated_height_m, 2.8e-3);
  EXPECT_DOUBLE_EQ(h.stages[0].weights.height_kPa_per_um, 1.0);
  e = error_of(curves + "[2.9] }\nheight_weight_kPa_per_um = 1\n" + kGoodParameters);
  EXPECT_NE(e.find("calibrate.stage[1].target.consolidated_height_mm"), std::string::npos) << e;
  e = error_of(curves + "[2.9, 6.5] }\nheight_weight_kPa_per_um = 1\n" + kGoodParameters);
  EXPECT_NE(e.find("consolidated_height_mm[1]"), std::string::npos) << e;
  e = error_of(curves + "[2.9, 2.8] }\n" + kGoodParameters);
  EXPECT_NE(e.find("calibrate.stage[1].height_weight_kPa_per_um"), std::string::npos) << e;
  e = error_of("target = { curves = [\"both.csv\"] }\nheight_weight_kPa_per_um = 1\n" +
               kGoodParameters);
  EXPECT_NE(e.find("consolidated_height_mm"), std::string::npos) << e;
  e = error_of("target = { peak_shear_stress_kPa = [30, 90], consolidated_height_mm = [2.9, 2.8] "
               "}\n" +
               kGoodParameters);
  EXPECT_NE(e.find("only beside measured curves"), std::string::npos) << e;
}

// Unload-reload moduli: one per pressure, positive, with their weight, and only
// when the scenario runs the loop (shear.unload_reload_fraction).
TEST_F(CalibrationConfig, UnloadReloadModuliNeedTheLoopAndAWeight) {
  const std::string loop = "set = [\"shear.unload_reload_fraction = 0.9\"]\n";
  const std::string weight = "modulus_weight_kPa_per_percent = 0.5\n";
  const std::string curves = "target = { curves = [\"both.csv\"], reloading_modulus_MPa = ";
  const CalibrationScenario c = parse(loop + curves + "[30, 45] }\n" + weight + kGoodParameters);
  EXPECT_DOUBLE_EQ(c.stages[0].curves[0].reloading_modulus_Pa, 30e6);
  EXPECT_DOUBLE_EQ(c.stages[0].curves[1].reloading_modulus_Pa, 45e6);
  EXPECT_DOUBLE_EQ(c.stages[0].curves[1].unloading_modulus_Pa, 0.0);
  EXPECT_DOUBLE_EQ(c.stages[0].weights.modulus_kPa_per_percent, 0.5);
  std::string e = error_of(curves + "[30, 45] }\n" + weight + kGoodParameters);
  EXPECT_NE(e.find("calibrate.stage[1].target.reloading_modulus_MPa"), std::string::npos) << e;
  EXPECT_NE(e.find("shear.unload_reload_fraction"), std::string::npos) << e;
  e = error_of(loop + curves + "[30] }\n" + weight + kGoodParameters);
  EXPECT_NE(e.find("one per normal stress"), std::string::npos) << e;
  e = error_of(loop + curves + "[30, -1] }\n" + weight + kGoodParameters);
  EXPECT_NE(e.find("reloading_modulus_MPa[1]"), std::string::npos) << e;
  e = error_of(loop + curves + "[30, 45] }\n" + kGoodParameters);
  EXPECT_NE(e.find("calibrate.stage[1].modulus_weight_kPa_per_percent"), std::string::npos) << e;
  e = error_of(loop + "target = { curves = [\"both.csv\"] }\n" + weight + kGoodParameters);
  EXPECT_NE(e.find("unloading_modulus_MPa or reloading_modulus_MPa"), std::string::npos) << e;
  e = error_of(loop +
               "target = { peak_shear_stress_kPa = [30, 90], unloading_modulus_MPa = "
               "[30, 45] }\n" +
               kGoodParameters);
  EXPECT_NE(e.find("only beside measured curves"), std::string::npos) << e;
}

// Affine moduli: one per pressure, positive, with the moduli's weight; every shear run measures
// them, so no loop is needed.
TEST_F(CalibrationConfig, AffineModuliNeedOnePerPressureAndAWeight) {
  const std::string weight = "modulus_weight_kPa_per_percent = 1\n";
  const std::string curves = "target = { curves = [\"both.csv\"], affine_modulus_MPa = ";
  const CalibrationScenario c = parse(curves + "[80, 87.5] }\n" + weight + kGoodParameters);
  EXPECT_DOUBLE_EQ(c.stages[0].curves[0].affine_modulus_Pa, 80e6);
  EXPECT_DOUBLE_EQ(c.stages[0].curves[1].affine_modulus_Pa, 87.5e6);
  EXPECT_DOUBLE_EQ(c.stages[0].curves[1].reloading_modulus_Pa, 0.0);
  std::string e = error_of(curves + "[80] }\n" + weight + kGoodParameters);
  EXPECT_NE(e.find("calibrate.stage[1].target.affine_modulus_MPa"), std::string::npos) << e;
  EXPECT_NE(e.find("one per normal stress"), std::string::npos) << e;
  e = error_of(curves + "[80, 0] }\n" + weight + kGoodParameters);
  EXPECT_NE(e.find("affine_modulus_MPa[1]"), std::string::npos) << e;
  e = error_of(curves + "[80, 87.5] }\n" + kGoodParameters);
  EXPECT_NE(e.find("calibrate.stage[1].modulus_weight_kPa_per_percent"), std::string::npos) << e;
  e = error_of("target = { peak_shear_stress_kPa = [30, 90], affine_modulus_MPa = [80, 87.5] }\n" +
               kGoodParameters);
  EXPECT_NE(e.find("only beside measured curves"), std::string::npos) << e;
}

// Two stages as the paper's: the second has its own pressures (its `set`) and
// builds on the first's fitted values, passed as overrides.
TEST_F(CalibrationConfig, SecondStageHasItsOwnSetAndBuildsOnTheFirst) {
  write("humid.csv", "normal_stress_kPa,shear_strain,shear_stress_kPa\n"
                     "20,0.0,0\n20,0.01,15\n60,0.0,0\n60,0.01,45\n");
  const CalibrationScenario c =
      parse("target = { curves = [\"both.csv\"] }\n" + kGoodParameters +
            "[[calibrate.stage]]\nname = \"humid\"\n"
            "set = [\"contact.ball_ball.model = 'arrlinear'\", "
            "\"shear.normal_stresses_Pa = [20e3, 60e3]\"]\n"
            "target = { curves = [\"humid.csv\"] }\n"
            "parameters = [{ key = \"contact.ball_ball.attraction_force_N\", min = 0.0, "
            "max = 5e-4, start = 1e-4 }]\n");
  ASSERT_EQ(c.stages.size(), 2u);
  const CalibrationStage& humid = c.stages[1];
  EXPECT_EQ(humid.name, "humid");
  EXPECT_EQ(humid.normal_stresses_Pa, (std::vector<double>{20e3, 60e3}));
  ASSERT_EQ(humid.curves.size(), 2u);
  const ShearScenario sc =
      stage_scenario(c, humid, {parameter_override(c.stages[0].parameters[0], 0.21)}, {3e-4});
  EXPECT_DOUBLE_EQ(sc.ball_ball.rolling_friction, 0.21); // the first stage's fit
  EXPECT_DOUBLE_EQ(sc.ball_ball.attraction_force_N, 3e-4);
  EXPECT_EQ(sc.ball_ball.model, ContactModel::arrlinear);
  // The first stage is untouched by the second's set.
  EXPECT_EQ(stage_scenario(c, c.stages[0], {}, {0.2}).normal_stresses_Pa,
            (std::vector<double>{50e3, 150e3}));
}

// The command line refuses a bad calibration with exit code 2 and the key.
TEST_F(CalibrationConfig, CommandExitsWithTwoOnBadInput) {
  write("cal.toml", scenario_with("target = { curves = [\"both.csv\"] }\n"
                                  "parameters = [{ key = \"contact.ball_ball.friction\", "
                                  "min = 0.1, max = 0.5, start = 0.7 }]\n"));
  const testutil::CliRun r = testutil::run_centridem(
      {"calibrate", (dir_ / "cal.toml").string(), "--out", (dir_ / "out").string()},
      dir_ / "log.txt", 60);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("calibrate.stage[1].parameters[1].start"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// --set reaches a calibration as it reaches the other subcommands (issue 19):
// a key changed on the command line is checked with the measured data.
TEST_F(CalibrationConfig, CommandTakesSetAndCheck) {
  write("cal.toml", scenario_with("target = { curves = [\"both.csv\"] }\n" + kGoodParameters));
  const std::string cal = (dir_ / "cal.toml").string();
  testutil::CliRun r = testutil::run_centridem(
      {"calibrate", cal, "--check", "--set", "contact.ball_ball.friction=0.3"}, dir_ / "ok.txt",
      60);
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("stage dry: 1 parameter(s)"), std::string::npos) << r.output;
  // Pressures changed by --set no longer match the measured file's.
  r = testutil::run_centridem(
      {"calibrate", cal, "--check", "--set", "shear.normal_stresses_Pa=[50e3, 100e3]"},
      dir_ / "bad.txt", 60);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("a curve at 150 kPa"), std::string::npos) << r.output;
}

// The calibration examples and the truth behind the replicates example are
// valid as they stand (their bricks and measured files present and matching):
// `centridem calibrate --check` on each.
TEST_F(CalibrationConfig, TheExamplesCheck) {
  const fs::path ex = fs::path(CENTRIDEM_SOURCE_DIR) / "examples";
  for (const fs::path f :
       {ex / "calibrate_small.toml", ex / "calibrate_mohr_coulomb.toml",
        ex / "calibrate_replicates.toml", ex / "data" / "calibrate_replicates" / "truth.toml"}) {
    const testutil::CliRun r = testutil::run_centridem(
        {"calibrate", f.string(), "--check", "--out", (dir_ / "unused").string()},
        dir_ / "check.txt", 60);
    EXPECT_EQ(r.code, 0) << f << "\n" << r.output;
  }
}

// One evaluation of two replicates on the CI shear box, end to end: each
// replicate runs in its own folder with its own seed, and the evaluation is
// judged by the mean of the two (replicates.json and mean_100kPa.csv hold
// what the misfit was computed from). About 10 s.
TEST_F(CalibrationConfig, AnEvaluationOfReplicatesIsJudgedByTheirMean) {
  write("cal.toml", std::string(testutil::kSmallShearBox) +
                        "\n[calibrate]\n[[calibrate.stage]]\nname = \"dry\"\n" + kGoodParameters +
                        "budget = 1\nreplicates = [\"specimen.seed = 11\", "
                        "\"specimen.seed = 12\"]\ntarget = { peak_shear_stress_kPa = [60] }\n");
  const fs::path out = dir_ / "out";
  const testutil::CliRun r = testutil::run_centridem(
      {"calibrate", (dir_ / "cal.toml").string(), "--out", out.string(), "--jobs", "1"},
      dir_ / "run.txt", 600);
  ASSERT_EQ(r.code, 0) << r.output;
  const fs::path ev = out / "dry" / "eval_001";
  // Each replicate ran with its own seed.
  std::vector<double> peaks;
  std::vector<std::vector<double>> strain(2), tau(2);
  for (int k = 1; k <= 2; ++k) {
    const fs::path rep = ev / ("replicate_" + std::to_string(k));
    std::ifstream toml(ev / ("replicate_" + std::to_string(k) + ".toml"));
    const std::string text{std::istreambuf_iterator<char>(toml), {}};
    EXPECT_NE(text.find("seed = " + std::to_string(10 + k)), std::string::npos) << text;
    std::ifstream in(rep / "shear_100kPa.json");
    ASSERT_TRUE(in) << rep;
    const nlohmann::json res = nlohmann::json::parse(in);
    peaks.push_back(res.at("peak_shear_stress_Pa").get<double>());
    for (const auto& q : res.at("curve_strain_tau_dz")) {
      const double e = q[0].get<double>();
      if (!strain[k - 1].empty() && !(e > strain[k - 1].back())) continue;
      strain[k - 1].push_back(e);
      tau[k - 1].push_back(q[1].get<double>());
    }
  }
  EXPECT_NE(peaks[0], peaks[1]); // two specimens, two curves
  // replicates.json: each replicate's peak, and their mean.
  std::ifstream rj(ev / "replicates.json");
  const nlohmann::json j = nlohmann::json::parse(rj);
  const nlohmann::json& pk = j.at("pressures").at(0).at("peak_shear_stress_Pa");
  EXPECT_DOUBLE_EQ(pk.at("per_replicate").at(0).get<double>(), peaks[0]);
  EXPECT_DOUBLE_EQ(pk.at("per_replicate").at(1).get<double>(), peaks[1]);
  EXPECT_NEAR(pk.at("mean").get<double>(), (peaks[0] + peaks[1]) / 2, 1e-9 * peaks[0]);
  // mean_100kPa.csv: at each of the first replicate's strains inside both
  // runs, the mean of the first's stress and the second's interpolated there.
  const std::vector<MeasuredCurve> mean =
      read_measured_curves((ev / "mean_100kPa.csv").string(), 3e-3);
  ASSERT_EQ(mean.size(), 1u);
  ASSERT_GT(mean[0].strain.size(), 10u);
  for (std::size_t k = 0; k < mean[0].strain.size(); ++k) {
    const double e = mean[0].strain[k];
    const double expected =
        (interpolate(strain[0], tau[0], e) + interpolate(strain[1], tau[1], e)) / 2;
    EXPECT_NEAR(mean[0].shear_stress_Pa[k], expected, 1e-9 * 100e3 + 1e-6 * std::abs(expected))
        << "at strain " << e;
  }
  // The misfit is the mean curve's peak against 60 kPa.
  const double mean_peak =
      *std::max_element(mean[0].shear_stress_Pa.begin(), mean[0].shear_stress_Pa.end());
  std::ifstream sj(out / "summary.json");
  const nlohmann::json st = nlohmann::json::parse(sj).at("stages").at(0);
  EXPECT_NEAR(st.at("misfit").get<double>(), std::abs(mean_peak / 1e3 - 60.0), 1e-6) << st.dump(1);
}

} // namespace
