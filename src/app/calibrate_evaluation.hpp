// The record and the results of a calibration's evaluations (`centridem
// calibrate`, docs/calibrate.md): the history CSV of a stage (one line per
// finished evaluation, what --resume replays), and the comparison of a
// finished evaluation folder with the stage's target: one shear run, or one
// per replicate and their mean (mean_of_replicates).
#pragma once

#include "procedures/calibration.hpp"
#include "procedures/calibration_config.hpp"

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace centridem {

// A stress in kPa as the file and folder names write it ("50", "150").
std::string kpa_text(double Pa);

// The history CSV: the names of a stage's misfit parts, its header, one line,
// and the lines of an earlier run (none when the file does not exist; a
// header of another calibration or a broken line is an InputError naming the
// file and line).
std::vector<std::string> part_names(const CalibrationStage& st);
std::string history_header(const CalibrationStage& st);
std::string history_line(const Evaluation& e);
std::vector<Evaluation> read_history(const std::filesystem::path& path, const CalibrationStage& st);

// The folder of replicate k (0-based) inside an evaluation's folder.
std::string replicate_folder(std::size_t k);

// The result an evaluation is judged by at one pressure: its run's curve, or
// with replicates the mean of their runs.
SimulatedCurve evaluation_curve(const CalibrationStage& st, const std::filesystem::path& run,
                                double sigma);

// Beside the replicates of an evaluation, each file replaced whole (a stopped
// run never leaves half a file): mean_<kPa>kPa.csv (the mean curve in the
// columns a measured curve is read in, so a mean can be given as a target)
// and replicates.json (each replicate's overrides, peak, height and
// moduli, their mean and standard deviation).
void write_replicate_means(const CalibrationStage& st, const std::filesystem::path& run);

// Fills e.misfit and e.parts from a finished evaluation folder.
void compare_with_target(const CalibrationStage& st, const std::filesystem::path& run,
                         Evaluation& e);

} // namespace centridem
