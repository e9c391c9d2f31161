// Calibration of contact parameters against measured direct shear results
// (`centridem calibrate`, docs/calibrate.md): the misfit between measured and
// simulated results, and the optimiser loop that drives it. Nothing here runs
// a simulation: the loop calls an Evaluator (the command runs the shear test
// there; the tests give it an analytic function), so the loop, its stopping
// rules and its resume can be tested in milliseconds.
//
// The optimiser is NLopt's BOBYQA (M. J. D. Powell, "The BOBYQA algorithm for
// bound constrained optimization without derivatives", Cambridge report
// DAMTP 2009/NA06): a quadratic model of the misfit built from 2n + 1 points,
// refined inside a trust region; derivative-free and bound-constrained. It
// works on each parameter scaled to [0, 1] of its bounds (logarithmically for
// parameters spanning decades, such as a modulus).
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace centridem {

// ---- targets and misfits -------------------------------------------------

// One measured shear curve at one normal stress (strain as the scenario's
// shear.strain defines it).
struct MeasuredCurve {
  double normal_stress_Pa = 0;
  std::vector<double> strain;                  // rising [-]
  std::vector<double> shear_stress_Pa;         // [Pa]
  std::vector<double> vertical_displacement_m; // + dilation; empty when not measured [m]
  // The specimen's height after consolidation, before shearing; 0 when not
  // measured [m]. It sees the contact stiffness without the rolling
  // resistance, which the curves mix (docs/results/calibrate.md).
  double consolidated_height_m = 0;
  // The constrained moduli of an unload-reload loop after consolidation
  // (shear.unload_reload_fraction; docs/shear.md); 0 when not measured [Pa].
  double unloading_modulus_Pa = 0;
  double reloading_modulus_Pa = 0;
  // The consolidated packing's affine vertical modulus (World::affine_modulus_Pa: the contact
  // springs met by a uniform strain before any grain moves); 0 when not given [Pa]. It follows
  // E* and the fabric, and hardly the chaos that makes the loop's moduli noisy
  // (docs/results/calibrate.md section 7). A simulated quantity: a laboratory's nearest one is
  // the small-strain modulus of a bender element or resonant column, which it bounds from above in
  // a large specimen.
  double affine_modulus_Pa = 0;
  std::string source; // the file, for messages
};

// A simulated curve: the points of a shear run's result.
struct SimulatedCurve {
  double normal_stress_Pa = 0;
  std::vector<double> strain;                  // rising [-]
  std::vector<double> shear_stress_Pa;         // [Pa]
  std::vector<double> vertical_displacement_m; // + dilation [m]
  double consolidated_height_m = 0;            // after consolidation [m]
  double unloading_modulus_Pa = 0;             // of the unload-reload loop; 0: none run [Pa]
  double reloading_modulus_Pa = 0;             // [Pa]
  double affine_modulus_Pa = 0;                // after consolidation [Pa]
};

// The mean of replicate runs at one pressure (specimens of different seeds:
// `seeds` in a calibration stage, docs/calibrate.md "Replicates"): the curve on
// the first replicate's strains that every replicate reaches (each other one
// linearly interpolated there), shear stress and vertical displacement
// averaged; the consolidated heights and the loop's moduli averaged. The
// mean of n replicates scatters sqrt(n) times less than one run. One replicate
// is returned as it is. Throws std::invalid_argument for none, or for
// replicates at different pressures. Replicates without a common strain range
// give an empty curve (an infinite misfit).
SimulatedCurve mean_of_replicates(const std::vector<SimulatedCurve>& replicates);

// Optional terms beside the shear stress RMS.
struct CurveWeights {
  double peak = 0;                    // weight of the squared peak difference [-]
  double dilation_kPa_per_mm = 0;     // turns the vertical displacement RMS into kPa [kPa/mm]
  double height_kPa_per_um = 0;       // turns the consolidated height difference into kPa [kPa/um]
  double modulus_kPa_per_percent = 0; // turns a modulus's relative difference into kPa [kPa/%]
};

struct CurveMisfit {
  double normal_stress_Pa = 0;
  double rms_shear_stress_Pa = 0;         // over the measured points inside the simulated range
  double peak_difference_Pa = 0;          // simulated peak - measured peak
  double rms_vertical_displacement_m = 0; // 0 when not measured
  double height_difference_m = 0;         // consolidated height, simulated - measured (0: none)
  // The unload-reload moduli, simulated / measured - 1 (0: not measured) [-].
  double unloading_modulus_difference = 0;
  double reloading_modulus_difference = 0;
  double affine_modulus_difference = 0; // the affine modulus, likewise [-]
  // sqrt(rms^2 + w_p dpeak^2 + (w_d rms_dz)^2 + (w_h dh)^2 + (w_m 100 dMu)^2 + (w_m 100 dMr)^2
  //      + (w_m 100 dMa)^2)
  double total_Pa = 0;
  std::size_t points = 0; // measured points compared
};

// The simulated series at x by linear interpolation; x must lie inside
// [xs.front(), xs.back()] (xs rising).
double interpolate(const std::vector<double>& xs, const std::vector<double>& ys, double x);

// The misfit of one pressure: the simulated curve interpolated at each
// measured strain that it reaches (points beyond its last strain are left
// out and `points` says how many were compared; none compared gives an
// infinite misfit).
CurveMisfit curve_misfit(const MeasuredCurve& measured, const SimulatedCurve& simulated,
                         const CurveWeights& weights);

// The overall misfit of several pressures: sqrt of the mean of their squared
// totals [Pa].
double overall_misfit(const std::vector<CurveMisfit>& per_pressure);

// A Mohr-Coulomb target (peak strength envelope) and its misfit: degrees and
// kPa counted alike, total = sqrt(dphi_deg^2 + (dc / 1 kPa)^2).
struct MohrCoulombTarget {
  double friction_angle_deg = 0;
  double cohesion_Pa = 0;
};
struct MohrCoulombMisfit {
  double friction_angle_difference_deg = 0; // simulated - target
  double cohesion_difference_Pa = 0;        // simulated - target
  double total = 0;                         // [deg and kPa alike]
};
MohrCoulombMisfit mohr_coulomb_misfit(const MohrCoulombTarget& target,
                                      double simulated_friction_angle_deg,
                                      double simulated_cohesion_Pa);

// RMS of simulated - measured peak shear stresses, one per pressure [Pa].
double peak_stress_misfit(const std::vector<double>& measured_Pa,
                          const std::vector<double>& simulated_Pa);

// ---- parameters and the optimiser loop -----------------------------------

// One parameter to fit: a dotted scenario key (contact.ball_ball.friction,
// preparation.porosity, ...) with bounds and a start inside them.
struct CalibrationParameter {
  std::string key;
  double min = 0, max = 0, start = 0; // in the key's own unit
  bool log_scale = false;             // search in log(value) (min > 0)
};

// Where `value` lies in [0, 1] of the parameter's range, and back.
double to_unit(const CalibrationParameter& p, double value);
double from_unit(const CalibrationParameter& p, double u);

// One evaluation: the parameter values, the misfit and its parts.
struct Evaluation {
  int index = 0;              // 1, 2, ... within its stage
  std::vector<double> values; // one per parameter
  double misfit = 0;          // in the stage's misfit unit (kPa, or deg and kPa alike)
  std::vector<double> parts;  // per pressure [kPa], or dphi [deg] and dc [kPa]
  double wall_seconds = 0;
  std::string folder; // the simulation's run folder ("" for stand-ins)
};

struct OptimiserSettings {
  int budget = 30;                   // the most evaluations
  double tolerance = 0;              // stop once the misfit is at or below this (0: never early)
  double initial_step = 0.25;        // first trust-region radius, as a fraction of each range [-]
  double unit_step_tolerance = 1e-3; // stop when steps shrink below this fraction of a range [-]
  // Restarts from the best point when BOBYQA converges with budget left (a
  // noisy misfit; calibration.cpp) [-]
  int restarts = 0;
};

struct OptimiserResult {
  std::vector<Evaluation> history; // every evaluation, replayed or new, in order
  std::size_t best = 0;            // index into history of the lowest misfit
  std::string stop_reason;         // for the summary
  int restarts = 0;                // BOBYQA restarts from the best point
};

// Runs a simulation at `values` and returns its evaluation (index and values
// filled in by the loop when left empty).
using Evaluator = std::function<Evaluation(int index, const std::vector<double>& values)>;
// Called after each evaluation, with replayed = true for those taken from
// `recorded` instead of being run.
using EvaluationDone = std::function<void(const Evaluation&, bool replayed)>;

// Minimises the misfit over the parameters' box with BOBYQA, starting at the
// parameters' starts. `recorded` holds the evaluations of an earlier run of
// the same calibration that stopped: the optimiser is deterministic, so it
// asks for the same points in the same order, and those are answered from the
// record without calling `evaluate`. A point that differs from the record's
// throws InputError (the calibration or its inputs changed since). An
// exception thrown by `evaluate` (Interrupted, InstabilityError) stops the
// loop and propagates unchanged. Needs at least one parameter.
OptimiserResult run_optimiser(const std::vector<CalibrationParameter>& parameters,
                              const OptimiserSettings& settings, const Evaluator& evaluate,
                              const std::vector<Evaluation>& recorded = {},
                              const EvaluationDone& on_done = {});

} // namespace centridem
