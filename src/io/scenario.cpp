#include "io/scenario.hpp"
#include "io/toml_read.hpp"

#include "base/errors.hpp"
#include "io/specimen_config.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <toml++/toml.h>

namespace centridem {

namespace fs = std::filesystem;

// ------------------------------------------------------------- public helpers --

BodyField GravitySpec::field() const {
  if (form == Form::acceleration) {
    BodyField f;
    f.gravity_m_s2 = acceleration_m_per_s2;
    return f;
  }
  return BodyField::scaled_gravity(g_level, size_reduction_factor, direction);
}

ContactProperties apply(const ContactPatch& p, ContactProperties c) {
  if (p.model) c.model = *p.model;
  if (p.effective_modulus_Pa || p.stiffness_ratio)
    c.stiffness_method = StiffnessMethod::deformability;
  if (p.normal_stiffness_N_per_m || p.shear_stiffness_N_per_m)
    c.stiffness_method = StiffnessMethod::direct;
  if (p.effective_modulus_Pa) c.effective_modulus_Pa = *p.effective_modulus_Pa;
  if (p.stiffness_ratio) c.stiffness_ratio = *p.stiffness_ratio;
  if (p.normal_stiffness_N_per_m) c.normal_stiffness_N_per_m = *p.normal_stiffness_N_per_m;
  if (p.shear_stiffness_N_per_m) c.shear_stiffness_N_per_m = *p.shear_stiffness_N_per_m;
  if (p.friction) c.friction = *p.friction;
  if (p.rolling_friction) c.rolling_friction = *p.rolling_friction;
  if (p.attraction_force_N) c.attraction_force_N = *p.attraction_force_N;
  if (p.attraction_range_m) c.attraction_range_m = *p.attraction_range_m;
  if (p.dashpot_normal_ratio) c.dashpot_normal_ratio = *p.dashpot_normal_ratio;
  if (p.dashpot_shear_ratio) c.dashpot_shear_ratio = *p.dashpot_shear_ratio;
  if (p.dashpot_mode) c.dashpot_mode = *p.dashpot_mode;
  if (p.limits_use_net_force) c.limits_use_net_force = *p.limits_use_net_force;
  return c;
}

namespace {
// Edit distance counting a swap of two neighbouring letters as one edit
// (optimal string alignment), case-insensitive.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  auto same = [&](std::size_t i, std::size_t j) {
    return std::tolower(static_cast<unsigned char>(a[i])) ==
           std::tolower(static_cast<unsigned char>(b[j]));
  };
  const std::size_t w = b.size() + 1;
  std::vector<std::size_t> d((a.size() + 1) * w);
  for (std::size_t i = 0; i <= a.size(); ++i) d[i * w] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      std::size_t v = std::min({d[(i - 1) * w + j] + 1, d[i * w + j - 1] + 1,
                                d[(i - 1) * w + j - 1] + (same(i - 1, j - 1) ? 0 : 1)});
      if (i > 1 && j > 1 && same(i - 1, j - 2) && same(i - 2, j - 1))
        v = std::min(v, d[(i - 2) * w + j - 2] + 1);
      d[i * w + j] = v;
    }
  return d[a.size() * w + b.size()];
}
} // namespace

std::string did_you_mean(std::string_view key, const std::vector<std::string_view>& allowed) {
  std::string best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max(), best_prefix = 0;
  for (std::string_view k : allowed) {
    std::size_t d = edit_distance(key, k);
    // A key cut short, e.g. given without its unit suffix ("density" for
    // "density_kg_m3").
    if (key.size() >= 3 && k.size() > key.size() && k.substr(0, key.size()) == key) d = 1;
    std::size_t prefix = 0; // ties go to the longer common beginning
    while (prefix < k.size() && prefix < key.size() && k[prefix] == key[prefix]) ++prefix;
    if (d < best_d || (d == best_d && prefix > best_prefix))
      best_d = d, best_prefix = prefix, best = std::string(k);
  }
  const std::size_t limit = std::clamp<std::size_t>(key.size() / 3, 1, 3);
  return best_d <= limit ? best : std::string();
}

std::string_view to_string(StageEnd e) {
  switch (e) {
  case StageEnd::steps:
    return "steps";
  case StageEnd::time:
    return "time_s";
  case StageEnd::equilibrium:
    return "until_equilibrium";
  }
  return "?";
}

Wall WallSpec::make() const {
  Wall w = shape == WallShape::plane
               ? Wall::plane(name, point, normal)
               : Wall::rectangle(name, point, normal, u_direction, size_u_m, size_v_m);
  w.velocity = velocity;
  return w;
}

// ------------------------------------------------------------ TOML reading --

namespace {

using Keys = tomlread::Keys;
using tomlread::as_bool;
using tomlread::as_integer;
using tomlread::as_number;
using tomlread::as_string;
using tomlread::as_table;
using tomlread::as_vec3;
using tomlread::fail;
using tomlread::join;
using tomlread::missing;
using tomlread::num;
using tomlread::opt_integer;
using tomlread::opt_number;
using tomlread::path_of;
using tomlread::quote;
using tomlread::show;
using tomlread::vec;
using tomlread::where;

// A TOML float that reads back exactly (shortest round-trip, always with a
// '.' or an exponent so that it stays a float).

// Where a key lives when it is not in this table: helps with a key written
// after a [sub.table] header (TOML puts it into that sub-table).
const std::map<std::string_view, std::string_view>& key_homes() {
  static const std::map<std::string_view, std::string_view> homes = {
      {"steps", "[[stages]]"},
      {"time_s", "[[stages]]"},
      {"until_equilibrium", "[[stages]]"},
      {"frames_every", "[[stages]]"},
      {"measure_every", "[[stages]]"},
      {"remove_walls", "[[stages]]"},
      {"remove_particles", "[[stages]]"},
      {"modify_contacts", "[[stages]]"},
      {"reset_displacements", "[[stages]]"},
      {"timestep_s", "[simulation]"},
      {"threads", "[simulation]"},
      {"output_dir", "[simulation]"},
      {"checkpoint_interval_min", "[simulation]"},
      {"checkpoint_interval_steps", "[simulation]"},
      {"density_kg_m3", "[particles]"},
      {"file", "[particles]"},
      {"g_level", "[gravity]"},
      {"acceleration_m_per_s2", "[gravity]"},
      {"model", "[contact.ball_ball] or [walls.contact]"},
      {"friction", "[contact.ball_ball] or [walls.contact]"},
      {"effective_modulus_Pa", "[contact.ball_ball] or [walls.contact]"},
      {"velocity_m_per_s", "[[walls]]"},
      {"normal", "[[walls]]"},
  };
  return homes;
}

void check_keys(const toml::table& t, const std::string& path, const Keys& allowed) {
  tomlread::check_keys(t, path, allowed, [](std::string_view key) -> std::string {
    const auto it = key_homes().find(key);
    if (it == key_homes().end()) return "";
    return fmt::format(" (\"{}\" is a key of {}; keys written after a [table] header belong "
                       "to that table: put them before it)",
                       key, it->second);
  });
}

std::string one_of(const Keys& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : (i + 1 == names.size() ? " or " : ", ")) + quote(names[i]);
  return out;
}

// A string that must be one of `names`.
std::string as_choice(const toml::node& n, const std::string& key, const Keys& names) {
  const std::string s = as_string(n, key, "one of " + one_of(names));
  if (std::find(names.begin(), names.end(), s) != names.end()) return s;
  std::string msg = "allowed: " + one_of(names);
  if (const std::string g = did_you_mean(s, names); !g.empty())
    msg = "did you mean \"" + g + "\"? " + msg;
  fail(key, n, msg);
}

// Checked accessors on a table. `ok` is the range test, `allowed` the text
// that says what the range is.
template <class Ok>
double number(const toml::table& t, const std::string& path, std::string_view k, double def, Ok ok,
              const std::string& allowed) {
  return opt_number(t, path, k, ok, allowed).value_or(def);
}

std::optional<bool> opt_bool(const toml::table& t, const std::string& path, std::string_view k) {
  const toml::node* n = t.get(k);
  if (!n) return std::nullopt;
  return as_bool(*n, path_of(path, k));
}

std::optional<Vec3> opt_vec3(const toml::table& t, const std::string& path, std::string_view k,
                             const std::string& allowed) {
  const toml::node* n = t.get(k);
  if (!n) return std::nullopt;
  return as_vec3(*n, path_of(path, k), allowed);
}

Vec3 unit_vector(const toml::table& t, const std::string& path, std::string_view k,
                 std::optional<Vec3> def) {
  const toml::node* n = t.get(k);
  if (!n) {
    if (def) return *def;
    missing(path_of(path, k), "a non-zero direction vector [x, y, z]");
  }
  const Vec3 v = as_vec3(*n, path_of(path, k), "a non-zero direction vector");
  const double len = norm(v);
  if (!(len > 0)) fail(path_of(path, k), *n, "must be a non-zero direction vector");
  return v / len;
}

bool is_name(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  });
}

std::string read_name(const toml::table& t, const std::string& path, const char* what) {
  const toml::node* n = t.get("name");
  const std::string key = path_of(path, "name");
  const std::string rule = "letters, digits, '_' and '-' only (it names files and CSV columns)";
  if (!n) missing(key, fmt::format("the {} name ({})", what, rule));
  const std::string s = as_string(*n, key, rule);
  if (!is_name(s)) fail(key, *n, rule);
  return s;
}

// ------------------------------------------------------------ the sections --

const Keys kTopKeys = {"description", "simulation", "particles", "contact",
                       "walls",       "gravity",    "stages",    "specimen"};
const Keys kSimulationKeys = {"timestep_s",
                              "timestep_safety_factor",
                              "timestep_growth_limit",
                              "timestep_update_interval",
                              "local_damping",
                              "neighbour_skin_m",
                              "max_overlap_fraction",
                              "threads",
                              "output_dir",
                              "progress_interval_s",
                              "checkpoint_interval_min",
                              "checkpoint_interval_steps"};
const Keys kParticleKeys = {"file", "density_kg_m3", "group"};
const Keys kContactSectionKeys = {"ball_ball", "ball_wall"};
const Keys kContactKeys = {"model",
                           "effective_modulus_Pa",
                           "stiffness_ratio",
                           "normal_stiffness_N_per_m",
                           "shear_stiffness_N_per_m",
                           "friction",
                           "rolling_friction",
                           "attraction_force_N",
                           "attraction_range_m",
                           "dashpot_normal_ratio",
                           "dashpot_shear_ratio",
                           "dashpot_mode",
                           "limits_use_net_force"};
const Keys kModelNames = {"linear", "rrlinear", "arrlinear"};
const Keys kGravityKeys = {"acceleration_m_per_s2", "g_level", "size_reduction_factor",
                           "direction"};
const Keys kPlaneKeys = {"name", "type", "point_m", "normal", "velocity_m_per_s", "contact"};
const Keys kRectangleKeys = {"name",        "type",   "centre_m",         "normal",
                             "u_direction", "size_m", "velocity_m_per_s", "contact"};
const Keys kWallTypes = {"plane", "rectangle"};
const Keys kStageKeys = {"name",          "gravity",      "contact",          "modify_contacts",
                         "walls",         "remove_walls", "remove_particles", "reset_displacements",
                         "local_damping", "steps",        "time_s",           "until_equilibrium",
                         "frames_every",  "measure_every"};
const Keys kStageContactKeys = {"ball_ball"};
const Keys kStageWallKeys = {"velocity_m_per_s", "contact"};
const Keys kEquilibriumKeys = {"ratio", "max_steps", "check_interval"};
const Keys kModifyKeys = {"region", "set"};
const Keys kRemoveKeys = {"region", "outside"};
const Keys kRegionKeys = {"lo", "hi"};

auto positive = [](double v) { return v > 0; };
auto non_negative = [](double v) { return v >= 0; };
auto unit_open = [](double v) { return v >= 0 && v < 1; };

ContactPatch read_contact(const toml::node& node, const std::string& path) {
  const toml::table& t = as_table(node, path, "contact properties (see docs/scenario.md)");
  check_keys(t, path, kContactKeys);
  ContactPatch p;
  if (const toml::node* m = t.get("model")) {
    const std::string s = as_choice(*m, path_of(path, "model"), kModelNames);
    p.model = contact_model_from_string(s, path_of(path, "model"));
  }
  p.effective_modulus_Pa =
      opt_number(t, path, "effective_modulus_Pa", positive, "the effective modulus E*: > 0 [Pa]");
  p.stiffness_ratio = opt_number(t, path, "stiffness_ratio", positive, "kappa* = kn/ks: > 0 [-]");
  p.normal_stiffness_N_per_m =
      opt_number(t, path, "normal_stiffness_N_per_m", positive, "kn: > 0 [N/m]");
  p.shear_stiffness_N_per_m =
      opt_number(t, path, "shear_stiffness_N_per_m", non_negative, "ks: >= 0 [N/m]");
  p.friction = opt_number(t, path, "friction", non_negative, "the friction coefficient: >= 0 [-]");
  p.rolling_friction = opt_number(t, path, "rolling_friction", non_negative,
                                  "the rolling friction coefficient: >= 0 [-]");
  p.attraction_force_N = opt_number(t, path, "attraction_force_N", non_negative,
                                    "the maximum attractive force F0: >= 0 [N]");
  p.attraction_range_m =
      opt_number(t, path, "attraction_range_m", non_negative, "the attraction range D0: >= 0 [m]");
  p.dashpot_normal_ratio =
      opt_number(t, path, "dashpot_normal_ratio", unit_open, "must be in [0, 1) [-]");
  p.dashpot_shear_ratio =
      opt_number(t, path, "dashpot_shear_ratio", unit_open, "must be in [0, 1) [-]");
  if (auto m = opt_integer(
          t, path, "dashpot_mode", [](long v) { return v >= 0 && v <= 3; },
          "must be 0, 1, 2 or 3 (PFC dp_mode)"))
    p.dashpot_mode = static_cast<int>(*m);
  p.limits_use_net_force = opt_bool(t, path, "limits_use_net_force");
  const bool deform = p.effective_modulus_Pa || p.stiffness_ratio;
  const bool direct = p.normal_stiffness_N_per_m || p.shear_stiffness_N_per_m;
  if (deform && direct) {
    const char* k =
        p.normal_stiffness_N_per_m ? "normal_stiffness_N_per_m" : "shear_stiffness_N_per_m";
    fail(path_of(path, k), *t.get(k),
         "give either effective_modulus_Pa (+ stiffness_ratio), the deformability method, or "
         "normal_stiffness_N_per_m + shear_stiffness_N_per_m, the direct method; not both");
  }
  return p;
}

// A complete, validated set of properties: `patch` over `base`, or `patch`
// alone (then model and a stiffness are required).
ContactProperties resolve(const ContactPatch& p, const std::optional<ContactProperties>& base,
                          const std::string& path) {
  const bool deform = p.effective_modulus_Pa || p.stiffness_ratio;
  const bool direct = p.normal_stiffness_N_per_m || p.shear_stiffness_N_per_m;
  const auto base_method = base ? std::optional(base->stiffness_method) : std::nullopt;
  if (!base && !p.model)
    missing(path_of(path, "model"), "the contact model: " + one_of(kModelNames));
  if (direct && base_method != StiffnessMethod::direct) {
    if (!p.normal_stiffness_N_per_m)
      missing(path_of(path, "normal_stiffness_N_per_m"),
              "kn > 0 [N/m], with shear_stiffness_N_per_m (direct method)");
    if (!p.shear_stiffness_N_per_m)
      missing(path_of(path, "shear_stiffness_N_per_m"),
              "ks >= 0 [N/m], with normal_stiffness_N_per_m (direct method)");
  }
  if (!p.effective_modulus_Pa &&
      ((!base && !direct) || (deform && base_method == StiffnessMethod::direct)))
    missing(path_of(path, "effective_modulus_Pa"),
            "the effective modulus E* > 0 [Pa] (deformability method: kn = pi r^2 E*/L, "
            "ks = kn/stiffness_ratio), or normal_stiffness_N_per_m + shear_stiffness_N_per_m");
  ContactProperties c = apply(p, base.value_or(ContactProperties{}));
  // Canonical form: the unused method's values at their defaults.
  const ContactProperties d;
  if (c.stiffness_method == StiffnessMethod::direct) {
    c.effective_modulus_Pa = d.effective_modulus_Pa;
    c.stiffness_ratio = d.stiffness_ratio;
  } else {
    c.normal_stiffness_N_per_m = d.normal_stiffness_N_per_m;
    c.shear_stiffness_N_per_m = d.shear_stiffness_N_per_m;
  }
  validate(c, path);
  return c;
}

// The largest body acceleration a scenario may ask for [m/s^2]: 1e6 g, beyond any centrifuge
// (the largest reach about 1e3-1e4 g) and far below where a run's numbers overflow.
constexpr double kMaxGravity_m_s2 = 1e6 * standard_gravity_m_s2;

GravitySpec read_gravity(const toml::node& node, const std::string& path) {
  const toml::table& t = as_table(
      node, path, "acceleration_m_per_s2 = [x, y, z], or g_level (+ size_reduction_factor)");
  check_keys(t, path, kGravityKeys);
  GravitySpec g;
  const bool scaled =
      t.contains("g_level") || t.contains("size_reduction_factor") || t.contains("direction");
  if (const toml::node* a = t.get("acceleration_m_per_s2")) {
    if (scaled)
      fail(path_of(path, "acceleration_m_per_s2"), *a,
           "give either acceleration_m_per_s2, or g_level (+ size_reduction_factor, direction); "
           "not both");
    g.form = GravitySpec::Form::acceleration;
    g.acceleration_m_per_s2 =
        as_vec3(*a, path_of(path, "acceleration_m_per_s2"), "the acceleration [m/s^2]");
    if (!(norm(g.acceleration_m_per_s2) <= kMaxGravity_m_s2))
      fail(path_of(path, "acceleration_m_per_s2"), *a,
           fmt::format("an acceleration of at most {:g} m/s^2 (1e6 g)", kMaxGravity_m_s2));
    return g;
  }
  g.form = GravitySpec::Form::scaled;
  const auto n = opt_number(t, path, "g_level", non_negative, "the g-level n: >= 0 [-]");
  if (!n)
    missing(path_of(path, "g_level"),
            "the g-level n >= 0 (gravity n g / s), or acceleration_m_per_s2 = [x, y, z]");
  g.g_level = *n;
  g.size_reduction_factor = number(t, path, "size_reduction_factor", 1.0, positive,
                                   "the size reduction factor s: > 0 [-] (default 1)");
  g.direction = unit_vector(t, path, "direction", Vec3{0, 0, -1});
  // n g / s must be a number a run can use: 1e308 would give inf and then NaN positions.
  const double a = g.g_level * standard_gravity_m_s2 / g.size_reduction_factor;
  if (!(a <= kMaxGravity_m_s2))
    fail(path_of(path, "g_level"), *t.get("g_level"),
         fmt::format("gravity n g / s = {:g} m/s^2 is beyond {:g} m/s^2 (1e6 g): check g_level "
                     "and size_reduction_factor",
                     a, kMaxGravity_m_s2));
  return g;
}

Box read_box(const toml::node& node, const std::string& path) {
  const toml::table& t = as_table(node, path, "{ lo = [x, y, z], hi = [x, y, z] } [m]");
  check_keys(t, path, kRegionKeys);
  const auto lo = opt_vec3(t, path, "lo", "the box's low corner [m]");
  const auto hi = opt_vec3(t, path, "hi", "the box's high corner [m]");
  if (!lo) missing(path_of(path, "lo"), "the box's low corner [x, y, z] [m]");
  if (!hi) missing(path_of(path, "hi"), "the box's high corner [x, y, z] [m]");
  for (int c = 0; c < 3; ++c)
    if (!((*hi)[c] >= (*lo)[c]))
      fail(path_of(path, "hi"), *t.get("hi"), "must be >= lo on every axis");
  return Box{*lo, *hi};
}

SimulationSpec read_simulation(const toml::table* t, const std::string& default_output) {
  SimulationSpec s;
  s.output_dir = default_output;
  if (!t) return s;
  const std::string p = "simulation";
  check_keys(*t, p, kSimulationKeys);
  WorldSettings& w = s.world;
  if (const toml::node* n = t->get("timestep_s")) {
    const std::string allowed = "a fixed timestep > 0 [s], or \"auto\"";
    if (auto str = n->as_string()) {
      if (str->get() != "auto") fail("simulation.timestep_s", *n, allowed);
      w.timestep_s = 0;
    } else {
      w.timestep_s = as_number(*n, "simulation.timestep_s", allowed);
      if (!(w.timestep_s > 0)) fail("simulation.timestep_s", *n, allowed);
    }
  }
  w.timestep_safety_factor = number(
      *t, p, "timestep_safety_factor", w.timestep_safety_factor,
      [](double v) { return v > 0 && v <= 1; }, "must be in (0, 1] [-]");
  w.timestep_growth_limit = number(
      *t, p, "timestep_growth_limit", w.timestep_growth_limit,
      [](double v) { return v >= 0 && v <= 1; }, "must be in [0, 1] [-]");
  if (auto v = opt_integer(
          *t, p, "timestep_update_interval", [](long x) { return x >= 1 && x <= 1'000'000'000; },
          "steps between critical-timestep estimates: >= 1"))
    w.timestep_update_interval = static_cast<int>(*v);
  w.local_damping = number(*t, p, "local_damping", w.local_damping, unit_open,
                           "the local damping coefficient alpha: in [0, 1) [-]");
  w.neighbour_skin_m = number(*t, p, "neighbour_skin_m", w.neighbour_skin_m, non_negative,
                              "the Verlet skin: >= 0 [m] (0 = half the smallest radius)");
  w.max_overlap_fraction = number(*t, p, "max_overlap_fraction", w.max_overlap_fraction, positive,
                                  "the instability guard, overlap / smaller radius: > 0 [-]");
  if (auto v = opt_integer(
          *t, p, "threads", [](long x) { return x >= 0 && x <= 4096; },
          "OpenMP threads: >= 0 (0 = the OpenMP default)"))
    w.threads = static_cast<int>(*v);
  if (const toml::node* n = t->get("output_dir")) {
    s.output_dir = as_string(*n, "simulation.output_dir", "a folder path");
    if (s.output_dir.empty()) fail("simulation.output_dir", *n, "must not be empty");
  }
  s.progress_interval_s = number(*t, p, "progress_interval_s", s.progress_interval_s, non_negative,
                                 "seconds between progress lines: >= 0 [s]");
  s.checkpoint_interval_min =
      number(*t, p, "checkpoint_interval_min", s.checkpoint_interval_min, non_negative,
             "wall-clock minutes between checkpoints: >= 0 [min] (0 = not by time)");
  if (auto v = opt_integer(
          *t, p, "checkpoint_interval_steps", [](long x) { return x >= 0; },
          "steps between checkpoints: >= 0 (0 = not by steps)"))
    s.checkpoint_interval_steps = *v;
  validate(w);
  return s;
}

// The state a run starts from must not trip its own overlap guard at the first step: two
// particles (a line given twice, a packing not yet relaxed), or a particle and a wall (positions
// or radii written in mm put the particles through walls placed in m) overlapping by more than
// simulation.max_overlap_fraction of the (smaller) radius are refused here, exit 2, with the
// lines named, instead of an "unstable" exit 3 at step 1.
void check_start_overlaps(const Scenario& sc) {
  const double guard = sc.simulation.world.max_overlap_fraction;
  const auto& recs = sc.particles.records;
  check_particle_overlaps(recs, sc.particles.path, guard);
  for (const WallSpec& ws : sc.walls) {
    const Wall w = ws.make();
    for (const ParticleRecord& q : recs) {
      const WallProximity p = wall_proximity(w, q.position);
      const double overlap = q.radius - p.distance;
      if (overlap > guard * q.radius)
        throw InputError(
            fmt::format("{}:{}", sc.particles.path, q.line),
            fmt::format("a particle at ({:g}, {:g}, {:g}) m of radius {:g} m", q.position.x,
                        q.position.y, q.position.z, q.radius),
            fmt::format("{} wall \"{}\" by {:.3g} of its radius, more than the overlap guard "
                        "allows ({:g}, simulation.max_overlap_fraction). Everything is SI: "
                        "positions or radii written in mm put particles through walls placed in "
                        "m",
                        p.distance < 0 ? "it lies behind" : "it overlaps", ws.name,
                        overlap / q.radius, guard));
    }
  }
}

ParticlesSpec read_particles(const toml::node* node, const std::string& base_dir,
                             const toml::node& root) {
  const std::string p = "particles";
  if (!node)
    missing(p,
            "a [particles] table with file = \"PATH\" (x y z r per line, SI) and "
            "density_kg_m3",
            root);
  const toml::table& t = as_table(*node, p, "file, density_kg_m3, group");
  check_keys(t, p, kParticleKeys);
  ParticlesSpec s;
  const toml::node* f = t.get("file");
  if (!f)
    missing("particles.file", "the particle file: one particle per line, x y z r in metres "
                              "(relative paths are relative to the scenario file)");
  s.file = as_string(*f, "particles.file", "a file path");
  fs::path path(s.file);
  if (path.is_relative()) path = fs::path(base_dir) / path;
  s.path = path.lexically_normal().string();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    fail("particles.file", *f,
         fmt::format("file not found (looked for {}); relative paths are relative to the "
                     "scenario file's folder",
                     s.path));
  const auto density =
      opt_number(t, p, "density_kg_m3", positive, "the particle density: > 0 [kg/m^3]");
  if (!density) missing("particles.density_kg_m3", "the particle density > 0 [kg/m^3]");
  s.density_kg_m3 = *density;
  if (auto g = opt_integer(
          t, p, "group", [](long v) { return v >= INT32_MIN && v <= INT32_MAX; },
          "a 32-bit group number"))
    s.group = static_cast<int>(*g);
  try {
    s.records = read_particle_file(s.path);
  } catch (const InputError& e) {
    throw InputError(std::string("particles.file: ") + e.what());
  }
  return s;
}

WallSpec read_wall(const toml::node& node, const std::string& path,
                   const std::optional<ContactProperties>& ball_wall) {
  const toml::table& t = as_table(node, path, "a wall (see docs/scenario.md)");
  WallSpec w;
  w.name = read_name(t, path, "wall");
  const toml::node* type = t.get("type");
  if (!type) missing(path_of(path, "type"), "the wall type: " + one_of(kWallTypes));
  const std::string ty = as_choice(*type, path_of(path, "type"), kWallTypes);
  w.shape = ty == "plane" ? WallShape::plane : WallShape::rectangle;
  const Keys& own = w.shape == WallShape::plane ? kPlaneKeys : kRectangleKeys;
  const Keys& other = w.shape == WallShape::plane ? kRectangleKeys : kPlaneKeys;
  for (auto&& [k, v] : t) {
    const std::string_view key = k.str();
    if (std::find(own.begin(), own.end(), key) == own.end() &&
        std::find(other.begin(), other.end(), key) != other.end())
      fail(path_of(path, key), v,
           fmt::format("not a key of a {} wall; a {} wall takes {}", ty, ty, join(own)));
  }
  check_keys(t, path, own);
  auto required_vec = [&](std::string_view k, const char* what) {
    const auto v = opt_vec3(t, path, k, what);
    if (!v) missing(path_of(path, k), std::string(what) + " [x, y, z]");
    return *v;
  };
  if (w.shape == WallShape::plane) {
    w.point = required_vec("point_m", "a point on the plane [m]");
    w.normal = unit_vector(t, path, "normal", std::nullopt);
  } else {
    w.point = required_vec("centre_m", "the rectangle's centre [m]");
    w.normal = unit_vector(t, path, "normal", std::nullopt);
    w.u_direction = unit_vector(t, path, "u_direction", std::nullopt);
    if (norm(w.u_direction - dot(w.u_direction, w.normal) * w.normal) < 1e-9)
      fail(path_of(path, "u_direction"), *t.get("u_direction"),
           "must not be parallel to the normal (it gives the rectangle's first edge)");
    const toml::node* sz = t.get("size_m");
    const std::string key = path_of(path, "size_m");
    if (!sz) missing(key, "the edge lengths [lu, lv] > 0 [m]");
    const toml::array* a = sz->as_array();
    if (!a || a->size() != 2) fail(key, *sz, "expected [lu, lv], the edge lengths > 0 [m]");
    w.size_u_m = as_number((*a)[0], key + "[0]", "an edge length > 0 [m]");
    w.size_v_m = as_number((*a)[1], key + "[1]", "an edge length > 0 [m]");
    if (!(w.size_u_m > 0) || !(w.size_v_m > 0)) fail(key, *sz, "both edge lengths must be > 0 [m]");
  }
  w.velocity =
      opt_vec3(t, path, "velocity_m_per_s", "the prescribed velocity [m/s]").value_or(Vec3{});
  if (const toml::node* c = t.get("contact")) {
    const std::string cp = path_of(path, "contact");
    w.contact = resolve(read_contact(*c, cp), ball_wall, cp);
  } else if (ball_wall) {
    w.contact = *ball_wall;
  } else {
    missing(path_of(path, "contact"),
            "the ball-wall contact properties of this wall (a table like [contact.ball_ball]), "
            "or a default for every wall in [contact.ball_wall]");
  }
  return w;
}

// The state that stages change, followed through the stage list so that each
// stage is validated against what exists when it starts.
struct StageState {
  ContactProperties ball_ball;
  std::vector<std::string> walls; // present
  std::map<std::string, ContactProperties> wall_contact;
};

std::string known_walls(const std::vector<std::string>& walls) {
  if (walls.empty()) return "there are no walls left";
  std::string out = "known walls: ";
  for (std::size_t i = 0; i < walls.size(); ++i) out += (i ? ", " : "") + quote(walls[i]);
  return out;
}

void check_wall_name(const std::string& name, const toml::node& n, const std::string& key,
                     const std::vector<std::string>& walls) {
  if (std::find(walls.begin(), walls.end(), name) != walls.end()) return;
  Keys names(walls.begin(), walls.end());
  std::string msg = "no such wall at this stage; " + known_walls(walls);
  if (const std::string g = did_you_mean(name, names); !g.empty())
    msg = "did you mean \"" + g + "\"? " + msg;
  fail(key, n, msg);
}

StageSpec read_stage(const toml::node& node, const std::string& path, StageState& st) {
  const toml::table& t = as_table(node, path, "a stage (see docs/scenario.md)");
  check_keys(t, path, kStageKeys);
  StageSpec s;
  s.name = read_name(t, path, "stage");

  if (const toml::node* n = t.get("remove_walls")) {
    const std::string key = path_of(path, "remove_walls");
    const toml::array* a = n->as_array();
    if (!a) fail(key, *n, "expected an array of wall names [\"name\", ...]");
    for (std::size_t i = 0; i < a->size(); ++i) {
      const std::string k = fmt::format("{}[{}]", key, i);
      const std::string name = as_string((*a)[i], k, "a wall name");
      check_wall_name(name, (*a)[i], k, st.walls);
      st.walls.erase(std::find(st.walls.begin(), st.walls.end(), name));
      s.remove_walls.push_back(name);
    }
  }
  if (const toml::node* n = t.get("remove_particles")) {
    const std::string key = path_of(path, "remove_particles");
    const toml::table& r =
        as_table(*n, key, "{ region = { lo = [..], hi = [..] }, outside = false }");
    check_keys(r, key, kRemoveKeys);
    RegionSpec spec;
    const toml::node* region = r.get("region");
    if (!region) missing(path_of(key, "region"), "the box { lo = [x, y, z], hi = [x, y, z] } [m]");
    spec.box = read_box(*region, path_of(key, "region"));
    spec.outside = opt_bool(r, key, "outside").value_or(false);
    s.remove_particles = spec;
  }
  if (const toml::node* n = t.get("walls")) {
    const std::string key = path_of(path, "walls");
    const toml::table& ws =
        as_table(*n, key, "{ NAME = { velocity_m_per_s = [..], contact = {..} } }");
    for (auto&& [k, v] : ws) {
      const std::string name(k.str());
      const std::string wp = path_of(key, name);
      check_wall_name(name, v, wp, st.walls);
      const toml::table& wt = as_table(v, wp, "{ velocity_m_per_s = [..], contact = {..} }");
      check_keys(wt, wp, kStageWallKeys);
      WallChange c;
      c.name = name;
      c.velocity = opt_vec3(wt, wp, "velocity_m_per_s", "the prescribed velocity [m/s]");
      if (const toml::node* cn = wt.get("contact")) {
        const std::string cp = path_of(wp, "contact");
        c.contact_patch = read_contact(*cn, cp);
        c.contact = resolve(c.contact_patch, st.wall_contact.at(name), cp);
        st.wall_contact[name] = *c.contact;
      }
      s.walls.push_back(std::move(c));
    }
  }
  if (const toml::node* n = t.get("gravity"))
    s.gravity = read_gravity(*n, path_of(path, "gravity"));
  if (const toml::node* n = t.get("contact")) {
    const std::string key = path_of(path, "contact");
    const toml::table& c = as_table(*n, key, "{ ball_ball = { ... } }");
    check_keys(c, key, kStageContactKeys);
    if (const toml::node* bb = c.get("ball_ball")) {
      const std::string bp = path_of(key, "ball_ball");
      s.ball_ball_patch = read_contact(*bb, bp);
      s.ball_ball = resolve(s.ball_ball_patch, st.ball_ball, bp);
      st.ball_ball = *s.ball_ball;
    }
  }
  if (const toml::node* n = t.get("modify_contacts")) {
    const std::string key = path_of(path, "modify_contacts");
    const toml::table& m =
        as_table(*n, key, "{ region = { lo = [..], hi = [..] } (optional), set = { ... } }");
    check_keys(m, key, kModifyKeys);
    ModifyContactsSpec spec;
    if (const toml::node* r = m.get("region")) spec.region = read_box(*r, path_of(key, "region"));
    const toml::node* set = m.get("set");
    if (!set)
      missing(path_of(key, "set"), "the properties to change, e.g. set = { rolling_friction = 0 }");
    spec.set = read_contact(*set, path_of(key, "set"));
    if (spec.set.empty())
      fail(path_of(key, "set"), *set, "name at least one contact property to change");
    if (spec.set.normal_stiffness_N_per_m.has_value() !=
        spec.set.shear_stiffness_N_per_m.has_value())
      fail(path_of(key, "set"), *set,
           "give normal_stiffness_N_per_m and shear_stiffness_N_per_m together");
    // Each value was range-checked above; the combination is checked against
    // each contact's own properties when the stage runs.
    s.modify_contacts = spec;
  }
  s.local_damping = opt_number(t, path, "local_damping", unit_open,
                               "the local damping coefficient alpha: in [0, 1) [-]");
  s.reset_displacements = opt_bool(t, path, "reset_displacements").value_or(false);

  const auto steps = opt_integer(
      t, path, "steps", [](long v) { return v >= 0; }, "the number of steps: >= 0");
  const auto time = opt_number(t, path, "time_s", positive, "the simulated time: > 0 [s]");
  const toml::node* eq = t.get("until_equilibrium");
  const int ends = (steps ? 1 : 0) + (time ? 1 : 0) + (eq ? 1 : 0);
  const std::string how = "exactly one of steps = N, time_s = T or until_equilibrium = { ratio = "
                          "1e-4, max_steps = N, check_interval = 100 }";
  if (ends == 0) missing(path_of(path, "steps"), how);
  if (ends > 1) {
    const char* k = eq ? "until_equilibrium" : "time_s";
    fail(path_of(path, k), *t.get(k), "a stage takes " + how);
  }
  if (steps) s.end = StageEnd::steps, s.steps = *steps;
  if (time) s.end = StageEnd::time, s.time_s = *time;
  if (eq) {
    const std::string key = path_of(path, "until_equilibrium");
    const toml::table& e =
        as_table(*eq, key, "{ ratio = 1e-4, max_steps = N, check_interval = 100 }");
    check_keys(e, key, kEquilibriumKeys);
    s.end = StageEnd::equilibrium;
    s.equilibrium_ratio =
        number(e, key, "ratio", s.equilibrium_ratio, positive,
               "the target mean unbalanced force ratio: > 0 [-] (PFC mech.ratio.avg)");
    s.equilibrium_max_steps =
        opt_integer(
            e, key, "max_steps", [](long v) { return v >= 1; }, "the most steps to take: >= 1")
            .value_or(s.equilibrium_max_steps);
    s.equilibrium_check_interval = opt_integer(
                                       e, key, "check_interval", [](long v) { return v >= 1; },
                                       "steps between ratio checks: >= 1")
                                       .value_or(s.equilibrium_check_interval);
  }
  s.frames_every = opt_integer(
                       t, path, "frames_every", [](long v) { return v >= 0; },
                       "steps between ParaView frames: >= 0 (0 = no frames)")
                       .value_or(s.frames_every);
  s.measure_every = opt_integer(
                        t, path, "measure_every", [](long v) { return v >= 0; },
                        "steps between rows of measurements.csv: >= 0 (0 = at the stage end "
                        "only)")
                        .value_or(s.measure_every);
  return s;
}

Scenario parse_table(const toml::table& root, const std::string& source_name,
                     const std::string& base_dir) {
  check_keys(root, "", kTopKeys);
  Scenario sc;
  sc.source_path = source_name;
  sc.base_dir = base_dir;
  if (const toml::node* d = root.get("description"))
    sc.description = as_string(*d, "description", "a free text");

  std::string stem = source_name.empty() ? "scenario" : fs::path(source_name).stem().string();
  if (stem.empty()) stem = "scenario";
  const toml::node* sim = root.get("simulation");
  sc.simulation = read_simulation(
      sim ? &as_table(*sim, "simulation", "the [simulation] settings") : nullptr, "runs/" + stem);

  const toml::node* contact = root.get("contact");
  if (!contact)
    missing("contact.ball_ball", "a [contact.ball_ball] table with at least model and "
                                 "effective_modulus_Pa");
  const toml::table& ct = as_table(*contact, "contact", "[contact.ball_ball], [contact.ball_wall]");
  check_keys(ct, "contact", kContactSectionKeys);
  const toml::node* bb = ct.get("ball_ball");
  if (!bb)
    missing("contact.ball_ball", "a [contact.ball_ball] table with at least model and "
                                 "effective_modulus_Pa");
  sc.ball_ball = resolve(read_contact(*bb, "contact.ball_ball"), std::nullopt, "contact.ball_ball");
  if (const toml::node* bw = ct.get("ball_wall"))
    sc.ball_wall =
        resolve(read_contact(*bw, "contact.ball_wall"), std::nullopt, "contact.ball_wall");

  if (const toml::node* g = root.get("gravity")) sc.gravity = read_gravity(*g, "gravity");

  if (const toml::node* w = root.get("walls")) {
    const toml::array* a = w->as_array();
    if (!a) fail("walls", *w, "expected an array of tables: write each wall as [[walls]]");
    std::set<std::string> names;
    for (std::size_t i = 0; i < a->size(); ++i) {
      const std::string path = fmt::format("walls[{}]", i);
      sc.walls.push_back(read_wall((*a)[i], path, sc.ball_wall));
      if (!names.insert(sc.walls.back().name).second)
        fail(path + ".name", *(*a)[i].as_table()->get("name"), "wall names must be unique");
    }
  }

  const toml::node* stages = root.get("stages");
  if (!stages)
    missing("stages", "at least one [[stages]] table (name, and one of steps, time_s, "
                      "until_equilibrium)");
  const toml::array* sa = stages->as_array();
  if (!sa || sa->empty())
    fail("stages", *stages, "expected at least one stage: write each as [[stages]]");
  StageState st;
  st.ball_ball = sc.ball_ball;
  for (const WallSpec& w : sc.walls) {
    st.walls.push_back(w.name);
    st.wall_contact[w.name] = w.contact;
  }
  std::set<std::string> stage_names;
  for (std::size_t i = 0; i < sa->size(); ++i) {
    const std::string path = fmt::format("stages[{}]", i);
    sc.stages.push_back(read_stage((*sa)[i], path, st));
    if (!stage_names.insert(sc.stages.back().name).second)
      fail(path + ".name", *(*sa)[i].as_table()->get("name"), "stage names must be unique");
  }

  // Particles last: reading the file is the slow part, so the cheap checks
  // report first.
  if (!root.get("particles") && root.get("specimen"))
    missing("particles", "a [particles] table with file = \"PATH\" and density_kg_m3: `centridem "
                         "run` does not generate the [specimen] yet; generate it with `centridem "
                         "generate` and give the particle file it writes");
  sc.particles = read_particles(root.get("particles"), base_dir, root);
  if (auto w = tomlread::density_warning("particles.density_kg_m3", sc.particles.density_kg_m3);
      !w.empty())
    sc.warnings.push_back(w);
  check_start_overlaps(sc);
  return sc;
}

} // namespace

ContactPatch read_contact_patch(const toml::node& node, const std::string& path) {
  return read_contact(node, path);
}

Scenario parse_scenario(std::string_view text, const std::string& source_name,
                        const std::string& base_dir) {
  const toml::table root = tomlread::parse_document(text, source_name);
  Scenario sc = parse_table(root, source_name, base_dir);
  // [specimen] is for `centridem generate` (io/specimen_config.hpp); checked
  // here too, so that a mistake in it never passes silently.
  if (root.contains("specimen")) {
    parse_specimen(text, source_name, base_dir);
    sc.has_specimen = true;
  }
  return sc;
}

Scenario load_scenario(const std::string& path, const std::vector<std::string>& overrides) {
  const tomlread::ScenarioText t = tomlread::read_scenario_text(path, overrides);
  return parse_scenario(t.text, t.source, t.base_dir);
}

// ------------------------------------------------------------ TOML writing --

std::string inline_patch(const ContactPatch& p) {
  std::vector<std::string> kv;
  auto add = [&](const char* k, const std::optional<double>& v) {
    if (v) kv.push_back(fmt::format("{} = {}", k, num(*v)));
  };
  if (p.model) kv.push_back(fmt::format("model = {}", quote(to_string(*p.model))));
  add("effective_modulus_Pa", p.effective_modulus_Pa);
  add("stiffness_ratio", p.stiffness_ratio);
  add("normal_stiffness_N_per_m", p.normal_stiffness_N_per_m);
  add("shear_stiffness_N_per_m", p.shear_stiffness_N_per_m);
  add("friction", p.friction);
  add("rolling_friction", p.rolling_friction);
  add("attraction_force_N", p.attraction_force_N);
  add("attraction_range_m", p.attraction_range_m);
  add("dashpot_normal_ratio", p.dashpot_normal_ratio);
  add("dashpot_shear_ratio", p.dashpot_shear_ratio);
  if (p.dashpot_mode) kv.push_back(fmt::format("dashpot_mode = {}", *p.dashpot_mode));
  if (p.limits_use_net_force)
    kv.push_back(fmt::format("limits_use_net_force = {}", *p.limits_use_net_force));
  std::string out = "{ ";
  for (std::size_t i = 0; i < kv.size(); ++i) out += (i ? ", " : "") + kv[i];
  return out + " }";
}

namespace {

void write_contact_lines(std::string& out, const ContactProperties& c) {
  out += fmt::format("model = {}\n", quote(to_string(c.model)));
  if (c.stiffness_method == StiffnessMethod::deformability) {
    out += fmt::format("effective_modulus_Pa = {}\n", num(c.effective_modulus_Pa));
    out += fmt::format("stiffness_ratio = {}\n", num(c.stiffness_ratio));
  } else {
    out += fmt::format("normal_stiffness_N_per_m = {}\n", num(c.normal_stiffness_N_per_m));
    out += fmt::format("shear_stiffness_N_per_m = {}\n", num(c.shear_stiffness_N_per_m));
  }
  out += fmt::format("friction = {}\n", num(c.friction));
  out += fmt::format("rolling_friction = {}\n", num(c.rolling_friction));
  out += fmt::format("attraction_force_N = {}\n", num(c.attraction_force_N));
  out += fmt::format("attraction_range_m = {}\n", num(c.attraction_range_m));
  out += fmt::format("dashpot_normal_ratio = {}\n", num(c.dashpot_normal_ratio));
  out += fmt::format("dashpot_shear_ratio = {}\n", num(c.dashpot_shear_ratio));
  out += fmt::format("dashpot_mode = {}\n", c.dashpot_mode);
  out += fmt::format("limits_use_net_force = {}\n", c.limits_use_net_force);
}

std::string inline_gravity(const GravitySpec& g) {
  if (g.form == GravitySpec::Form::acceleration)
    return fmt::format("{{ acceleration_m_per_s2 = {} }}", vec(g.acceleration_m_per_s2));
  return fmt::format("{{ g_level = {}, size_reduction_factor = {}, direction = {} }}",
                     num(g.g_level), num(g.size_reduction_factor), vec(g.direction));
}

std::string inline_box(const Box& b) {
  return fmt::format("{{ lo = {}, hi = {} }}", vec(b.lo), vec(b.hi));
}

} // namespace

std::string resolved_toml(const Scenario& s) {
  std::string o;
  o += "# centridem scenario, resolved: every default made explicit (docs/scenario.md).\n";
  if (!s.source_path.empty()) o += "# Read from: " + s.source_path + "\n";
  if (s.has_specimen)
    o += "# The source's [specimen] table (for `centridem generate`) is not used by `run`.\n";
  o += fmt::format("description = {}\n", quote(s.description));

  const WorldSettings& w = s.simulation.world;
  o += "\n[simulation]\n";
  o += w.timestep_s > 0 ? fmt::format("timestep_s = {}\n", num(w.timestep_s))
                        : std::string("timestep_s = \"auto\"\n");
  o += fmt::format("timestep_safety_factor = {}\n", num(w.timestep_safety_factor));
  o += fmt::format("timestep_growth_limit = {}\n", num(w.timestep_growth_limit));
  o += fmt::format("timestep_update_interval = {}\n", w.timestep_update_interval);
  o += fmt::format("local_damping = {}\n", num(w.local_damping));
  o += fmt::format("neighbour_skin_m = {}  # 0 = half the smallest radius\n",
                   num(w.neighbour_skin_m));
  o += fmt::format("max_overlap_fraction = {}\n", num(w.max_overlap_fraction));
  o += fmt::format("threads = {}  # 0 = the OpenMP default\n", w.threads);
  o += fmt::format("output_dir = {}\n", quote(s.simulation.output_dir));
  o += fmt::format("progress_interval_s = {}\n", num(s.simulation.progress_interval_s));
  o += fmt::format("checkpoint_interval_min = {}  # 0 = not by time\n",
                   num(s.simulation.checkpoint_interval_min));
  o += fmt::format("checkpoint_interval_steps = {}  # 0 = not by steps\n",
                   s.simulation.checkpoint_interval_steps);

  o += "\n[particles]\n";
  std::string abs = s.particles.path;
  if (!abs.empty()) {
    std::error_code ec;
    const fs::path a = fs::absolute(abs, ec);
    if (!ec) abs = a.lexically_normal().string();
  }
  o += fmt::format("file = {}  # {} particles\n", quote(abs), s.particles.records.size());
  o += fmt::format("density_kg_m3 = {}\n", num(s.particles.density_kg_m3));
  o += fmt::format("group = {}\n", s.particles.group);

  o += "\n[contact.ball_ball]\n";
  write_contact_lines(o, s.ball_ball);
  if (s.ball_wall) {
    o += "\n[contact.ball_wall]\n";
    write_contact_lines(o, *s.ball_wall);
  }

  o += "\n[gravity]\n";
  if (s.gravity.form == GravitySpec::Form::acceleration) {
    o += fmt::format("acceleration_m_per_s2 = {}\n", vec(s.gravity.acceleration_m_per_s2));
  } else {
    o += fmt::format("g_level = {}\n", num(s.gravity.g_level));
    o += fmt::format("size_reduction_factor = {}\n", num(s.gravity.size_reduction_factor));
    o += fmt::format("direction = {}\n", vec(s.gravity.direction));
    o += fmt::format("# = acceleration {} m/s^2\n", vec(s.gravity.field().gravity_m_s2));
  }

  for (const WallSpec& wl : s.walls) {
    o += "\n[[walls]]\n";
    o += fmt::format("name = {}\n", quote(wl.name));
    if (wl.shape == WallShape::plane) {
      o += "type = \"plane\"\n";
      o += fmt::format("point_m = {}\n", vec(wl.point));
      o += fmt::format("normal = {}\n", vec(wl.normal));
    } else {
      o += "type = \"rectangle\"\n";
      o += fmt::format("centre_m = {}\n", vec(wl.point));
      o += fmt::format("normal = {}\n", vec(wl.normal));
      o += fmt::format("u_direction = {}\n", vec(wl.u_direction));
      o += fmt::format("size_m = [{}, {}]\n", num(wl.size_u_m), num(wl.size_v_m));
    }
    o += fmt::format("velocity_m_per_s = {}\n", vec(wl.velocity));
    o += "[walls.contact]\n";
    write_contact_lines(o, wl.contact);
  }

  for (const StageSpec& st : s.stages) {
    o += "\n[[stages]]\n";
    o += fmt::format("name = {}\n", quote(st.name));
    if (!st.remove_walls.empty()) {
      o += "remove_walls = [";
      for (std::size_t i = 0; i < st.remove_walls.size(); ++i)
        o += (i ? ", " : "") + quote(st.remove_walls[i]);
      o += "]\n";
    }
    if (st.remove_particles)
      o += fmt::format("remove_particles = {{ region = {}, outside = {} }}\n",
                       inline_box(st.remove_particles->box), st.remove_particles->outside);
    if (st.gravity) o += fmt::format("gravity = {}\n", inline_gravity(*st.gravity));
    if (st.modify_contacts) {
      o += "modify_contacts = { ";
      if (st.modify_contacts->region)
        o += fmt::format("region = {}, ", inline_box(*st.modify_contacts->region));
      o += fmt::format("set = {} }}\n", inline_patch(st.modify_contacts->set));
    }
    if (st.local_damping) o += fmt::format("local_damping = {}\n", num(*st.local_damping));
    o += fmt::format("reset_displacements = {}\n", st.reset_displacements);
    switch (st.end) {
    case StageEnd::steps:
      o += fmt::format("steps = {}\n", st.steps);
      break;
    case StageEnd::time:
      o += fmt::format("time_s = {}\n", num(st.time_s));
      break;
    case StageEnd::equilibrium:
      o += fmt::format(
          "until_equilibrium = {{ ratio = {}, max_steps = {}, check_interval = {} }}\n",
          num(st.equilibrium_ratio), st.equilibrium_max_steps, st.equilibrium_check_interval);
      break;
    }
    o += fmt::format("frames_every = {}\n", st.frames_every);
    o += fmt::format("measure_every = {}\n", st.measure_every);
    if (st.ball_ball) {
      o += fmt::format("[stages.contact.ball_ball]  # named here: {}\n",
                       inline_patch(st.ball_ball_patch));
      write_contact_lines(o, *st.ball_ball);
    }
    for (const WallChange& c : st.walls) {
      o += fmt::format("[stages.walls.{}]\n", c.name);
      if (c.velocity) o += fmt::format("velocity_m_per_s = {}\n", vec(*c.velocity));
      if (c.contact) {
        o += fmt::format("[stages.walls.{}.contact]  # named here: {}\n", c.name,
                         inline_patch(c.contact_patch));
        write_contact_lines(o, *c.contact);
      }
    }
  }
  return o;
}

} // namespace centridem
