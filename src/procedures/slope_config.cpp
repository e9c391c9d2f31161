#include "procedures/slope_config.hpp"

#include "base/errors.hpp"
#include "io/scenario.hpp"
#include "io/toml_read.hpp"
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

using namespace tomlread;

const Keys kTopKeys = {"description", "specimen", "preparation", "contact",
                       "slope",       "field",    "moisture",    "limit_equilibrium",
                       "trial",       "failure",  "campaign",    "output"};
const Keys kLimitEquilibriumKeys = {"cohesion_Pa", "friction_angle_deg", "bulk_density_kg_m3",
                                    "source"};
const Keys kContactSectionKeys = {"ball_ball"};
const Keys kModelNames = {"linear", "rrlinear", "arrlinear"};
const Keys kSlopeKeys = {
    "name",      "size_reduction_factor", "total_height_m", "foundation_height_m",     "benches",
    "breadth_m", "crest_to_wall_m",       "length_m",       "attraction_divided_by_s", "walls"};
const Keys kBenchKeys = {"height_m", "width_m", "face_angle_deg"};
const Keys kWallKeys = {"chamber", "end_wall", "end"};
const Keys kFieldKeys = {"kind", "base_radius_m", "reference", "reference_radius_m",
                         "axis", "coriolis"};
const Keys kMoistureKeys = {"profile", "adhesion",    "reference_water_content_percent",
                            "table",   "top_factor",  "bottom_factor",
                            "bands",   "new_contacts"};
const Keys kTrialKeys = {"local_damping",
                         "equilibrium_ratio",
                         "foundation_max_steps",
                         "rest_kinetic_ratio",
                         "check_interval_steps",
                         "max_time_s",
                         "min_time_s",
                         "after_failure_time_s",
                         "after_cut",
                         "at_cut",
                         "threads",
                         "checkpoint_interval_min",
                         "checkpoint_interval_steps"};
const Keys kFailureKeys = {"displacement_threshold_d50",
                           "displacement_threshold_m",
                           "link_distance_factor",
                           "min_particles",
                           "min_volume_fraction",
                           "moving_speed_factor",
                           "moving_speed_m_s",
                           "consecutive_checks",
                           "failure_displacement_d50",
                           "equilibrium_ratio",
                           "growth_tolerance",
                           "slip_surface_bin_d50",
                           "start_share",
                           "bench_share"};
const Keys kCampaignKeys = {"g_levels", "search", "schedule", "jobs"};
const Keys kSearchKeys = {"stable_g", "failed_g", "tolerance_g"};
const Keys kScheduleKeys = {"g_levels", "step_g", "max_g", "max_slides"};
const Keys kOutputKeys = {"colour_range_m", "frame_interval_steps", "vtk", "picture_width_px"};

auto positive = [](double v) { return v > 0; };
auto non_negative = [](double v) { return v >= 0; };
auto unit_open = [](double v) { return v >= 0 && v < 1; };

const toml::table* opt_table(const toml::table& root, const std::string& key,
                             const std::string& what) {
  const toml::node* n = root.get(key);
  return n ? &as_table(*n, key, what) : nullptr;
}

bool opt_bool(const toml::table& t, const std::string& path, std::string_view k, bool def) {
  const toml::node* n = t.get(k);
  return n ? as_bool(*n, path_of(path, k)) : def;
}

// A list of [x, y] points with x strictly increasing, x within [x_min,
// x_max], y >= 0 (and <= y_max) (`what` names x and y for the messages).
std::vector<std::array<double, 2>> point_list(const toml::node& n, const std::string& key,
                                              double x_min, double x_max, double y_max,
                                              const std::string& what) {
  const toml::array* a = n.as_array();
  if (!a || a->empty()) fail(key, n, "expected a non-empty list of points [" + what + "]");
  std::vector<std::array<double, 2>> out;
  for (std::size_t i = 0; i < a->size(); ++i) {
    const std::string ki = fmt::format("{}[{}]", key, i);
    const toml::array* p = (*a)[i].as_array();
    if (!p || p->size() != 2) fail(ki, (*a)[i], "a point [" + what + "]");
    const double x = as_number((*p)[0], ki + "[0]", "a number");
    const double y = as_number((*p)[1], ki + "[1]", "a number");
    if (!(x >= x_min && x <= x_max))
      fail(ki + "[0]", (*p)[0], fmt::format("in [{:g}, {:g}]", x_min, x_max));
    if (!(y >= 0 && y <= y_max)) fail(ki + "[1]", (*p)[1], fmt::format("in [0, {:g}]", y_max));
    if (!out.empty() && !(x > out.back()[0]))
      fail(ki + "[0]", (*p)[0], "points in strictly increasing order of their first number");
    out.push_back({x, y});
  }
  return out;
}

// [moisture] (physics/moisture.hpp; docs/slope.md "Moisture").
MoistureSpec read_moisture(const toml::table& t, const std::string& P) {
  MoistureSpec m;
  m.enabled = true;
  const bool linear = t.get("top_factor") || t.get("bottom_factor");
  if (linear)
    for (const char* k : {"profile", "adhesion", "reference_water_content_percent", "table"})
      if (const toml::node* n = t.get(k))
        fail(P + "." + k, *n,
             "not with moisture.top_factor / bottom_factor (a factor linear in height, no water "
             "contents): give either those or the water-content keys");
  if (const toml::node* n = t.get("profile"))
    m.profile = point_list(*n, P + ".profile", 0.0, 1.0, 100.0,
                           "height over the model's height 0 (floor) .. 1 (crest), water "
                           "content 0 .. 100 %");
  if (const toml::node* n = t.get("adhesion")) {
    const std::string a =
        as_string(*n, P + ".adhesion", "\"proportional\", \"constant\" or \"table\"");
    if (a == "proportional")
      m.adhesion = MoistureSpec::Adhesion::proportional;
    else if (a == "constant")
      m.adhesion = MoistureSpec::Adhesion::constant;
    else if (a == "table")
      m.adhesion = MoistureSpec::Adhesion::table;
    else
      fail(P + ".adhesion", *n,
           "\"proportional\" (F0 x w / reference_water_content_percent), \"constant\" (F0 at "
           "every height) or \"table\" (moisture.table of [water content %, factor])");
  }
  if (auto v = opt_number(
          t, P, "reference_water_content_percent", [](double x) { return x > 0 && x <= 100; },
          "the water content of the calibrated F0, in (0, 100] [%]"))
    m.reference_water_content_percent = *v;
  if (const toml::node* n = t.get("table")) {
    if (m.adhesion != MoistureSpec::Adhesion::table)
      fail(P + ".table", *n, "only with moisture.adhesion = \"table\"");
    m.table = point_list(*n, P + ".table", 0.0, 100.0, 1e6,
                         "water content 0 .. 100 %, factor on F0 >= 0");
  } else if (m.adhesion == MoistureSpec::Adhesion::table) {
    missing(
        P + ".table",
        "moisture.adhesion = \"table\" needs the table: [[water content %, factor on F0], ...]");
  }
  if (linear) {
    m.adhesion = MoistureSpec::Adhesion::linear_factor;
    const std::string f = "a factor on F0 >= 0 [-]";
    if (auto v = opt_number(t, P, "top_factor", non_negative, f)) m.top_factor = *v;
    if (auto v = opt_number(t, P, "bottom_factor", non_negative, f)) m.bottom_factor = *v;
  }
  if (auto v = opt_integer(
          t, P, "bands", [](long x) { return x >= 1 && x <= 1000; }, "1 .. 1000"))
    m.bands = static_cast<int>(*v);
  m.new_contacts = opt_bool(t, P, "new_contacts", true);
  return m;
}

// A list of g-levels > 0, strictly increasing when `increasing`.
std::vector<double> g_list(const toml::node& n, const std::string& key, bool increasing) {
  const toml::array* a = n.as_array();
  if (!a || a->empty()) fail(key, n, "expected a non-empty list of g-levels > 0, e.g. [35, 40]");
  std::vector<double> out;
  for (std::size_t i = 0; i < a->size(); ++i) {
    const std::string ki = fmt::format("{}[{}]", key, i);
    const double v = as_number((*a)[i], ki, "a g-level > 0");
    if (!(v > 0) || v > 1e4) fail(ki, (*a)[i], "a g-level in (0, 10000]");
    for (double prev : out)
      if (std::abs(prev - v) <= 1e-9 * v) fail(ki, (*a)[i], "each g-level once");
    if (increasing && !out.empty() && !(v > out.back()))
      fail(ki, (*a)[i], "g-levels in increasing order (the schedule raises g)");
    out.push_back(v);
  }
  return out;
}

BenchedSlope read_slope(const toml::table& t, const std::string& P, std::string& name) {
  BenchedSlope b;
  if (const toml::node* n = t.get("name")) name = as_string(*n, P + ".name", "a label");
  auto num_key = [&](std::string_view k, double& out, const std::string& allowed) {
    if (auto v = opt_number(t, P, k, positive, allowed)) out = *v;
  };
  num_key("size_reduction_factor", b.size_reduction_factor, "DEM = model x s: in [1e-4, 1] [-]");
  num_key("total_height_m", b.total_height_m, "model height floor to crest > 0 [m]");
  if (auto v = opt_number(t, P, "foundation_height_m", non_negative, "soil below the toe >= 0 [m]"))
    b.foundation_height_m = *v;
  num_key("breadth_m", b.breadth_m, "model breadth > 0 [m]");
  num_key("crest_to_wall_m", b.crest_to_wall_m, "back wall to crest edge > 0 [m]");
  num_key("length_m", b.length_m, "back wall to end of model > 0 [m]");
  const toml::node* bn = t.get("benches");
  if (!bn)
    missing(P + ".benches", "a list of benches from the toe up, e.g. [{ height_m = 0.0375, "
                            "width_m = 0.03, face_angle_deg = 70 }, { height_m = 0.1125 }]");
  const toml::array* a = bn->as_array();
  if (!a || a->empty())
    fail(P + ".benches", *bn, "expected a non-empty list of { height_m, width_m, face_angle_deg }");
  for (std::size_t i = 0; i < a->size(); ++i) {
    const std::string bp = fmt::format("{}.benches[{}]", P, i);
    const toml::table& bt = as_table((*a)[i], bp, "{ height_m, width_m, face_angle_deg }");
    check_keys(bt, bp, kBenchKeys);
    Bench bench;
    if (auto v = opt_number(bt, bp, "height_m", positive, "the face height > 0 [m]"))
      bench.height_m = *v;
    else
      missing(bp + ".height_m", "the bench's face height > 0 [m, model scale]");
    bench.width_m = opt_number(bt, bp, "width_m", non_negative, "bench top width >= 0 [m]");
    if (auto v = opt_number(
            bt, bp, "face_angle_deg", [](double x) { return x > 0 && x <= 90; },
            "face inclination from horizontal in (0, 90] [deg]"))
      bench.face_angle_deg = *v;
    b.benches.push_back(bench);
  }
  validate(b, P);
  return b;
}

ContactProperties read_wall(const toml::table& t, const std::string& P, std::string_view k,
                            const ContactProperties& base) {
  const toml::node* n = t.get(k);
  if (!n) return base;
  const std::string key = path_of(P, k);
  ContactProperties c = apply(read_contact_patch(*n, key), base);
  validate(c, key);
  return c;
}

FailureCriteria read_failure(const toml::table& t, const std::string& P) {
  FailureCriteria c;
  auto any = [](double) { return true; };
  auto set = [&](std::string_view k, double& out) {
    if (auto v = opt_number(t, P, k, any, "a number (see docs/slope.md)")) out = *v;
  };
  set("displacement_threshold_d50", c.mass.displacement_threshold_d50);
  set("displacement_threshold_m", c.mass.displacement_threshold_m);
  set("link_distance_factor", c.mass.link_distance_factor);
  set("min_volume_fraction", c.min_volume_fraction);
  set("moving_speed_factor", c.moving_speed_factor);
  set("moving_speed_m_s", c.moving_speed_m_s);
  set("equilibrium_ratio", c.equilibrium_ratio);
  set("failure_displacement_d50", c.failure_displacement_d50);
  set("growth_tolerance", c.growth_tolerance);
  set("slip_surface_bin_d50", c.slip_surface_bin_d50);
  set("start_share", c.start_share);
  set("bench_share", c.bench_share);
  if (auto v = opt_integer(
          t, P, "min_particles", [](long x) { return x >= 1; }, "particles >= 1"))
    c.min_particles = static_cast<std::size_t>(*v);
  if (auto v = opt_integer(
          t, P, "consecutive_checks", [](long x) { return x >= 1 && x <= 1000; },
          "checks in a row, 1 .. 1000"))
    c.consecutive_checks = static_cast<int>(*v);
  validate(c, P);
  return c;
}

} // namespace

ContactProperties SlopeScenario::soil() const {
  ContactProperties c = ball_ball;
  if (attraction_divided_by_s) c.attraction_force_N /= slope.size_reduction_factor;
  return c;
}

ContactProperties SlopeScenario::soil_after_cut() const {
  return apply(trial.after_cut, soil());
}

ContactProperties SlopeScenario::soil_at_cut() const {
  return apply(trial.at_cut, soil());
}

SlopeScenario parse_slope_scenario(std::string_view text, const std::string& source_name,
                                   const std::string& base_dir) {
  const toml::table root = tomlread::parse_document(text, source_name);
  check_keys(root, "", kTopKeys);
  SlopeScenario sc;
  sc.source_path = source_name;
  sc.base_dir = base_dir;
  if (const toml::node* d = root.get("description"))
    sc.description = as_string(*d, "description", "a one-line description");

  // [slope]
  {
    const std::string P = "slope";
    const toml::table* t = opt_table(root, P, "the benched slope (docs/slope.md)");
    if (!t) missing(P, "a [slope] table with at least benches (docs/slope.md)");
    check_keys(*t, P, kSlopeKeys);
    sc.slope = read_slope(*t, P, sc.name);
    sc.attraction_divided_by_s = opt_bool(*t, P, "attraction_divided_by_s", true);
    sc.walls.chamber = paper::ball_wall(0.2);
    sc.walls.end = paper::ball_wall(0.0);
    if (const toml::node* wn = t->get("walls")) {
      const std::string W = P + ".walls";
      const toml::table& w = as_table(*wn, W, "{ chamber = {...}, end_wall = true, end = {...} }");
      check_keys(w, W, kWallKeys);
      sc.walls.chamber = read_wall(w, W, "chamber", sc.walls.chamber);
      sc.walls.end_wall = opt_bool(w, W, "end_wall", true);
      sc.walls.end = read_wall(w, W, "end", sc.walls.end);
    }
  }

  // [contact.ball_ball]: complete.
  {
    const toml::node* contact = root.get("contact");
    const std::string what = "a [contact.ball_ball] table with at least model and "
                             "effective_modulus_Pa (docs/scenario.md)";
    if (!contact) missing("contact.ball_ball", what);
    const toml::table& ct = as_table(*contact, "contact", "[contact.ball_ball]");
    check_keys(ct, "contact", kContactSectionKeys);
    const toml::node* bb = ct.get("ball_ball");
    if (!bb) missing("contact.ball_ball", what);
    const ContactPatch p = read_contact_patch(*bb, "contact.ball_ball");
    if (!p.model)
      missing("contact.ball_ball.model", "the contact model: one of " + join(kModelNames));
    if (!p.effective_modulus_Pa && !p.normal_stiffness_N_per_m)
      missing("contact.ball_ball.effective_modulus_Pa",
              "the effective modulus E* > 0 [Pa], or normal_stiffness_N_per_m + "
              "shear_stiffness_N_per_m");
    sc.ball_ball = apply(p, ContactProperties{});
    validate(sc.ball_ball, "contact.ball_ball");
  }

  // [specimen]: the region defaults to the slope's DEM box.
  {
    const double s = sc.slope.size_reduction_factor;
    const Box box{{0, 0, 0},
                  {sc.slope.length_m * s, sc.slope.breadth_m * s, sc.slope.total_height_m * s}};
    sc.specimen = parse_specimen(text, source_name, base_dir, box);
    if (sc.specimen.source != SpecimenSpec::Source::file) {
      const Box r = *sc.specimen.region;
      const double tol = 1e-9;
      bool ok = true;
      for (int a = 0; a < 3; ++a)
        ok = ok && std::abs(r.lo[a] - box.lo[a]) < tol && std::abs(r.hi[a] - box.hi[a]) < tol;
      if (!ok)
        throw InputError("specimen.region",
                         fmt::format("{{ lo_m = {}, hi_m = {} }}", vec(r.lo), vec(r.hi)),
                         fmt::format("must be the slope's DEM box lo_m = [0, 0, 0], hi_m = {} "
                                     "(slope length, breadth, total height x s); leave it out to "
                                     "get it",
                                     vec(box.hi)));
    }
  }

  // [preparation] (io/preparation_config.hpp): the foundation is generated
  // overfilled, compacted, switched to the soil, settled and trimmed.
  sc.preparation = read_preparation(root, sc.ball_ball);
  if (sc.preparation.enabled && sc.specimen.source == SpecimenSpec::Source::file)
    throw InputError("preparation", "a table",
                     "only for a distributed specimen (the foundation is generated overfilled "
                     "and trimmed): remove [preparation] or specimen.file");

  // [field]
  if (const toml::table* t = opt_table(root, "field", "the body field (docs/slope.md)")) {
    const std::string P = "field";
    check_keys(*t, P, kFieldKeys);
    if (const toml::node* n = t->get("kind")) {
      const std::string k = as_string(*n, P + ".kind", "\"uniform\" or \"centrifuge\"");
      if (k == "uniform")
        sc.field.kind = FieldKind::uniform;
      else if (k == "centrifuge")
        sc.field.kind = FieldKind::centrifuge;
      else
        fail(P + ".kind", *n, "\"uniform\" (n g / s downwards) or \"centrifuge\" (radial)");
    }
    if (auto v = opt_number(*t, P, "base_radius_m", positive,
                            "radius of the model base from the axis > 0 [m, real scale]"))
      sc.field.base_radius_m = *v;
    if (const toml::node* n = t->get("reference")) {
      const std::string r = as_string(*n, P + ".reference", "\"third_depth\" or \"base\"");
      if (r == "third_depth")
        sc.field.reference = FieldReference::third_depth;
      else if (r == "base")
        sc.field.reference = FieldReference::base;
      else
        fail(P + ".reference", *n,
             "\"third_depth\" (n g at one third of the model's depth below its top) or "
             "\"base\" (n g at the model's base); or give reference_radius_m instead");
    }
    if (const toml::node* n = t->get("reference_radius_m")) {
      if (t->get("reference"))
        fail(P + ".reference_radius_m", *n,
             "either field.reference or field.reference_radius_m, not both");
      sc.field.reference_radius_m = as_number(*n, P + ".reference_radius_m", "a radius [m]");
      if (!(sc.field.reference_radius_m > 0))
        fail(P + ".reference_radius_m", *n,
             "the radius where the g-level is n, > 0 [m, real scale]");
      sc.field.reference = FieldReference::radius;
    }
    if (const toml::node* n = t->get("axis")) {
      const std::string a = as_string(*n, P + ".axis", "\"y\" or \"x\"");
      if (a != "x" && a != "y")
        fail(P + ".axis", *n,
             "\"y\" (rotation in the section plane) or \"x\" (in the breadth plane)");
      sc.field.axis = a[0];
    }
    sc.field.coriolis = opt_bool(*t, P, "coriolis", false);
    const double H = sc.slope.total_height_m;
    if (sc.field.kind == FieldKind::centrifuge && !(sc.field.base_radius_m > H))
      throw InputError(P + ".base_radius_m", fmt::format("{:g}", sc.field.base_radius_m),
                       fmt::format("must exceed the model height {:g} m (the axis lies above "
                                   "the model)",
                                   H));
  }

  // [moisture]
  if (const toml::table* t = opt_table(root, "moisture", "the adhesion gradient")) {
    const std::string P = "moisture";
    check_keys(*t, P, kMoistureKeys);
    sc.moisture = read_moisture(*t, P);
  }

  // [limit_equilibrium]
  if (const toml::table* t = opt_table(root, "limit_equilibrium",
                                       "the soil's c and phi for the limit-equilibrium estimate")) {
    const std::string P = "limit_equilibrium";
    check_keys(*t, P, kLimitEquilibriumKeys);
    LimitEquilibriumSpec& le = sc.limit_equilibrium;
    le.enabled = true;
    const std::string c_allowed = "the soil's cohesion c >= 0 [Pa] (from the shear box on F0 / s)";
    const std::string phi_allowed = "the soil's friction angle in (0, 90) [deg]";
    auto c = opt_number(*t, P, "cohesion_Pa", non_negative, c_allowed);
    if (!c) missing(P + ".cohesion_Pa", c_allowed);
    auto phi = opt_number(
        *t, P, "friction_angle_deg", [](double x) { return x > 0 && x < 90; }, phi_allowed);
    if (!phi) missing(P + ".friction_angle_deg", phi_allowed);
    le.cohesion_Pa = *c;
    le.friction_angle_deg = *phi;
    if (auto v = opt_number(
            *t, P, "bulk_density_kg_m3", [](double x) { return x >= 0 && x <= 3e4; },
            "the soil's bulk density: 0 (from the prepared foundation) to 30000 [kg/m^3]"))
      le.bulk_density_kg_m3 = *v;
    if (const toml::node* n = t->get("source"))
      le.source = as_string(*n, P + ".source", "where c and phi come from (text)");
    if (le.bulk_density_kg_m3 == 0 && !sc.preparation.enabled)
      missing(P + ".bulk_density_kg_m3",
              "the soil's bulk density > 0 [kg/m^3] (it is taken from the prepared foundation "
              "only when the scenario has a [preparation] table)");
  }

  // [trial]
  TrialSpec& tr = sc.trial;
  tr.after_cut.rolling_friction = 0.0; // the paper's rule (section 3.3)
  if (const toml::table* t = opt_table(root, "trial", "one trial's settings (docs/slope.md)")) {
    const std::string P = "trial";
    check_keys(*t, P, kTrialKeys);
    if (auto v = opt_number(*t, P, "local_damping", unit_open, "Cundall local damping in [0, 1)"))
      tr.local_damping = *v;
    if (auto v = opt_number(*t, P, "equilibrium_ratio", positive,
                            "mean unbalanced-force ratio ending the foundation stage > 0"))
      tr.equilibrium_ratio = *v;
    auto pos_long = [](long x) { return x > 0; };
    if (auto v = opt_integer(*t, P, "foundation_max_steps", pos_long, "a step limit > 0"))
      tr.foundation_max_steps = *v;
    if (auto v = opt_number(
            *t, P, "rest_kinetic_ratio", [](double x) { return x > 0 && x < 1; },
            "kinetic energy / (weight x d50) below which a packing is at rest: in (0, 1) [-]"))
      tr.rest_kinetic_ratio = *v;
    if (auto v = opt_integer(*t, P, "check_interval_steps", pos_long, "steps between checks > 0"))
      tr.check_interval_steps = *v;
    if (auto v = opt_number(*t, P, "max_time_s", positive, "trial time after the cut > 0 [s]"))
      tr.max_time_s = *v;
    if (auto v = opt_number(*t, P, "min_time_s", non_negative,
                            "trial time after the cut before the slope may be called stable "
                            ">= 0 [s]"))
      tr.min_time_s = *v;
    if (tr.min_time_s > tr.max_time_s)
      throw InputError(P + ".min_time_s", num(tr.min_time_s),
                       fmt::format("at most {}.max_time_s = {} [s]", P, num(tr.max_time_s)));
    if (auto v = opt_number(*t, P, "after_failure_time_s", non_negative,
                            "time to follow a slide after its onset >= 0 [s]"))
      tr.after_failure_time_s = *v;
    if (const toml::node* n = t->get("after_cut")) {
      tr.after_cut = read_contact_patch(*n, P + ".after_cut");
      validate(apply(tr.after_cut, sc.soil()), P + ".after_cut");
    }
    if (const toml::node* n = t->get("at_cut")) {
      tr.at_cut = read_contact_patch(*n, P + ".at_cut");
      validate(apply(tr.at_cut, sc.soil()), P + ".at_cut");
    }
    if (auto v = opt_integer(
            *t, P, "threads", [](long x) { return x >= 0 && x <= 1024; },
            "OpenMP threads per trial: 0 (the OpenMP default) to 1024"))
      tr.threads = static_cast<int>(*v);
    if (auto v = opt_number(*t, P, "checkpoint_interval_min", non_negative,
                            "wall-clock minutes between checkpoints >= 0 (0 = none)"))
      tr.checkpoint_interval_min = *v;
    if (auto v = opt_integer(
            *t, P, "checkpoint_interval_steps", [](long x) { return x >= 0; },
            "steps between checkpoints >= 0 (0 = none)"))
      tr.checkpoint_interval_steps = *v;
  }

  // [failure]
  if (const toml::table* t = opt_table(root, "failure", "failure detection (docs/slope.md)")) {
    check_keys(*t, "failure", kFailureKeys);
    sc.failure = read_failure(*t, "failure");
  }

  // [campaign]
  {
    const std::string P = "campaign";
    const toml::table* t = opt_table(root, P, "g-levels, search or schedule (docs/slope.md)");
    if (!t)
      missing(P, "a [campaign] table: g_levels = [35, 40], or search = { stable_g, failed_g }, "
                 "or schedule = { g_levels, step_g, max_g }");
    check_keys(*t, P, kCampaignKeys);
    CampaignSpec& c = sc.campaign;
    const int kinds =
        (t->get("g_levels") ? 1 : 0) + (t->get("search") ? 1 : 0) + (t->get("schedule") ? 1 : 0);
    if (kinds != 1)
      throw InputError(P, kinds == 0 ? "(none given)" : "(more than one given)",
                       "exactly one of g_levels (independent trials), search (critical-g "
                       "bisection) or schedule (one model, g raised in steps)");
    if (const toml::node* n = t->get("g_levels")) {
      c.kind = CampaignKind::list;
      c.g_levels = g_list(*n, P + ".g_levels", false);
    } else if (const toml::node* sn = t->get("search")) {
      c.kind = CampaignKind::search;
      const std::string S = P + ".search";
      const toml::table& st = as_table(*sn, S, "{ stable_g, failed_g, tolerance_g }");
      check_keys(st, S, kSearchKeys);
      const std::string g = "a g-level > 0";
      if (auto v = opt_number(st, S, "stable_g", positive, g))
        c.stable_g = *v;
      else
        missing(S + ".stable_g", "a g-level at which the slope is (expected) stable");
      if (auto v = opt_number(st, S, "failed_g", positive, g))
        c.failed_g = *v;
      else
        missing(S + ".failed_g", "a g-level at which the slope (expectedly) fails");
      if (!(c.failed_g > c.stable_g))
        fail(S + ".failed_g", *st.get("failed_g"),
             fmt::format("must exceed stable_g = {:g}", c.stable_g));
      if (auto v = opt_number(st, S, "tolerance_g", positive, "bracket width to stop at > 0 [g]"))
        c.tolerance_g = *v;
    } else {
      c.kind = CampaignKind::schedule;
      const std::string S = P + ".schedule";
      const toml::node* sn2 = t->get("schedule");
      const toml::table& st = as_table(*sn2, S, "{ g_levels, step_g, max_g, max_slides }");
      check_keys(st, S, kScheduleKeys);
      if (const toml::node* gn = st.get("g_levels"))
        c.g_levels = g_list(*gn, S + ".g_levels", true);
      else
        missing(S + ".g_levels", "the first g-levels, increasing, e.g. [10, 20, 30, 40, 50]");
      if (auto v = opt_number(st, S, "step_g", positive, "g added per step after g_levels > 0"))
        c.step_g = *v;
      c.max_g = std::max(c.g_levels.back(), 100.0);
      if (auto v = opt_number(st, S, "max_g", positive, "the highest g-level to reach > 0"))
        c.max_g = *v;
      if (c.max_g < c.g_levels.back())
        fail(S + ".max_g", *st.get("max_g"), "must be at least the last of g_levels");
      if (auto v = opt_integer(
              st, S, "max_slides", [](long x) { return x >= 1 && x <= 100; }, "1 .. 100"))
        c.max_slides = static_cast<int>(*v);
    }
    if (auto v = opt_integer(
            *t, P, "jobs", [](long x) { return x >= 1 && x <= 256; }, "trials at once, 1 .. 256"))
      c.jobs = static_cast<int>(*v);
  }

  // [output]
  if (const toml::table* t = opt_table(root, "output", "pictures and frames (docs/slope.md)")) {
    const std::string P = "output";
    check_keys(*t, P, kOutputKeys);
    if (const toml::node* n = t->get("colour_range_m")) {
      const toml::array* a = n->as_array();
      const std::string allowed = "[min, max] displacements for the log colour scale, "
                                  "0 < min < max [m]";
      if (!a || a->size() != 2) fail(P + ".colour_range_m", *n, allowed);
      const double lo = as_number((*a)[0], P + ".colour_range_m[0]", allowed);
      const double hi = as_number((*a)[1], P + ".colour_range_m[1]", allowed);
      if (!(lo > 0 && hi > lo)) fail(P + ".colour_range_m", *n, allowed);
      sc.output.colour_min_m = lo;
      sc.output.colour_max_m = hi;
    }
    if (auto v = opt_integer(
            *t, P, "frame_interval_steps", [](long x) { return x >= 0; },
            "steps between frames >= 0 (0: first and last only)"))
      sc.output.frame_interval_steps = *v;
    sc.output.vtk = opt_bool(*t, P, "vtk", true);
    if (auto v = opt_integer(
            *t, P, "picture_width_px", [](long x) { return x >= 200 && x <= 8000; },
            "200 .. 8000 pixels"))
      sc.output.picture_width_px = static_cast<int>(*v);
  }
  return sc;
}

SlopeScenario load_slope_scenario(const std::string& path,
                                  const std::vector<std::string>& overrides) {
  const tomlread::ScenarioText t = tomlread::read_scenario_text(path, overrides);
  return parse_slope_scenario(t.text, t.source, t.base_dir);
}

void apply_scale(SlopeScenario& sc, double s, const std::string& key) {
  if (!(s >= 1e-4 && s <= 1))
    throw InputError(key, fmt::format("{:g}", s), "a size reduction factor in [1e-4, 1]");
  if (sc.attraction_divided_by_s) {
    sc.ball_ball.attraction_force_N /= sc.slope.size_reduction_factor;
    sc.attraction_divided_by_s = false;
  }
  sc.slope.size_reduction_factor = s;
  validate(sc.slope, "slope");
  if (sc.specimen.source != SpecimenSpec::Source::file)
    sc.specimen.region = Box{
        {0, 0, 0}, {sc.slope.length_m * s, sc.slope.breadth_m * s, sc.slope.total_height_m * s}};
}

std::string resolved_slope_toml(const SlopeScenario& sc) {
  std::string o;
  if (!sc.description.empty()) o += "description = " + quote(sc.description) + "\n\n";
  o += resolved_specimen_toml(sc.specimen);
  o += resolved_preparation_toml(sc.preparation);
  o += "\n[contact]\nball_ball = " + contact_inline(sc.ball_ball) + "\n";
  const BenchedSlope& b = sc.slope;
  o += "\n[slope]\n";
  if (!sc.name.empty()) o += "name = " + quote(sc.name) + "\n";
  o += fmt::format("size_reduction_factor = {}\ntotal_height_m = {}\nfoundation_height_m = {}\n",
                   num(b.size_reduction_factor), num(b.total_height_m), num(b.foundation_height_m));
  o += "benches = [\n";
  for (const Bench& bench : b.benches) {
    o += fmt::format("  {{ height_m = {}", num(bench.height_m));
    if (bench.width_m) o += fmt::format(", width_m = {}", num(*bench.width_m));
    o += fmt::format(", face_angle_deg = {} }},\n", num(bench.face_angle_deg));
  }
  o += "]\n";
  o += fmt::format("breadth_m = {}\ncrest_to_wall_m = {}\nlength_m = {}\n", num(b.breadth_m),
                   num(b.crest_to_wall_m), num(b.length_m));
  o += fmt::format("attraction_divided_by_s = {}\n", sc.attraction_divided_by_s);
  o += fmt::format("walls = {{ chamber = {}, end_wall = {}, end = {} }}\n",
                   contact_inline(sc.walls.chamber), sc.walls.end_wall,
                   contact_inline(sc.walls.end));
  const FieldSpec& f = sc.field;
  o += fmt::format("\n[field]\nkind = \"{}\"\nbase_radius_m = {}\n",
                   f.kind == FieldKind::uniform ? "uniform" : "centrifuge", num(f.base_radius_m));
  if (f.reference == FieldReference::radius)
    o += fmt::format("reference_radius_m = {}\n", num(f.reference_radius_m));
  else
    o += fmt::format("reference = \"{}\"\n",
                     f.reference == FieldReference::base ? "base" : "third_depth");
  o += fmt::format("axis = \"{}\"\ncoriolis = {}\n", f.axis, f.coriolis);
  if (const MoistureSpec& m = sc.moisture; m.enabled) {
    auto points = [](const std::vector<std::array<double, 2>>& p) {
      std::string t = "[";
      for (std::size_t k = 0; k < p.size(); ++k)
        t += fmt::format("{}[{}, {}]", k ? ", " : "", num(p[k][0]), num(p[k][1]));
      return t + "]";
    };
    o += "\n[moisture]\n";
    if (m.adhesion == MoistureSpec::Adhesion::linear_factor) {
      o += fmt::format("top_factor = {}\nbottom_factor = {}\n", num(m.top_factor),
                       num(m.bottom_factor));
    } else {
      const char* a = m.adhesion == MoistureSpec::Adhesion::constant ? "constant"
                      : m.adhesion == MoistureSpec::Adhesion::table  ? "table"
                                                                     : "proportional";
      o += fmt::format("profile = {}\nadhesion = \"{}\"\nreference_water_content_percent = {}\n",
                       points(m.profile), a, num(m.reference_water_content_percent));
      if (m.adhesion == MoistureSpec::Adhesion::table)
        o += fmt::format("table = {}\n", points(m.table));
    }
    o += fmt::format("bands = {}\nnew_contacts = {}\n", m.bands, m.new_contacts);
  }
  if (const LimitEquilibriumSpec& le = sc.limit_equilibrium; le.enabled)
    o += fmt::format("\n[limit_equilibrium]\ncohesion_Pa = {}\nfriction_angle_deg = {}\n"
                     "bulk_density_kg_m3 = {}\nsource = {}\n",
                     num(le.cohesion_Pa), num(le.friction_angle_deg), num(le.bulk_density_kg_m3),
                     quote(le.source));
  const TrialSpec& t = sc.trial;
  o += fmt::format("\n[trial]\nlocal_damping = {}\nequilibrium_ratio = {}\n"
                   "foundation_max_steps = {}\nrest_kinetic_ratio = {}\ncheck_interval_steps = {}\n"
                   "max_time_s = {}\nmin_time_s = {}\n"
                   "after_failure_time_s = {}\nafter_cut = {}\nat_cut = {}\nthreads = {}\n"
                   "checkpoint_interval_min = {}\ncheckpoint_interval_steps = {}\n",
                   num(t.local_damping), num(t.equilibrium_ratio), t.foundation_max_steps,
                   num(t.rest_kinetic_ratio), t.check_interval_steps, num(t.max_time_s),
                   num(t.min_time_s), num(t.after_failure_time_s), inline_patch(t.after_cut),
                   inline_patch(t.at_cut), t.threads, num(t.checkpoint_interval_min),
                   t.checkpoint_interval_steps);
  const FailureCriteria& c = sc.failure;
  o += fmt::format("\n[failure]\ndisplacement_threshold_d50 = {}\ndisplacement_threshold_m = {}\n"
                   "link_distance_factor = {}\nmin_particles = {}\nmin_volume_fraction = {}\n"
                   "moving_speed_factor = {}\nmoving_speed_m_s = {}\nconsecutive_checks = {}\n"
                   "failure_displacement_d50 = {}\n"
                   "equilibrium_ratio = {}\ngrowth_tolerance = {}\nslip_surface_bin_d50 = {}\n"
                   "start_share = {}\nbench_share = {}\n",
                   num(c.mass.displacement_threshold_d50), num(c.mass.displacement_threshold_m),
                   num(c.mass.link_distance_factor), c.min_particles, num(c.min_volume_fraction),
                   num(c.moving_speed_factor), num(c.moving_speed_m_s), c.consecutive_checks,
                   num(c.failure_displacement_d50), num(c.equilibrium_ratio),
                   num(c.growth_tolerance), num(c.slip_surface_bin_d50), num(c.start_share),
                   num(c.bench_share));
  const CampaignSpec& cp = sc.campaign;
  auto list = [](const std::vector<double>& v) {
    std::string l;
    for (double x : v) l += (l.empty() ? "" : ", ") + num(x);
    return "[" + l + "]";
  };
  o += "\n[campaign]\n";
  switch (cp.kind) {
  case CampaignKind::list:
    o += "g_levels = " + list(cp.g_levels) + "\n";
    break;
  case CampaignKind::search:
    o += fmt::format("search = {{ stable_g = {}, failed_g = {}, tolerance_g = {} }}\n",
                     num(cp.stable_g), num(cp.failed_g), num(cp.tolerance_g));
    break;
  case CampaignKind::schedule:
    o += fmt::format("schedule = {{ g_levels = {}, step_g = {}, max_g = {}, max_slides = {} }}\n",
                     list(cp.g_levels), num(cp.step_g), num(cp.max_g), cp.max_slides);
    break;
  }
  o += fmt::format("jobs = {}\n", cp.jobs);
  const SlopeOutput& out = sc.output;
  o += fmt::format("\n[output]\ncolour_range_m = [{}, {}]\nframe_interval_steps = {}\nvtk = {}\n"
                   "picture_width_px = {}\n",
                   num(out.colour_min_m), num(out.colour_max_m), out.frame_interval_steps, out.vtk,
                   out.picture_width_px);
  return o;
}

} // namespace centridem
