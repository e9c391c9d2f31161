// A calibration scenario (`centridem calibrate`, docs/calibrate.md): a shear
// scenario (docs/shear.md) plus a [calibrate] table with one
// [[calibrate.stage]] per stage, each naming its target (measured curves in
// CSV files, a Mohr-Coulomb envelope, or peak shear stresses), the parameters
// to fit (dotted scenario keys with bounds and a start), optional `set`
// overrides of the scenario for that stage, a budget and a tolerance. Stages
// run in order; each later stage starts from the earlier stages' fitted
// values. Every mistake is an InputError naming the dotted key (or FILE line N)
// and what is allowed.
#pragma once

#include "procedures/calibration.hpp"
#include "procedures/shear_config.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace centridem {

enum class CalibrationTargetKind { curves, mohr_coulomb, peak_stresses };

struct CalibrationStage {
  std::string name;                             // also the stage's output folder
  std::vector<std::string> set;                 // KEY = VALUE overrides for this stage
  std::vector<CalibrationParameter> parameters; // in the order given
  CalibrationTargetKind kind = CalibrationTargetKind::curves;
  std::vector<MeasuredCurve> curves;        // kind curves: by rising normal stress
  MohrCoulombTarget mohr_coulomb;           // kind mohr_coulomb (peak envelope)
  std::vector<double> peak_shear_stress_Pa; // kind peak_stresses: one per pressure, rising
  CurveWeights weights;                     // kind curves
  OptimiserSettings optimiser;              // budget, tolerance
  std::vector<double> normal_stresses_Pa;   // the stage scenario's pressures, rising
  // Replicate specimens (`replicates`): each evaluation runs the shear test
  // once per replicate, with that replicate's KEY = VALUE overrides applied
  // last (another specimen.seed, another specimen.file), and compares the
  // mean of the runs (mean_of_replicates); empty: one run.
  std::vector<std::vector<std::string>> replicates;
  std::string misfit_unit() const; // "kPa" or "deg & kPa"
};

struct CalibrationScenario {
  std::string source;   // the file (or "FILE (with --set)")
  std::string base_dir; // relative CSV paths start here
  std::string text;     // the whole scenario text (with --set merged)
  std::vector<CalibrationStage> stages;
};

// Reads the [calibrate] table of `text` and checks each stage against the
// shear scenario it builds: every parameter key set to its start must give a
// valid scenario, and the measured curves must match the stage's pressures.
CalibrationScenario parse_calibration(std::string_view text, const std::string& source,
                                      const std::string& base_dir);
CalibrationScenario load_calibration(const std::string& path,
                                     const std::vector<std::string>& overrides = {});

// `KEY = VALUE` for a parameter value (17 significant digits: reads back exactly).
std::string parameter_override(const CalibrationParameter& p, double value);

// The shear scenario of a stage at the given parameter values, after the
// overrides of the stages before it (`earlier`, KEY = VALUE lines).
// `replicate`: one of the stage's replicates, whose overrides come last.
ShearScenario stage_scenario(const CalibrationScenario& c, const CalibrationStage& stage,
                             const std::vector<std::string>& earlier,
                             const std::vector<double>& values,
                             const std::vector<std::string>& replicate = {});

// Reads measured curves from a CSV file with a header naming its columns
// (any order): shear_strain | shear_strain_percent | shear_displacement_mm |
// shear_displacement_m; shear_stress_kPa | shear_stress_Pa; optionally
// normal_stress_kPa | normal_stress_Pa (else `normal_stress_Pa` must be given,
// > 0) and vertical_displacement_mm | vertical_displacement_m. Displacements
// become strains over `strain_length_m` (the box height or length, as
// shear.strain says). Strains must rise within each pressure. Errors name the
// file and line.
std::vector<MeasuredCurve> read_measured_curves(const std::string& path, double strain_length_m,
                                                double normal_stress_Pa = 0);

} // namespace centridem
