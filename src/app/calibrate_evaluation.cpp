#include "app/calibrate_evaluation.hpp"

#include "app/cmd_shear.hpp"

#include "base/errors.hpp"
#include "io/csv.hpp"
#include "io/output.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace centridem {

namespace fs = std::filesystem;

std::string kpa_text(double Pa) {
  return fmt::format("{:g}", Pa / 1e3);
}

namespace {

// A shear run's result at one pressure, as the calibration compares it.
SimulatedCurve simulated_curve(const fs::path& run, double sigma) {
  const fs::path p = run / (shear_run_stem(sigma) + ".json");
  std::ifstream in(p);
  if (!in) throw std::runtime_error("missing shear result " + p.string());
  const nlohmann::json j = nlohmann::json::parse(in);
  SimulatedCurve c;
  c.normal_stress_Pa = sigma;
  c.consolidated_height_m = j.at("consolidated_height_m").get<double>();
  c.affine_modulus_Pa = j.value("consolidated_affine_modulus_Pa", 0.0);
  if (j.contains("unload_reload")) {
    c.unloading_modulus_Pa = j.at("unload_reload").at("unloading_modulus_Pa").get<double>();
    c.reloading_modulus_Pa = j.at("unload_reload").at("reloading_modulus_Pa").get<double>();
  }
  for (const auto& q : j.at("curve_strain_tau_dz")) {
    const double e = q[0].get<double>();
    if (!c.strain.empty() && !(e > c.strain.back())) continue; // keep the strains rising
    c.strain.push_back(e);
    c.shear_stress_Pa.push_back(q[1].get<double>());
    c.vertical_displacement_m.push_back(q[2].get<double>());
  }
  return c;
}

} // namespace

// ---- the history of a stage: one CSV line per finished evaluation ----------

std::vector<std::string> part_names(const CalibrationStage& st) {
  std::vector<std::string> n;
  switch (st.kind) {
  case CalibrationTargetKind::curves:
    for (double s : st.normal_stresses_Pa) n.push_back("misfit_at_" + kpa_text(s) + "kPa_kPa");
    if (st.weights.height_kPa_per_um > 0)
      for (double s : st.normal_stresses_Pa)
        n.push_back("height_difference_at_" + kpa_text(s) + "kPa_um");
    if (st.curves.front().unloading_modulus_Pa > 0)
      for (double s : st.normal_stresses_Pa)
        n.push_back("unloading_modulus_difference_at_" + kpa_text(s) + "kPa_percent");
    if (st.curves.front().reloading_modulus_Pa > 0)
      for (double s : st.normal_stresses_Pa)
        n.push_back("reloading_modulus_difference_at_" + kpa_text(s) + "kPa_percent");
    if (st.curves.front().affine_modulus_Pa > 0)
      for (double s : st.normal_stresses_Pa)
        n.push_back("affine_modulus_difference_at_" + kpa_text(s) + "kPa_percent");
    break;
  case CalibrationTargetKind::peak_stresses:
    for (double s : st.normal_stresses_Pa)
      n.push_back("peak_difference_at_" + kpa_text(s) + "kPa_kPa");
    break;
  case CalibrationTargetKind::mohr_coulomb:
    n = {"friction_angle_difference_deg", "cohesion_difference_kPa"};
    break;
  }
  return n;
}

std::string history_header(const CalibrationStage& st) {
  std::string h = "evaluation";
  for (const CalibrationParameter& p : st.parameters) h += "," + p.key;
  h += st.kind == CalibrationTargetKind::mohr_coulomb ? ",misfit_deg_and_kPa" : ",misfit_kPa";
  for (const std::string& n : part_names(st)) h += "," + n;
  return h + ",wall_s,folder";
}

std::string history_line(const Evaluation& e) {
  std::string l = std::to_string(e.index);
  for (double v : e.values) l += fmt::format(",{:.17g}", v);
  l += fmt::format(",{:.17g}", e.misfit);
  for (double v : e.parts) l += fmt::format(",{:.17g}", v);
  return l + fmt::format(",{:.3f},{}", e.wall_seconds, e.folder);
}

std::vector<Evaluation> read_history(const fs::path& path, const CalibrationStage& st) {
  std::vector<Evaluation> h;
  std::ifstream in(path);
  if (!in) return h;
  std::string line;
  std::getline(in, line);
  const std::string header = history_header(st);
  if (std::string(trim_blanks(line)) != header)
    throw InputError(path.string() + " line 1", "\"" + line + "\"",
                     "the header \"" + header +
                         "\" of this stage: the calibration changed since the history was "
                         "written; start a new output folder");
  const std::size_t np = st.parameters.size(), nparts = part_names(st).size();
  long n = 1;
  while (std::getline(in, line)) {
    ++n;
    if (trim_blanks(line).empty()) continue;
    const std::vector<std::string_view> f = split_commas(line);
    const std::string where = fmt::format("{} line {}", path.string(), n);
    if (f.size() != np + nparts + 4)
      throw InputError(where, "\"" + line + "\"",
                       fmt::format("{} comma-separated fields", np + nparts + 4));
    Evaluation e;
    e.index = static_cast<int>(parse_finite_number(f[0], where + " column 1"));
    if (e.index != static_cast<int>(h.size()) + 1)
      throw InputError(where, std::string(f[0]), fmt::format("evaluation {}", h.size() + 1));
    for (std::size_t k = 0; k < np; ++k)
      e.values.push_back(parse_finite_number(f[1 + k], fmt::format("{} column {}", where, k + 2)));
    // An evaluation whose comparison failed is recorded as inf.
    const std::string m(f[1 + np]);
    e.misfit = m == "inf" ? std::numeric_limits<double>::infinity()
                          : parse_finite_number(f[1 + np], where + " (misfit)");
    for (std::size_t k = 0; k < nparts; ++k) {
      const std::string v(f[2 + np + k]);
      e.parts.push_back(v == "inf" ? std::numeric_limits<double>::infinity()
                                   : parse_finite_number(f[2 + np + k], where));
    }
    e.wall_seconds = parse_finite_number(f[2 + np + nparts], where + " (wall_s)");
    e.folder = std::string(f[3 + np + nparts]);
    h.push_back(std::move(e));
  }
  return h;
}

// ---- replicate specimens (stage.replicates) ----------------------------------

std::string replicate_folder(std::size_t k) {
  return fmt::format("replicate_{}", k + 1);
}

namespace {

// Each replicate's result at one pressure, in the order of stage.replicates.
std::vector<SimulatedCurve> replicate_curves(const CalibrationStage& st, const fs::path& run,
                                             double sigma) {
  std::vector<SimulatedCurve> r;
  for (std::size_t k = 0; k < st.replicates.size(); ++k)
    r.push_back(simulated_curve(run / replicate_folder(k), sigma));
  return r;
}

// The values, their mean and sample standard deviation, for replicates.json.
nlohmann::json spread(const std::vector<double>& v) {
  double mean = 0, var = 0;
  for (double x : v) mean += x / static_cast<double>(v.size());
  for (double x : v) var += (x - mean) * (x - mean);
  const double sd = v.size() > 1 ? std::sqrt(var / static_cast<double>(v.size() - 1)) : 0.0;
  return {{"per_replicate", v}, {"mean", mean}, {"standard_deviation", sd}};
}

} // namespace

SimulatedCurve evaluation_curve(const CalibrationStage& st, const fs::path& run, double sigma) {
  if (st.replicates.empty()) return simulated_curve(run, sigma);
  return mean_of_replicates(replicate_curves(st, run, sigma));
}

void write_replicate_means(const CalibrationStage& st, const fs::path& run) {
  nlohmann::json j = {{"replicates", st.replicates}, {"pressures", nlohmann::json::array()}};
  for (double sigma : st.normal_stresses_Pa) {
    const std::vector<SimulatedCurve> r = replicate_curves(st, run, sigma);
    const SimulatedCurve m = mean_of_replicates(r);
    const std::string csv_name = "mean_" + kpa_text(sigma) + "kPa.csv";
    std::string csv = "shear_strain,shear_stress_Pa,normal_stress_Pa,vertical_displacement_m\n";
    for (std::size_t k = 0; k < m.strain.size(); ++k)
      csv += fmt::format("{:.12g},{:.12g},{:.12g},{:.12g}\n", m.strain[k], m.shear_stress_Pa[k],
                         sigma, m.vertical_displacement_m[k]);
    replace_text_file((run / csv_name).string(), csv);
    std::vector<double> peak, height, unloading, reloading, affine;
    for (const SimulatedCurve& c : r) {
      peak.push_back(c.shear_stress_Pa.empty()
                         ? 0.0
                         : *std::max_element(c.shear_stress_Pa.begin(), c.shear_stress_Pa.end()));
      height.push_back(c.consolidated_height_m);
      unloading.push_back(c.unloading_modulus_Pa);
      reloading.push_back(c.reloading_modulus_Pa);
      affine.push_back(c.affine_modulus_Pa);
    }
    j["pressures"].push_back({{"normal_stress_Pa", sigma},
                              {"mean_curve", csv_name},
                              {"peak_shear_stress_Pa", spread(peak)},
                              {"consolidated_height_m", spread(height)},
                              {"unloading_modulus_Pa", spread(unloading)},
                              {"reloading_modulus_Pa", spread(reloading)},
                              {"affine_modulus_Pa", spread(affine)}});
  }
  replace_text_file((run / "replicates.json").string(), j.dump(1) + "\n");
}

// Compares a finished run folder with the stage's target.
void compare_with_target(const CalibrationStage& st, const fs::path& run, Evaluation& e) {
  e.parts.clear();
  switch (st.kind) {
  case CalibrationTargetKind::curves: {
    std::vector<CurveMisfit> per;
    for (const MeasuredCurve& m : st.curves) {
      per.push_back(curve_misfit(m, evaluation_curve(st, run, m.normal_stress_Pa), st.weights));
      e.parts.push_back(per.back().total_Pa / 1e3);
    }
    if (st.weights.height_kPa_per_um > 0)
      for (const CurveMisfit& m : per) e.parts.push_back(m.height_difference_m * 1e6);
    if (st.curves.front().unloading_modulus_Pa > 0)
      for (const CurveMisfit& m : per) e.parts.push_back(m.unloading_modulus_difference * 100);
    if (st.curves.front().reloading_modulus_Pa > 0)
      for (const CurveMisfit& m : per) e.parts.push_back(m.reloading_modulus_difference * 100);
    if (st.curves.front().affine_modulus_Pa > 0)
      for (const CurveMisfit& m : per) e.parts.push_back(m.affine_modulus_difference * 100);
    e.misfit = overall_misfit(per) / 1e3;
    break;
  }
  case CalibrationTargetKind::peak_stresses: {
    std::vector<double> peaks;
    for (std::size_t k = 0; k < st.normal_stresses_Pa.size(); ++k) {
      const SimulatedCurve c = evaluation_curve(st, run, st.normal_stresses_Pa[k]);
      peaks.push_back(*std::max_element(c.shear_stress_Pa.begin(), c.shear_stress_Pa.end()));
      e.parts.push_back((peaks.back() - st.peak_shear_stress_Pa[k]) / 1e3);
    }
    e.misfit = peak_stress_misfit(st.peak_shear_stress_Pa, peaks) / 1e3;
    break;
  }
  case CalibrationTargetKind::mohr_coulomb: {
    std::vector<double> peaks;
    for (double s : st.normal_stresses_Pa) {
      const SimulatedCurve c = evaluation_curve(st, run, s);
      peaks.push_back(*std::max_element(c.shear_stress_Pa.begin(), c.shear_stress_Pa.end()));
    }
    const MohrCoulombFit f = fit_mohr_coulomb(st.normal_stresses_Pa, peaks);
    const MohrCoulombMisfit m =
        mohr_coulomb_misfit(st.mohr_coulomb, f.friction_angle_deg, f.cohesion_Pa);
    e.parts = {m.friction_angle_difference_deg, m.cohesion_difference_Pa / 1e3};
    e.misfit = m.total;
    break;
  }
  }
}

} // namespace centridem
