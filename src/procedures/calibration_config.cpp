#include "procedures/calibration_config.hpp"

#include "base/errors.hpp"
#include "io/csv.hpp"
#include "io/toml_read.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <optional>

namespace centridem {

namespace fs = std::filesystem;
using tomlread::check_keys;
using tomlread::fail;
using tomlread::Keys;
using tomlread::missing;

namespace {

const Keys kCalibrateKeys = {"stage"};
const Keys kStageKeys = {"name",
                         "set",
                         "parameters",
                         "target",
                         "budget",
                         "restarts",
                         "replicates",
                         "tolerance",
                         "peak_weight",
                         "dilation_weight_kPa_per_mm",
                         "height_weight_kPa_per_um",
                         "modulus_weight_kPa_per_percent"};
const Keys kParameterKeys = {"key", "min", "max", "start", "scale"};
const Keys kTargetKeys = {"curves",
                          "friction_angle_deg",
                          "cohesion_kPa",
                          "peak_shear_stress_kPa",
                          "consolidated_height_mm",
                          "unloading_modulus_MPa",
                          "reloading_modulus_MPa",
                          "affine_modulus_MPa"};
const Keys kCurveFileKeys = {"file", "normal_stress_kPa"};

std::string kpa(double Pa) {
  return fmt::format("{:g}", Pa / 1e3);
}

bool same_pressure(double a, double b) {
  return std::abs(a - b) <= 1e-6 * std::max(a, b);
}

// One column of a measured-curve CSV: its role and the factor to SI.
struct Column {
  enum Role { strain, displacement, tau, sigma, dz, ignored } role;
  double to_si;
};
const std::map<std::string, Column, std::less<>> kColumns = {
    {"shear_strain", {Column::strain, 1.0}},
    {"shear_strain_percent", {Column::strain, 0.01}},
    {"shear_displacement_mm", {Column::displacement, 1e-3}},
    {"shear_displacement_m", {Column::displacement, 1.0}},
    {"shear_stress_kPa", {Column::tau, 1e3}},
    {"shear_stress_Pa", {Column::tau, 1.0}},
    {"normal_stress_kPa", {Column::sigma, 1e3}},
    {"normal_stress_Pa", {Column::sigma, 1.0}},
    {"vertical_displacement_mm", {Column::dz, 1e-3}},
    {"vertical_displacement_m", {Column::dz, 1.0}},
    // The other columns of a `centridem shear` curve (shear_<kPa>kPa.csv), so
    // that a simulated run can be given as "measured" as it is.
    {"step", {Column::ignored, 1.0}},
    {"time_s", {Column::ignored, 1.0}},
    {"porosity", {Column::ignored, 1.0}},
};
const char* kColumnList =
    "shear_strain | shear_strain_percent | shear_displacement_mm | shear_displacement_m, "
    "shear_stress_kPa | shear_stress_Pa, optionally normal_stress_kPa | normal_stress_Pa and "
    "vertical_displacement_mm | vertical_displacement_m (step, time_s and porosity, as in a "
    "centridem shear curve, are read and left out)";

} // namespace

std::vector<MeasuredCurve> read_measured_curves(const std::string& path, double strain_length_m,
                                                double normal_stress_Pa) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "(cannot be read)", "a CSV file of measured shear curves");
  std::string line;
  long n = 0;
  std::vector<std::optional<Column>> cols;
  int have[6] = {0, 0, 0, 0, 0, 0};
  while (std::getline(in, line)) {
    ++n;
    const std::string_view t = trim_blanks(line);
    if (t.empty() || t.front() == '#') continue;
    for (std::string_view f : split_commas(t)) {
      const auto it = kColumns.find(f);
      if (it == kColumns.end())
        throw InputError(fmt::format("{} line {} (header)", path, n), "\"" + std::string(f) + "\"",
                         std::string("a column name: ") + kColumnList);
      cols.push_back(it->second);
      ++have[it->second.role];
    }
    break;
  }
  const std::string header_where = fmt::format("{} line {} (header)", path, n);
  if (cols.empty())
    throw InputError(path, "(no header)", std::string("a header line: ") + kColumnList);
  if (have[Column::strain] > 1 || have[Column::displacement] > 1 ||
      have[Column::strain] + have[Column::displacement] == 0)
    throw InputError(header_where, "\"" + line + "\"",
                     "one of shear_strain, shear_strain_percent, shear_displacement_mm, "
                     "shear_displacement_m (a strain and a displacement: the strain is used)");
  const bool strain_given = have[Column::strain] == 1;
  // A normal stress given with the file names the test; a column beside it
  // (a servo's measured stress) is then left out.
  const bool sigma_from_column = have[Column::sigma] == 1 && !(normal_stress_Pa > 0);
  if (have[Column::tau] != 1)
    throw InputError(header_where, "\"" + line + "\"",
                     "exactly one of shear_stress_kPa, shear_stress_Pa");
  if (have[Column::sigma] > 1 || have[Column::dz] > 1)
    throw InputError(header_where, "\"" + line + "\"",
                     "at most one normal stress and one vertical displacement column");
  if (!have[Column::sigma] && !(normal_stress_Pa > 0))
    throw InputError(header_where, "\"" + line + "\"",
                     "a normal_stress_kPa column, or the file given as { file = ..., "
                     "normal_stress_kPa = ... } in the scenario");
  std::vector<MeasuredCurve> curves;
  while (std::getline(in, line)) {
    ++n;
    const std::string_view t = trim_blanks(line);
    if (t.empty() || t.front() == '#') continue;
    const std::vector<std::string_view> f = split_commas(t);
    const std::string where = fmt::format("{} line {}", path, n);
    if (f.size() != cols.size())
      throw InputError(where, "\"" + line + "\"",
                       fmt::format("{} comma-separated numbers as in the header, found {}",
                                   cols.size(), f.size()));
    double e = 0, tau = 0, sigma = normal_stress_Pa, dz = 0;
    for (std::size_t k = 0; k < f.size(); ++k) {
      const double v =
          parse_finite_number(f[k], fmt::format("{} column {}", where, k + 1)) * cols[k]->to_si;
      switch (cols[k]->role) {
      case Column::strain:
        e = v;
        break;
      case Column::displacement:
        if (!strain_given) e = v / strain_length_m;
        break;
      case Column::tau:
        tau = v;
        break;
      case Column::sigma:
        if (sigma_from_column) sigma = v;
        break;
      case Column::dz:
        dz = v;
        break;
      case Column::ignored:
        break;
      }
    }
    if (!(sigma > 0)) throw InputError(where, fmt::format("normal stress {:g} Pa", sigma), "> 0");
    if (e < 0) throw InputError(where, fmt::format("strain {:g}", e), ">= 0");
    auto it = std::find_if(curves.begin(), curves.end(), [&](const MeasuredCurve& c) {
      return same_pressure(c.normal_stress_Pa, sigma);
    });
    if (it == curves.end()) {
      MeasuredCurve c;
      c.normal_stress_Pa = sigma;
      c.source = path;
      curves.push_back(std::move(c));
      it = curves.end() - 1;
    }
    if (!it->strain.empty() && !(e > it->strain.back()))
      throw InputError(where, fmt::format("strain {:g} after {:g}", e, it->strain.back()),
                       fmt::format("strains rising within each normal stress ({} kPa here): "
                                   "sort the file by strain",
                                   kpa(sigma)));
    it->strain.push_back(e);
    it->shear_stress_Pa.push_back(tau);
    if (have[Column::dz]) it->vertical_displacement_m.push_back(dz);
  }
  if (curves.empty()) throw InputError(path, "(no data rows)", "at least one row of numbers");
  std::sort(curves.begin(), curves.end(), [](const MeasuredCurve& a, const MeasuredCurve& b) {
    return a.normal_stress_Pa < b.normal_stress_Pa;
  });
  return curves;
}

std::string CalibrationStage::misfit_unit() const {
  return kind == CalibrationTargetKind::mohr_coulomb ? "deg & kPa" : "kPa";
}

std::string parameter_override(const CalibrationParameter& p, double value) {
  return fmt::format("{} = {}", p.key, tomlread::num(value));
}

ShearScenario stage_scenario(const CalibrationScenario& c, const CalibrationStage& stage,
                             const std::vector<std::string>& earlier,
                             const std::vector<double>& values,
                             const std::vector<std::string>& replicate) {
  std::vector<std::string> o = earlier;
  o.insert(o.end(), stage.set.begin(), stage.set.end());
  for (std::size_t k = 0; k < stage.parameters.size() && k < values.size(); ++k)
    o.push_back(parameter_override(stage.parameters[k], values[k]));
  o.insert(o.end(), replicate.begin(), replicate.end());
  const std::string text = tomlread::apply_overrides(c.text, c.source, o);
  return parse_shear_scenario(text, c.source + " (stage " + stage.name + ")", c.base_dir);
}

namespace {

CalibrationParameter read_parameter(const toml::node& node, const std::string& P) {
  const toml::table& t =
      tomlread::as_table(node, P, "{ key = ..., min = ..., max = ..., start = ... }");
  check_keys(t, P, kParameterKeys);
  CalibrationParameter p;
  const toml::node* k = t.get("key");
  if (!k)
    missing(P + ".key", "the dotted scenario key to fit, e.g. \"contact.ball_ball.friction\"", t);
  p.key = tomlread::as_string(*k, P + ".key", "a dotted scenario key");
  auto number = [&](std::string_view name) {
    const toml::node* v = t.get(name);
    if (!v)
      missing(P + "." + std::string(name),
              "bounds and a start for " + p.key + ": min < start < max (a number)", t);
    return tomlread::as_number(*v, P + "." + std::string(name), "a number");
  };
  p.min = number("min");
  p.max = number("max");
  p.start = number("start");
  if (!(p.max > p.min)) fail(P + ".max", *t.get("max"), fmt::format("> min = {:g}", p.min));
  if (!(p.start >= p.min && p.start <= p.max))
    fail(P + ".start", *t.get("start"),
         fmt::format("inside the bounds [{:g}, {:g}]", p.min, p.max));
  if (const toml::node* s = t.get("scale")) {
    const std::string v = tomlread::as_string(*s, P + ".scale", "\"linear\" or \"log\"");
    if (v == "log")
      p.log_scale = true;
    else if (v != "linear")
      fail(P + ".scale", *s, "\"linear\" or \"log\"");
    if (p.log_scale && !(p.min > 0))
      fail(P + ".scale", *s, "\"linear\": a log scale needs min > 0");
  }
  return p;
}

void read_target(const toml::node& node, const std::string& P, CalibrationStage& st,
                 const ShearScenario& sc, const std::string& base_dir) {
  const toml::table& t =
      tomlread::as_table(node, P,
                         "{ curves = [...] }, { friction_angle_deg = ..., cohesion_kPa = ... } or "
                         "{ peak_shear_stress_kPa = [...] }");
  check_keys(t, P, kTargetKeys);
  const bool curves = t.contains("curves");
  const bool mc = t.contains("friction_angle_deg") || t.contains("cohesion_kPa");
  const bool peaks = t.contains("peak_shear_stress_kPa");
  if (int(curves) + int(mc) + int(peaks) != 1)
    fail(P, node,
         "one kind of target: curves = [FILE, ...], or friction_angle_deg and cohesion_kPa, "
         "or peak_shear_stress_kPa = [...]");
  const std::vector<double>& sigmas = st.normal_stresses_Pa;
  std::string pressures;
  for (double s : sigmas) pressures += (pressures.empty() ? "" : ", ") + kpa(s);
  const toml::node* heights = t.get("consolidated_height_mm");
  if (heights && !curves)
    fail(P + ".consolidated_height_mm", *heights, "only beside measured curves (target.curves)");
  for (const char* k : {"unloading_modulus_MPa", "reloading_modulus_MPa", "affine_modulus_MPa"})
    if (const toml::node* n = t.get(k); n && !curves)
      fail(P + "." + k, *n, "only beside measured curves (target.curves)");
  if (mc) {
    st.kind = CalibrationTargetKind::mohr_coulomb;
    const toml::node* f = t.get("friction_angle_deg");
    const toml::node* c = t.get("cohesion_kPa");
    if (!f)
      missing(P + ".friction_angle_deg", "the target peak friction angle in (0, 90) [deg]", t);
    if (!c) missing(P + ".cohesion_kPa", "the target peak cohesion >= 0 [kPa]", t);
    st.mohr_coulomb.friction_angle_deg =
        tomlread::as_number(*f, P + ".friction_angle_deg", "(0, 90) [deg]");
    if (!(st.mohr_coulomb.friction_angle_deg > 0 && st.mohr_coulomb.friction_angle_deg < 90))
      fail(P + ".friction_angle_deg", *f, "(0, 90) [deg]");
    const double ck = tomlread::as_number(*c, P + ".cohesion_kPa", ">= 0 [kPa]");
    if (!(ck >= 0)) fail(P + ".cohesion_kPa", *c, ">= 0 [kPa]");
    st.mohr_coulomb.cohesion_Pa = ck * 1e3;
    if (sigmas.size() < 2)
      fail(P, node,
           "an envelope needs at least two normal stresses in shear.normal_stresses_Pa (found " +
               pressures + " kPa)");
    return;
  }
  if (peaks) {
    st.kind = CalibrationTargetKind::peak_stresses;
    const toml::node* n = t.get("peak_shear_stress_kPa");
    const toml::array* a = n->as_array();
    const std::string key = P + ".peak_shear_stress_kPa";
    if (!a || a->size() != sigmas.size())
      fail(key, *n,
           fmt::format("a list of {} peak shear stresses [kPa], one per normal stress of the "
                       "stage ({} kPa)",
                       sigmas.size(), pressures));
    for (const toml::node& v : *a) {
      const double x = tomlread::as_number(v, key, "> 0 [kPa]");
      if (!(x > 0)) fail(key, v, "> 0 [kPa]");
      st.peak_shear_stress_Pa.push_back(x * 1e3);
    }
    return;
  }
  st.kind = CalibrationTargetKind::curves;
  const std::string key = P + ".curves";
  const toml::node* n = t.get("curves");
  const toml::array* a = n->as_array();
  if (!a || a->empty())
    fail(key, *n, "a list of CSV files, or of { file = ..., normal_stress_kPa = ... }");
  const double strain_length =
      sc.test.strain == StrainDefinition::height ? sc.test.box.height_m : sc.test.box.length_m;
  for (const toml::node& e : *a) {
    std::string file;
    double sigma = 0;
    if (e.is_string()) {
      file = tomlread::as_string(e, key, "a CSV file");
    } else if (const toml::table* ft = e.as_table()) {
      check_keys(*ft, key, kCurveFileKeys);
      const toml::node* fn = ft->get("file");
      if (!fn) missing(key + ".file", "the CSV file", *ft);
      file = tomlread::as_string(*fn, key + ".file", "a CSV file");
      if (const toml::node* s = ft->get("normal_stress_kPa")) {
        sigma = tomlread::as_number(*s, key + ".normal_stress_kPa", "> 0 [kPa]") * 1e3;
        if (!(sigma > 0)) fail(key + ".normal_stress_kPa", *s, "> 0 [kPa]");
      }
    } else {
      fail(key, e, "a CSV file, or { file = ..., normal_stress_kPa = ... }");
    }
    fs::path path(file);
    if (path.is_relative() && !base_dir.empty()) path = fs::path(base_dir) / path;
    for (MeasuredCurve& c : read_measured_curves(path.string(), strain_length, sigma)) {
      for (const MeasuredCurve& d : st.curves)
        if (same_pressure(d.normal_stress_Pa, c.normal_stress_Pa))
          throw InputError(key, c.source,
                           fmt::format("one measured curve per normal stress: {} kPa is also in {}",
                                       kpa(c.normal_stress_Pa), d.source));
      st.curves.push_back(std::move(c));
    }
  }
  std::sort(st.curves.begin(), st.curves.end(), [](const MeasuredCurve& x, const MeasuredCurve& y) {
    return x.normal_stress_Pa < y.normal_stress_Pa;
  });
  const double max_strain = sc.test.max_shear_displacement_m / strain_length;
  for (const MeasuredCurve& c : st.curves) {
    if (std::none_of(sigmas.begin(), sigmas.end(),
                     [&](double s) { return same_pressure(s, c.normal_stress_Pa); }))
      throw InputError(c.source, fmt::format("a curve at {} kPa", kpa(c.normal_stress_Pa)),
                       "a normal stress the stage runs (shear.normal_stresses_Pa: " + pressures +
                           " kPa): add it there, or leave the curve out");
    if (c.strain.front() > max_strain * (1 + 1e-9))
      throw InputError(c.source, fmt::format("strains from {:g}", c.strain.front()),
                       fmt::format("strains the simulation reaches (up to {:g}: raise "
                                   "shear.max_shear_displacement_m)",
                                   max_strain));
  }
  for (double s : sigmas)
    if (std::none_of(st.curves.begin(), st.curves.end(),
                     [&](const MeasuredCurve& c) { return same_pressure(s, c.normal_stress_Pa); }))
      fail(key, node,
           fmt::format("a measured curve at every normal stress of the stage: none at {} kPa "
                       "(shear.normal_stresses_Pa: {} kPa; a stage's set can change them)",
                       kpa(s), pressures));
  if (heights) {
    const std::string hk = P + ".consolidated_height_mm";
    const toml::array* h = heights->as_array();
    const std::string allowed =
        fmt::format("a list of {} specimen heights after consolidation [mm], one per normal "
                    "stress of the stage, rising ({} kPa), each in (0, {:g}] (twice the box "
                    "height)",
                    st.curves.size(), pressures, 2e3 * sc.test.box.height_m);
    if (!h || h->size() != st.curves.size()) fail(hk, *heights, allowed);
    for (std::size_t k = 0; k < h->size(); ++k) {
      const double mm = tomlread::as_number((*h)[k], fmt::format("{}[{}]", hk, k), allowed);
      if (!(mm > 0 && mm <= 2e3 * sc.test.box.height_m))
        fail(fmt::format("{}[{}]", hk, k), (*h)[k], allowed);
      st.curves[k].consolidated_height_m = mm * 1e-3;
    }
  }
  // The moduli: one per pressure, each > 0 [MPa], into the curve's field `into`.
  auto read_moduli = [&](const char* name, const std::string& what, bool needs_loop,
                         double MeasuredCurve::*into) {
    const toml::node* mn = t.get(name);
    if (!mn) return;
    const std::string mk = P + "." + name;
    if (needs_loop && !(sc.test.unload_reload_fraction > 0))
      fail(mk, *mn,
           "a modulus target only with an unload-reload loop in the scenario: "
           "shear.unload_reload_fraction in (0, 1), e.g. 0.9 (docs/shear.md)");
    const toml::array* ma = mn->as_array();
    const std::string allowed = fmt::format(
        "a list of {} {}, one per normal stress of the stage, rising ({} kPa), each > 0",
        st.curves.size(), what, pressures);
    if (!ma || ma->size() != st.curves.size()) fail(mk, *mn, allowed);
    for (std::size_t k = 0; k < ma->size(); ++k) {
      const double MPa = tomlread::as_number((*ma)[k], fmt::format("{}[{}]", mk, k), allowed);
      if (!(MPa > 0)) fail(fmt::format("{}[{}]", mk, k), (*ma)[k], allowed);
      st.curves[k].*into = MPa * 1e6;
    }
  };
  // The unload-reload loop's (the scenario must run it), and the affine moduli (every shear run
  // measures them).
  const std::string loop = "constrained moduli [MPa] of the unload-reload loop";
  read_moduli("unloading_modulus_MPa", loop, true, &MeasuredCurve::unloading_modulus_Pa);
  read_moduli("reloading_modulus_MPa", loop, true, &MeasuredCurve::reloading_modulus_Pa);
  read_moduli("affine_modulus_MPa",
              "affine moduli [MPa] after consolidation (the shear runs' "
              "consolidated_affine_modulus_Pa / 1e6)",
              false, &MeasuredCurve::affine_modulus_Pa);
}

} // namespace

CalibrationScenario parse_calibration(std::string_view text, const std::string& source,
                                      const std::string& base_dir) {
  CalibrationScenario c;
  c.source = source;
  c.base_dir = base_dir;
  c.text = std::string(text);
  const toml::table root = tomlread::parse_document(text, source);
  const toml::node* cal = root.get("calibrate");
  if (!cal)
    missing("calibrate",
            "a [calibrate] table with one [[calibrate.stage]] per stage "
            "(docs/calibrate.md)",
            root);
  const toml::table& ct = tomlread::as_table(*cal, "calibrate", "a table");
  check_keys(ct, "calibrate", kCalibrateKeys);
  const toml::node* sn = ct.get("stage");
  const toml::array* stages = sn ? sn->as_array() : nullptr;
  if (!stages || stages->empty())
    missing("calibrate.stage",
            "one [[calibrate.stage]] per stage, each with name, target and "
            "parameters (docs/calibrate.md)",
            ct);
  std::vector<std::string> earlier; // the earlier stages' parameters at their starts
  for (std::size_t i = 0; i < stages->size(); ++i) {
    const std::string P = fmt::format("calibrate.stage[{}]", i + 1);
    const toml::table& t = tomlread::as_table((*stages)[i], P, "a table");
    check_keys(t, P, kStageKeys);
    CalibrationStage st;
    const toml::node* nm = t.get("name");
    if (!nm)
      missing(P + ".name", "a name of letters, digits, - or _ (the stage's output folder)", t);
    st.name = tomlread::as_string(*nm, P + ".name", "letters, digits, - or _");
    if (st.name.empty() || !std::all_of(st.name.begin(), st.name.end(), [](char ch) {
          return std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_';
        }))
      fail(P + ".name", *nm, "letters, digits, - or _ (it names the stage's output folder)");
    for (const CalibrationStage& o : c.stages)
      if (o.name == st.name) fail(P + ".name", *nm, "a name no other stage has");
    if (const toml::node* s = t.get("set")) {
      const toml::array* a = s->as_array();
      if (!a) fail(P + ".set", *s, "a list of \"KEY = VALUE\" strings");
      for (const toml::node& v : *a)
        st.set.push_back(tomlread::as_string(v, P + ".set", "\"KEY = VALUE\" (TOML syntax)"));
    }
    const toml::node* pn = t.get("parameters");
    const toml::array* pa = pn ? pn->as_array() : nullptr;
    if (!pa || pa->empty())
      missing(P + ".parameters",
              "a list of { key = ..., min = ..., max = ..., start = ... } (at least one)", t);
    for (std::size_t j = 0; j < pa->size(); ++j) {
      st.parameters.push_back(read_parameter((*pa)[j], fmt::format("{}.parameters[{}]", P, j + 1)));
      for (std::size_t q = 0; q + 1 < st.parameters.size(); ++q)
        if (st.parameters[q].key == st.parameters.back().key)
          fail(fmt::format("{}.parameters[{}].key", P, j + 1), *(*pa)[j].as_table()->get("key"),
               "a key not fitted twice in one stage");
    }
    if (auto b = tomlread::opt_integer(
            t, P, "budget", [](long v) { return v >= 1 && v <= 10000; },
            "a whole number of evaluations in [1, 10000]"))
      st.optimiser.budget = static_cast<int>(*b);
    if (auto v = tomlread::opt_integer(
            t, P, "restarts", [](long x) { return x >= 0 && x <= 100; },
            "a whole number in [0, 100]: how often BOBYQA may start again from the best point "
            "when it converges with budget left (noisy misfits)"))
      st.optimiser.restarts = static_cast<int>(*v);
    if (const toml::node* rn = t.get("replicates")) {
      const std::string allowed =
          "a list of 1 to 64 replicate specimens, each a \"KEY = VALUE\" override or a list of "
          "them, e.g. [\"specimen.seed = 11\", \"specimen.seed = 12\"] (docs/calibrate.md "
          "\"Replicates\")";
      const toml::array* a = rn->as_array();
      if (!a || a->empty() || a->size() > 64) fail(P + ".replicates", *rn, allowed);
      for (std::size_t k = 0; k < a->size(); ++k) {
        const std::string key = fmt::format("{}.replicates[{}]", P, k + 1);
        std::vector<std::string> o;
        if (const toml::array* list = (*a)[k].as_array()) {
          for (const toml::node& v : *list) o.push_back(tomlread::as_string(v, key, allowed));
        } else {
          o.push_back(tomlread::as_string((*a)[k], key, allowed));
        }
        if (o.empty()) fail(key, (*a)[k], allowed);
        if (std::find(st.replicates.begin(), st.replicates.end(), o) != st.replicates.end())
          fail(key, (*a)[k], "a replicate unlike the others (" + allowed + ")");
        st.replicates.push_back(std::move(o));
      }
    }
    if (auto v = tomlread::opt_number(
            t, P, "tolerance", [](double x) { return x >= 0; },
            ">= 0, in the misfit's unit (kPa; degrees and kPa for a "
            "Mohr-Coulomb target)"))
      st.optimiser.tolerance = *v;
    if (auto v = tomlread::opt_number(
            t, P, "peak_weight", [](double x) { return x >= 0; }, ">= 0"))
      st.weights.peak = *v;
    if (auto v = tomlread::opt_number(
            t, P, "dilation_weight_kPa_per_mm", [](double x) { return x >= 0; }, ">= 0 [kPa/mm]"))
      st.weights.dilation_kPa_per_mm = *v;
    if (auto v = tomlread::opt_number(
            t, P, "height_weight_kPa_per_um", [](double x) { return x >= 0; }, ">= 0 [kPa/um]"))
      st.weights.height_kPa_per_um = *v;
    if (auto v = tomlread::opt_number(
            t, P, "modulus_weight_kPa_per_percent", [](double x) { return x >= 0; },
            ">= 0 [kPa/%]"))
      st.weights.modulus_kPa_per_percent = *v;
    // The stage's scenario at the starts: checks `set` and every parameter key.
    ShearScenario sc;
    try {
      sc = stage_scenario(c, st, earlier, {});
    } catch (const InputError& e) {
      throw InputError(P + ".set", "[...]",
                       std::string("overrides that give a valid shear scenario: ") + e.what());
    }
    for (std::size_t k = 0; k < st.replicates.size(); ++k) {
      try {
        stage_scenario(c, st, earlier, {}, st.replicates[k]);
      } catch (const InputError& e) {
        throw InputError(fmt::format("{}.replicates[{}]", P, k + 1),
                         "\"" + st.replicates[k].front() + "\"",
                         std::string("overrides that give a valid shear scenario: ") + e.what());
      }
    }
    for (std::size_t j = 0; j < st.parameters.size(); ++j) {
      std::vector<double> starts;
      for (std::size_t q = 0; q <= j; ++q) starts.push_back(st.parameters[q].start);
      try {
        stage_scenario(c, st, earlier, starts);
      } catch (const InputError& e) {
        throw InputError(
            fmt::format("{}.parameters[{}].key", P, j + 1), "\"" + st.parameters[j].key + "\"",
            std::string("a number key of the shear scenario, valid at its start: ") + e.what());
      }
    }
    st.normal_stresses_Pa = sc.normal_stresses_Pa;
    std::sort(st.normal_stresses_Pa.begin(), st.normal_stresses_Pa.end());
    const toml::node* tn = t.get("target");
    if (!tn)
      missing(P + ".target",
              "{ curves = [FILE, ...] }, { friction_angle_deg = ..., cohesion_kPa = ... } or "
              "{ peak_shear_stress_kPa = [...] }",
              t);
    read_target(*tn, P + ".target", st, sc, base_dir);
    const bool heights =
        st.kind == CalibrationTargetKind::curves && st.curves.front().consolidated_height_m > 0;
    if (heights != (st.weights.height_kPa_per_um > 0))
      throw InputError(heights ? P + ".height_weight_kPa_per_um" : P + ".target",
                       heights ? "(not given)" : "(no consolidated_height_mm)",
                       "measured consolidated heights and a weight > 0 for them go together: "
                       "target.consolidated_height_mm = [...] with height_weight_kPa_per_um "
                       "(e.g. 1: a micrometre counts as a kPa)");
    const bool moduli =
        st.kind == CalibrationTargetKind::curves &&
        (st.curves.front().unloading_modulus_Pa > 0 || st.curves.front().reloading_modulus_Pa > 0 ||
         st.curves.front().affine_modulus_Pa > 0);
    if (moduli != (st.weights.modulus_kPa_per_percent > 0))
      throw InputError(
          moduli ? P + ".modulus_weight_kPa_per_percent" : P + ".target",
          moduli ? "(not given)"
                 : "(no unloading_modulus_MPa or reloading_modulus_MPa, no affine_modulus_MPa)",
          "measured moduli and a weight > 0 for them go together: "
          "target.affine_modulus_MPa = [...] (or the loop's reloading_modulus_MPa) with "
          "modulus_weight_kPa_per_percent (e.g. 0.5: a per cent counts as half a kPa)");
    for (const CalibrationParameter& p : st.parameters)
      earlier.push_back(parameter_override(p, p.start));
    c.stages.push_back(std::move(st));
  }
  return c;
}

CalibrationScenario load_calibration(const std::string& path,
                                     const std::vector<std::string>& overrides) {
  const tomlread::ScenarioText t = tomlread::read_scenario_text(path, overrides);
  return parse_calibration(t.text, t.source, t.base_dir);
}

} // namespace centridem
