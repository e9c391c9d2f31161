#include "procedures/calibration.hpp"

#include "base/errors.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <fmt/format.h>
#include <limits>
#include <memory>
#include <nlopt.h>
#include <stdexcept>
#include <type_traits>

namespace centridem {

double interpolate(const std::vector<double>& xs, const std::vector<double>& ys, double x) {
  if (xs.empty() || xs.size() != ys.size())
    throw std::logic_error("interpolate: series of different lengths or empty");
  if (x <= xs.front()) return ys.front();
  if (x >= xs.back()) return ys.back();
  const auto hi = std::upper_bound(xs.begin(), xs.end(), x);
  const std::size_t k = static_cast<std::size_t>(hi - xs.begin());
  const double x0 = xs[k - 1], x1 = xs[k];
  if (x1 <= x0) return ys[k];
  const double w = (x - x0) / (x1 - x0);
  return ys[k - 1] + w * (ys[k] - ys[k - 1]);
}

SimulatedCurve mean_of_replicates(const std::vector<SimulatedCurve>& replicates) {
  if (replicates.empty()) throw std::invalid_argument("mean_of_replicates: no replicate");
  const SimulatedCurve& first = replicates.front();
  if (replicates.size() == 1) return first;
  const double n = static_cast<double>(replicates.size());
  SimulatedCurve m;
  m.normal_stress_Pa = first.normal_stress_Pa;
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  for (const SimulatedCurve& r : replicates) {
    if (r.normal_stress_Pa != first.normal_stress_Pa)
      throw std::invalid_argument("mean_of_replicates: replicates at different normal stresses");
    m.consolidated_height_m += r.consolidated_height_m / n;
    m.unloading_modulus_Pa += r.unloading_modulus_Pa / n;
    m.reloading_modulus_Pa += r.reloading_modulus_Pa / n;
    m.affine_modulus_Pa += r.affine_modulus_Pa / n;
    if (r.strain.empty()) return m; // nothing in common: no curve
    lo = std::max(lo, r.strain.front());
    hi = std::min(hi, r.strain.back());
  }
  for (std::size_t k = 0; k < first.strain.size(); ++k) {
    const double e = first.strain[k];
    if (e < lo || e > hi) continue;
    double tau = 0, dz = 0;
    for (const SimulatedCurve& r : replicates) {
      tau += interpolate(r.strain, r.shear_stress_Pa, e);
      dz += interpolate(r.strain, r.vertical_displacement_m, e);
    }
    m.strain.push_back(e);
    m.shear_stress_Pa.push_back(tau / n);
    m.vertical_displacement_m.push_back(dz / n);
  }
  return m;
}

CurveMisfit curve_misfit(const MeasuredCurve& measured, const SimulatedCurve& simulated,
                         const CurveWeights& weights) {
  CurveMisfit m;
  m.normal_stress_Pa = measured.normal_stress_Pa;
  if (simulated.strain.empty() || measured.strain.empty()) {
    m.total_Pa = m.rms_shear_stress_Pa = std::numeric_limits<double>::infinity();
    return m;
  }
  const double first = simulated.strain.front(), last = simulated.strain.back();
  const bool with_dz = !measured.vertical_displacement_m.empty() &&
                       simulated.vertical_displacement_m.size() == simulated.strain.size();
  double sum_tau = 0, sum_dz = 0;
  for (std::size_t k = 0; k < measured.strain.size(); ++k) {
    const double e = measured.strain[k];
    if (e < first || e > last) continue;
    const double dt =
        interpolate(simulated.strain, simulated.shear_stress_Pa, e) - measured.shear_stress_Pa[k];
    sum_tau += dt * dt;
    if (with_dz) {
      const double dz = interpolate(simulated.strain, simulated.vertical_displacement_m, e) -
                        measured.vertical_displacement_m[k];
      sum_dz += dz * dz;
    }
    ++m.points;
  }
  if (m.points == 0) {
    m.total_Pa = m.rms_shear_stress_Pa = std::numeric_limits<double>::infinity();
    return m;
  }
  const double n = static_cast<double>(m.points);
  m.rms_shear_stress_Pa = std::sqrt(sum_tau / n);
  m.rms_vertical_displacement_m = with_dz ? std::sqrt(sum_dz / n) : 0.0;
  // The peaks: the largest stress of each curve (the measured one over its
  // whole length, the simulated one over the strains it reached).
  m.peak_difference_Pa =
      *std::max_element(simulated.shear_stress_Pa.begin(), simulated.shear_stress_Pa.end()) -
      *std::max_element(measured.shear_stress_Pa.begin(), measured.shear_stress_Pa.end());
  // Dilation in kPa: (weight kPa/mm) x (RMS mm) x 1000 Pa/kPa.
  const double dz_Pa = weights.dilation_kPa_per_mm * (m.rms_vertical_displacement_m * 1e3) * 1e3;
  // Consolidated height in kPa: (weight kPa/um) x (difference um) x 1000 Pa/kPa.
  if (measured.consolidated_height_m > 0)
    m.height_difference_m = simulated.consolidated_height_m - measured.consolidated_height_m;
  const double dh_Pa = weights.height_kPa_per_um * (m.height_difference_m * 1e6) * 1e3;
  // Moduli in kPa: (weight kPa/%) x (relative difference x 100 %) x 1000 Pa/kPa. A modulus
  // measured but not simulated (no loop run) counts as -100 %.
  auto relative = [](double sim, double meas) { return meas > 0 ? sim / meas - 1.0 : 0.0; };
  m.unloading_modulus_difference =
      relative(simulated.unloading_modulus_Pa, measured.unloading_modulus_Pa);
  m.reloading_modulus_difference =
      relative(simulated.reloading_modulus_Pa, measured.reloading_modulus_Pa);
  const double du_Pa =
      weights.modulus_kPa_per_percent * (m.unloading_modulus_difference * 100) * 1e3;
  const double dr_Pa =
      weights.modulus_kPa_per_percent * (m.reloading_modulus_difference * 100) * 1e3;
  m.affine_modulus_difference = relative(simulated.affine_modulus_Pa, measured.affine_modulus_Pa);
  const double da_Pa = weights.modulus_kPa_per_percent * (m.affine_modulus_difference * 100) * 1e3;
  m.total_Pa =
      std::sqrt(m.rms_shear_stress_Pa * m.rms_shear_stress_Pa +
                weights.peak * m.peak_difference_Pa * m.peak_difference_Pa + dz_Pa * dz_Pa +
                dh_Pa * dh_Pa + du_Pa * du_Pa + dr_Pa * dr_Pa + da_Pa * da_Pa);
  return m;
}

double overall_misfit(const std::vector<CurveMisfit>& per_pressure) {
  if (per_pressure.empty()) return std::numeric_limits<double>::infinity();
  double sum = 0;
  for (const CurveMisfit& m : per_pressure) sum += m.total_Pa * m.total_Pa;
  return std::sqrt(sum / static_cast<double>(per_pressure.size()));
}

MohrCoulombMisfit mohr_coulomb_misfit(const MohrCoulombTarget& target,
                                      double simulated_friction_angle_deg,
                                      double simulated_cohesion_Pa) {
  MohrCoulombMisfit m;
  m.friction_angle_difference_deg = simulated_friction_angle_deg - target.friction_angle_deg;
  m.cohesion_difference_Pa = simulated_cohesion_Pa - target.cohesion_Pa;
  const double dc_kPa = m.cohesion_difference_Pa / 1e3;
  m.total = std::sqrt(m.friction_angle_difference_deg * m.friction_angle_difference_deg +
                      dc_kPa * dc_kPa);
  return m;
}

double peak_stress_misfit(const std::vector<double>& measured_Pa,
                          const std::vector<double>& simulated_Pa) {
  if (measured_Pa.empty() || measured_Pa.size() != simulated_Pa.size())
    throw std::logic_error("peak_stress_misfit: one simulated peak per measured one");
  double sum = 0;
  for (std::size_t k = 0; k < measured_Pa.size(); ++k) {
    const double d = simulated_Pa[k] - measured_Pa[k];
    sum += d * d;
  }
  return std::sqrt(sum / static_cast<double>(measured_Pa.size()));
}

double to_unit(const CalibrationParameter& p, double value) {
  if (p.log_scale) return std::log(value / p.min) / std::log(p.max / p.min);
  return (value - p.min) / (p.max - p.min);
}

double from_unit(const CalibrationParameter& p, double u) {
  u = std::clamp(u, 0.0, 1.0);
  if (p.log_scale) return p.min * std::exp(u * std::log(p.max / p.min));
  return p.min + u * (p.max - p.min);
}

namespace {

// What NLopt's C callback needs: the loop's state and the first exception
// thrown by the evaluator (NLopt must not see it: it is kept, the optimiser
// is stopped, and it is thrown again once nlopt_optimize has returned).
struct LoopState {
  const std::vector<CalibrationParameter>* parameters = nullptr;
  const Evaluator* evaluate = nullptr;
  const std::vector<Evaluation>* recorded = nullptr;
  const EvaluationDone* on_done = nullptr;
  nlopt_opt opt = nullptr;
  OptimiserResult result;
  std::exception_ptr error;
  int budget = 0;
};

bool same_values(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (std::abs(a[k] - b[k]) > 1e-12 * std::max(std::abs(a[k]), std::abs(b[k]))) return false;
  return true;
}

double objective(unsigned n, const double* u, double* /*gradient: none*/, void* data) {
  auto& s = *static_cast<LoopState*>(data);
  try {
    const int index = static_cast<int>(s.result.history.size()) + 1;
    std::vector<double> values(n);
    for (unsigned k = 0; k < n; ++k) values[k] = from_unit((*s.parameters)[k], u[k]);
    Evaluation e;
    bool replayed = false;
    if (static_cast<std::size_t>(index) <= s.recorded->size()) {
      e = (*s.recorded)[static_cast<std::size_t>(index - 1)];
      if (!same_values(e.values, values)) {
        std::string asked, held;
        for (unsigned k = 0; k < n; ++k) {
          asked += fmt::format("{}{} = {:.10g}", k ? ", " : "", (*s.parameters)[k].key, values[k]);
          held += fmt::format("{}{:.10g}", k ? ", " : "",
                              k < e.values.size() ? e.values[k] : std::nan(""));
        }
        throw InputError(fmt::format("evaluation {} of the recorded history", index),
                         "(" + held + ")",
                         "the optimiser now asks for (" + asked +
                             "): the calibration or its inputs changed since the history was "
                             "written; resume only an unchanged calibration, or start a new "
                             "output folder");
      }
      replayed = true;
    } else {
      e = (*s.evaluate)(index, values);
    }
    e.index = index;
    e.values = values;
    s.result.history.push_back(e);
    if (*s.on_done) (*s.on_done)(s.result.history.back(), replayed);
    // NaN would derail the quadratic model: a failed comparison counts as very bad.
    return std::isfinite(e.misfit) ? e.misfit : std::numeric_limits<double>::max() / 4;
  } catch (...) {
    if (!s.error) s.error = std::current_exception();
    nlopt_force_stop(s.opt);
    return 0.0;
  }
}

// The index of the lowest misfit (the first of equals); history not empty.
std::size_t best_index(const std::vector<Evaluation>& history) {
  std::size_t best = 0;
  for (std::size_t k = 1; k < history.size(); ++k)
    if (history[k].misfit < history[best].misfit) best = k;
  return best;
}

struct OptDeleter {
  void operator()(nlopt_opt o) const { nlopt_destroy(o); }
};

} // namespace

OptimiserResult run_optimiser(const std::vector<CalibrationParameter>& parameters,
                              const OptimiserSettings& settings, const Evaluator& evaluate,
                              const std::vector<Evaluation>& recorded,
                              const EvaluationDone& on_done) {
  const unsigned n = static_cast<unsigned>(parameters.size());
  if (n == 0) throw std::logic_error("run_optimiser: no parameter to fit");
  if (settings.budget < 1) throw std::logic_error("run_optimiser: budget < 1");
  std::vector<double> lo(n, 0.0), hi(n, 1.0), u(n);
  for (unsigned k = 0; k < n; ++k)
    u[k] = std::clamp(to_unit(parameters[k], parameters[k].start), 0.0, 1.0);
  LoopState s;
  s.parameters = &parameters;
  s.evaluate = &evaluate;
  s.recorded = &recorded;
  s.on_done = &on_done;
  s.budget = settings.budget;
  // One BOBYQA run from u with what is left of the budget.
  auto optimise = [&]() {
    std::unique_ptr<std::remove_pointer_t<nlopt_opt>, OptDeleter> opt(
        nlopt_create(NLOPT_LN_BOBYQA, n));
    if (!opt) throw std::runtime_error("NLopt could not create its optimiser");
    std::vector<double> step(n, settings.initial_step);
    for (unsigned k = 0; k < n; ++k) {
      // BOBYQA moves a start that lies closer to a bound than its first step:
      // the step shrinks to 0.9 of that distance instead, down to 5 % of the
      // range (a start closer than that to a bound is moved inward by NLopt).
      const double room = std::min(u[k], 1.0 - u[k]);
      if (room > 0) step[k] = std::min(settings.initial_step, std::max(0.9 * room, 0.05));
    }
    s.opt = opt.get();
    nlopt_set_lower_bounds(opt.get(), lo.data());
    nlopt_set_upper_bounds(opt.get(), hi.data());
    nlopt_set_initial_step(opt.get(), step.data());
    nlopt_set_maxeval(opt.get(), settings.budget - static_cast<int>(s.result.history.size()));
    if (settings.tolerance > 0) nlopt_set_stopval(opt.get(), settings.tolerance);
    nlopt_set_xtol_abs1(opt.get(), settings.unit_step_tolerance);
    nlopt_set_min_objective(opt.get(), objective, &s);
    double best = 0;
    const nlopt_result rc = nlopt_optimize(opt.get(), u.data(), &best);
    s.opt = nullptr;
    if (s.error) std::rethrow_exception(s.error);
    return rc;
  };
  auto converged = [](nlopt_result rc) {
    return rc == NLOPT_XTOL_REACHED || rc == NLOPT_SUCCESS || rc == NLOPT_FTOL_REACHED ||
           rc == NLOPT_ROUNDOFF_LIMITED;
  };
  // Restarts (Cartis, Fiala, Marteau and Roberts 2019, "Improving the
  // flexibility and robustness of model-based derivative-free optimization
  // solvers", ACM TOMS 45(3), the noisy-objective restarts of Py-BOBYQA): a
  // noisy misfit can shrink the trust region around a point that is only
  // luckier than its neighbours; with budget left, BOBYQA starts again from
  // the best point so far with its first step. Deterministic, so a resumed
  // calibration asks for the same points.
  nlopt_result rc = optimise();
  int restarts = 0;
  while (converged(rc) && restarts < settings.restarts &&
         static_cast<int>(s.result.history.size()) < settings.budget) {
    const std::size_t best = best_index(s.result.history);
    for (unsigned k = 0; k < n; ++k)
      u[k] = std::clamp(to_unit(parameters[k], s.result.history[best].values[k]), 0.0, 1.0);
    ++restarts;
    rc = optimise();
  }
  OptimiserResult r = std::move(s.result);
  if (r.history.empty())
    throw std::runtime_error(
        fmt::format("NLopt stopped before evaluating anything (code {})", static_cast<int>(rc)));
  r.best = best_index(r.history);
  switch (rc) {
  case NLOPT_STOPVAL_REACHED:
    r.stop_reason = fmt::format("the misfit reached the tolerance ({:g})", settings.tolerance);
    break;
  case NLOPT_MAXEVAL_REACHED:
    r.stop_reason = fmt::format("the budget of {} evaluations was spent", settings.budget);
    break;
  case NLOPT_XTOL_REACHED:
    r.stop_reason = fmt::format("the steps shrank below {:g} of each range (converged)",
                                settings.unit_step_tolerance);
    break;
  case NLOPT_SUCCESS:
    r.stop_reason = "converged (the trust region shrank to its smallest step)";
    break;
  case NLOPT_FTOL_REACHED:
    r.stop_reason = "the misfit stopped improving (converged)";
    break;
  case NLOPT_ROUNDOFF_LIMITED:
    r.stop_reason = "limited by round-off (converged)";
    break;
  default:
    r.stop_reason = fmt::format("NLopt stopped (code {})", static_cast<int>(rc));
    break;
  }
  r.restarts = restarts;
  if (restarts > 0) r.stop_reason += fmt::format(", after {} restart(s)", restarts);
  return r;
}

} // namespace centridem
