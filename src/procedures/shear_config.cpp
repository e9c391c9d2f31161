#include "procedures/shear_config.hpp"
#include "io/toml_read.hpp"

#include "base/errors.hpp"
#include "procedures/paper_material.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sstream>
#include <toml++/toml.h>

namespace centridem {

namespace {

using Keys = tomlread::Keys;
using tomlread::as_number;
using tomlread::as_table;
using tomlread::check_keys;
using tomlread::contact_inline;
using tomlread::fail;
using tomlread::join;
using tomlread::missing;
using tomlread::num;
using tomlread::opt_integer;
using tomlread::opt_number;
using tomlread::path_of;
using tomlread::show;
using tomlread::where;

// [calibrate] belongs to `centridem calibrate` (docs/calibrate.md): a calibration scenario is a
// shear scenario with that table, and `shear` runs it at its current values, ignoring the table.
const Keys kTopKeys = {"description", "specimen", "contact", "preparation", "shear", "calibrate"};
const Keys kContactSectionKeys = {"ball_ball"};
const Keys kModelNames = {"linear", "rrlinear", "arrlinear"};
const Keys kShearKeys = {"box",
                         "normal_stresses_Pa",
                         "shear_rate_m_per_s",
                         "max_shear_displacement_m",
                         "strain",
                         "ball_wall",
                         "during_shear",
                         "servo_gain_factor",
                         "servo_max_speed_m_per_s",
                         "servo_integral_time_s",
                         "consolidation_ratio",
                         "consolidation_stress_tolerance",
                         "consolidation_max_steps",
                         "unload_reload_fraction",
                         "record_interval_steps",
                         "local_damping",
                         "g_level",
                         "threads",
                         "checkpoint_interval_min"};
const Keys kBoxKeys = {"length_m", "width_m", "height_m", "plate_length_m"};
const Keys kStrainNames = {"height", "length"};

auto positive = [](double v) { return v > 0; };
auto non_negative = [](double v) { return v >= 0; };
auto unit_open = [](double v) { return v >= 0 && v < 1; };

// A contact table as a patch (only the named keys); the same keys and ranges
// as the scenario parser's [contact.ball_ball] (docs/scenario.md).
ContactPatch read_patch(const toml::node& node, const std::string& path) {
  return read_contact_patch(node, path);
}

// `patch` over `base`, validated.
ContactProperties resolve(const ContactPatch& p, const ContactProperties& base,
                          const std::string& path) {
  ContactProperties c = apply(p, base);
  validate(c, path);
  return c;
}

} // namespace

DirectShearSpec ShearScenario::run_spec(double normal_stress_Pa) const {
  DirectShearSpec s = test;
  s.normal_stress_Pa = normal_stress_Pa;
  if (!during_shear.empty())
    s.ball_ball_during_shear = apply(during_shear, ball_ball);
  else
    s.ball_ball_during_shear.reset();
  s.ball_ball = ball_ball;
  if (preparation.enabled)
    s.ball_ball_during_consolidation = apply(preparation.during_compaction, ball_ball);
  else
    s.ball_ball_during_consolidation.reset();
  return s;
}

ShearScenario parse_shear_scenario(std::string_view text, const std::string& source_name,
                                   const std::string& base_dir) {
  const toml::table root = tomlread::parse_document(text, source_name);
  check_keys(root, "", kTopKeys);
  ShearScenario sc;
  sc.source_path = source_name;
  sc.base_dir = base_dir;
  if (const toml::node* d = root.get("description")) {
    const auto* s = d->as_string();
    if (!s) fail("description", *d, "expected a string");
    sc.description = s->get();
  }

  // [contact.ball_ball]: complete (model and a stiffness required).
  const toml::node* contact = root.get("contact");
  if (!contact)
    missing("contact.ball_ball", "a [contact.ball_ball] table with at least model and "
                                 "effective_modulus_Pa (docs/scenario.md)");
  const toml::table& ct = as_table(*contact, "contact", "[contact.ball_ball]");
  check_keys(ct, "contact", kContactSectionKeys);
  const toml::node* bb = ct.get("ball_ball");
  if (!bb)
    missing("contact.ball_ball", "a [contact.ball_ball] table with at least model and "
                                 "effective_modulus_Pa (docs/scenario.md)");
  {
    const ContactPatch p = read_patch(*bb, "contact.ball_ball");
    if (!p.model)
      missing("contact.ball_ball.model", "the contact model: one of " + join(kModelNames));
    if (!p.effective_modulus_Pa && !p.normal_stiffness_N_per_m)
      missing("contact.ball_ball.effective_modulus_Pa",
              "the effective modulus E* > 0 [Pa], or normal_stiffness_N_per_m + "
              "shear_stiffness_N_per_m");
    sc.ball_ball = resolve(p, ContactProperties{}, "contact.ball_ball");
  }

  // [specimen] (its own parser; it ignores the other tables).
  sc.specimen = parse_specimen(text, source_name, base_dir);

  // [shear]
  const std::string P = "shear";
  const toml::node* sn = root.get(P);
  if (!sn) missing(P, "a [shear] table with at least normal_stresses_Pa (docs/shear.md)");
  const toml::table& t = as_table(*sn, P, "the direct shear test (docs/shear.md)");
  check_keys(t, P, kShearKeys, [](std::string_view k) -> std::string {
    if (k == "during_consolidation")
      return " (the preparation is shared with the slope now: give it as "
             "[preparation] during_compaction = {...}, docs/specimens.md \"Preparation\")";
    return {};
  });
  DirectShearSpec& s = sc.test;

  // The box: by default the specimen's region, which must start at the origin.
  const std::optional<Box> region = sc.specimen.region;
  if (region) {
    s.box.length_m = region->hi.x - region->lo.x;
    s.box.width_m = region->hi.y - region->lo.y;
    s.box.height_m = region->hi.z - region->lo.z;
  }
  if (const toml::node* bn = t.get("box")) {
    const std::string bp = P + ".box";
    const toml::table& b = as_table(*bn, bp, "{ length_m, width_m, height_m }");
    check_keys(b, bp, kBoxKeys);
    const std::string dims = "> 0 [m]";
    auto dim = [&](std::string_view k, double& out) {
      if (auto v = opt_number(b, bp, k, positive, dims))
        out = *v;
      else if (!region)
        missing(path_of(bp, k), "the box dimension " + dims);
    };
    dim("length_m", s.box.length_m);
    dim("width_m", s.box.width_m);
    dim("height_m", s.box.height_m);
    if (auto v = opt_number(b, bp, "plate_length_m", non_negative,
                            "length of the shear-plane plates: >= 0 [m] (0 = automatic)"))
      s.box.plate_length_m = *v;
  } else if (!region) {
    missing(P + ".box", "{ length_m, width_m, height_m } (or a specimen.region)");
  }
  if (region) {
    const double tol = 1e-9;
    const Vec3 lo = region->lo, hi = region->hi;
    const bool ok = std::abs(lo.x) < tol && std::abs(lo.y) < tol && std::abs(lo.z) < tol &&
                    std::abs(hi.x - s.box.length_m) < tol && std::abs(hi.y - s.box.width_m) < tol &&
                    std::abs(hi.z - s.box.height_m) < tol;
    if (!ok)
      throw InputError("specimen.region",
                       fmt::format("{{ lo_m = [{}, {}, {}], hi_m = [{}, {}, {}] }}", lo.x, lo.y,
                                   lo.z, hi.x, hi.y, hi.z),
                       fmt::format("must be the shear box: lo_m = [0, 0, 0], hi_m = [{}, {}, {}] "
                                   "(shear.box length_m, width_m, height_m)",
                                   s.box.length_m, s.box.width_m, s.box.height_m));
  }

  const toml::node* ns = t.get("normal_stresses_Pa");
  if (!ns)
    missing(P + ".normal_stresses_Pa", "a list of normal stresses > 0 [Pa], e.g. [40e3, 60e3]");
  {
    const std::string key = P + ".normal_stresses_Pa";
    const toml::array* a = ns->as_array();
    if (!a || a->empty()) fail(key, *ns, "expected a non-empty list of normal stresses > 0 [Pa]");
    for (std::size_t i = 0; i < a->size(); ++i) {
      const std::string ki = fmt::format("{}[{}]", key, i);
      const double v = as_number((*a)[i], ki, "a normal stress > 0 [Pa]");
      if (!(v > 0)) fail(ki, (*a)[i], "a normal stress > 0 [Pa]");
      for (double prev : sc.normal_stresses_Pa)
        if (std::abs(prev - v) <= 1e-9 * v) fail(ki, (*a)[i], "each normal stress once");
      sc.normal_stresses_Pa.push_back(v);
    }
  }
  if (auto v = opt_number(t, P, "shear_rate_m_per_s", positive, "the upper box speed: > 0 [m/s]"))
    s.shear_rate_m_per_s = *v;
  s.max_shear_displacement_m = 0.2 * s.box.height_m; // default: 20 % strain on the height
  if (auto v = opt_number(
          t, P, "max_shear_displacement_m", [&](double x) { return x > 0 && x < s.box.length_m; },
          "the upper box travel: > 0 and below the box length [m]"))
    s.max_shear_displacement_m = *v;
  if (const toml::node* n = t.get("strain")) {
    const auto* str = n->as_string();
    if (!str ||
        std::find(kStrainNames.begin(), kStrainNames.end(), str->get()) == kStrainNames.end())
      fail(P + ".strain", *n,
           "\"height\" (shear displacement / box height) or \"length\" (/ box length)");
    s.strain = str->get() == "height" ? StrainDefinition::height : StrainDefinition::length;
  }
  s.ball_wall = paper::ball_wall(0.0);
  if (const toml::node* n = t.get("ball_wall"))
    s.ball_wall = resolve(read_patch(*n, P + ".ball_wall"), s.ball_wall, P + ".ball_wall");
  if (const toml::node* n = t.get("during_shear")) {
    sc.during_shear = read_patch(*n, P + ".during_shear");
    validate(apply(sc.during_shear, sc.ball_ball), P + ".during_shear");
  }
  // [preparation]: the compaction properties, and its ratio and step limit
  // end the consolidation (which is then the preparation's compaction and
  // settling); without it the [shear] keys below do.
  sc.preparation = read_preparation(root, sc.ball_ball);
  if (sc.preparation.enabled) {
    for (std::string_view k : {"consolidation_ratio", "consolidation_max_steps"})
      if (const toml::node* n = t.get(k))
        fail(path_of(P, k), *n,
             "no value here when the scenario has a [preparation] table: its ratio and "
             "max_steps end the consolidation (docs/specimens.md \"Preparation\")");
    s.consolidation_ratio = sc.preparation.ratio;
    s.consolidation_max_steps = sc.preparation.max_steps;
  }
  if (auto v = opt_number(
          t, P, "servo_gain_factor", [](double x) { return x > 0 && x <= 1; },
          "the servo's alpha: in (0, 1] [-]"))
    s.servo_gain_factor = *v;
  if (auto v = opt_number(t, P, "servo_max_speed_m_per_s", positive,
                          "the servo's speed limit: > 0 [m/s]"))
    s.servo_max_speed_m_per_s = *v;
  if (auto v = opt_number(
          t, P, "servo_integral_time_s", [](double x) { return x >= 0; },
          "the servo's integral time: >= 0 [s] (0: proportional only, PFC's form)"))
    s.servo_integral_time_s = *v;
  if (auto v = opt_number(t, P, "consolidation_ratio", positive,
                          "mean unbalanced-force ratio that ends consolidation: > 0 [-]"))
    s.consolidation_ratio = *v;
  if (auto v = opt_number(t, P, "consolidation_stress_tolerance", positive,
                          "|sigma - target| / target that ends consolidation: > 0 [-]"))
    s.consolidation_stress_tolerance = *v;
  if (auto v = opt_number(
          t, P, "unload_reload_fraction", [](double x) { return x >= 0 && x < 1; },
          "in [0, 1): 0 for no unload-reload loop after consolidation, else the fraction of the "
          "normal stress it unloads to [-]"))
    s.unload_reload_fraction = *v;
  auto pos_int = [](long v) { return v > 0; };
  if (auto v = opt_integer(t, P, "consolidation_max_steps", pos_int, "a step limit > 0"))
    s.consolidation_max_steps = *v;
  if (auto v =
          opt_integer(t, P, "record_interval_steps", pos_int, "steps between curve points: > 0"))
    s.record_interval_steps = *v;
  if (auto v = opt_number(t, P, "local_damping", unit_open, "Cundall local damping in [0, 1) [-]"))
    sc.local_damping = *v;
  if (auto v = opt_number(t, P, "g_level", non_negative,
                          "gravity along -z in multiples of 9.81 m/s^2: >= 0 [-]"))
    sc.g_level = *v;
  if (auto v = opt_integer(
          t, P, "threads", [](long x) { return x >= 0 && x <= 1024; },
          "OpenMP threads per run: 0 (the OpenMP default) to 1024"))
    sc.threads = static_cast<int>(*v);
  if (auto v = opt_number(t, P, "checkpoint_interval_min", non_negative,
                          "wall-clock minutes between checkpoints: >= 0 (0 = only on "
                          "SIGINT/SIGTERM and at the start of shearing)"))
    sc.checkpoint_interval_min = *v;
  validate(sc.run_spec(sc.normal_stresses_Pa.front())); // cross-key checks, dotted keys
  return sc;
}

ShearScenario load_shear_scenario(const std::string& path,
                                  const std::vector<std::string>& overrides) {
  const tomlread::ScenarioText t = tomlread::read_scenario_text(path, overrides);
  return parse_shear_scenario(t.text, t.source, t.base_dir);
}

std::string resolved_shear_toml(const ShearScenario& sc) {
  std::string o;
  if (!sc.description.empty()) {
    std::string d;
    for (char c : sc.description) {
      if (c == '"' || c == '\\') d += '\\';
      d += c;
    }
    o += fmt::format("description = \"{}\"\n\n", d);
  }
  o += resolved_specimen_toml(sc.specimen);
  o += "\n[contact]\nball_ball = " + contact_inline(sc.ball_ball) + "\n";
  o += resolved_preparation_toml(sc.preparation);
  const DirectShearSpec& s = sc.test;
  o += "\n[shear]\n";
  o += fmt::format("box = {{ length_m = {}, width_m = {}, height_m = {}, plate_length_m = {} }}\n",
                   num(s.box.length_m), num(s.box.width_m), num(s.box.height_m),
                   num(s.box.plate_length_m));
  std::string list;
  for (double v : sc.normal_stresses_Pa) list += (list.empty() ? "" : ", ") + num(v);
  o += "normal_stresses_Pa = [" + list + "]\n";
  o += fmt::format("shear_rate_m_per_s = {}\n", num(s.shear_rate_m_per_s));
  o += fmt::format("max_shear_displacement_m = {}\n", num(s.max_shear_displacement_m));
  o += fmt::format("strain = \"{}\"\n", s.strain == StrainDefinition::height ? "height" : "length");
  o += "ball_wall = " + contact_inline(s.ball_wall) + "\n";
  o += "during_shear = " + inline_patch(sc.during_shear) + "\n";
  o += fmt::format("servo_gain_factor = {}\nservo_max_speed_m_per_s = {}\n"
                   "servo_integral_time_s = {}\n",
                   num(s.servo_gain_factor), num(s.servo_max_speed_m_per_s),
                   num(s.servo_integral_time_s));
  if (!sc.preparation.enabled)
    o += fmt::format("consolidation_ratio = {}\nconsolidation_max_steps = {}\n",
                     num(s.consolidation_ratio), s.consolidation_max_steps);
  o += fmt::format("consolidation_stress_tolerance = {}\nrecord_interval_steps = {}\n",
                   num(s.consolidation_stress_tolerance), s.record_interval_steps);
  o += fmt::format("unload_reload_fraction = {}\n", num(s.unload_reload_fraction));
  o += fmt::format("local_damping = {}\ng_level = {}\nthreads = {}\n", num(sc.local_damping),
                   num(sc.g_level), sc.threads);
  o += fmt::format("checkpoint_interval_min = {}\n", num(sc.checkpoint_interval_min));
  return o;
}

} // namespace centridem
