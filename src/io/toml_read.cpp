#include "io/toml_read.hpp"

#include "base/errors.hpp"
#include "io/scenario.hpp" // did_you_mean

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sstream>

namespace centridem::tomlread {

std::string quote(std::string_view s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
    case '"':
      out += "\\\"";
      break;
    case '\\':
      out += "\\\\";
      break;
    case '\n':
      out += "\\n";
      break;
    case '\t':
      out += "\\t";
      break;
    case '\r':
      out += "\\r";
      break;
    default:
      if (static_cast<unsigned char>(c) < 0x20)
        out += fmt::format("\\u{:04X}", static_cast<unsigned>(c));
      else
        out += c;
    }
  }
  return out + "\"";
}

std::string join(const Keys& keys) {
  std::string out;
  for (std::string_view k : keys) out += (out.empty() ? "" : ", ") + std::string(k);
  return out;
}

std::string show(const toml::node& n) {
  switch (n.type()) {
  case toml::node_type::string:
    return quote(n.as_string()->get());
  case toml::node_type::integer:
    return fmt::format("{}", n.as_integer()->get());
  case toml::node_type::floating_point:
    return fmt::format("{}", n.as_floating_point()->get());
  case toml::node_type::boolean:
    return n.as_boolean()->get() ? "true" : "false";
  case toml::node_type::array: {
    const toml::array& a = *n.as_array();
    std::string out = "[";
    for (std::size_t i = 0; i < a.size() && i < 8; ++i) out += (i ? ", " : "") + show(a[i]);
    return out + (a.size() > 8 ? ", ...]" : "]");
  }
  case toml::node_type::table: {
    std::string out = "{";
    for (auto&& [k, v] : *n.as_table())
      out += (out.size() > 1 ? ", " : " ") + std::string(k.str()) + " = " + show(v);
    return out + " }";
  }
  default:
    return "(a date/time)";
  }
}

std::string where(const toml::node& n) {
  const toml::source_region& s = n.source();
  if (s.begin.line == 0) return "";
  return fmt::format(" (at {}:{}:{})", s.path ? *s.path : std::string("<scenario>"), s.begin.line,
                     s.begin.column);
}

void fail(const std::string& key, const toml::node& n, const std::string& allowed) {
  throw InputError(key, show(n), allowed + where(n));
}

void missing(const std::string& key, const std::string& allowed) {
  throw InputError(key, "(missing)", "required: " + allowed);
}

void missing(const std::string& key, const std::string& allowed, const toml::node& within) {
  const auto& path = within.source().path;
  throw InputError(key, "(missing)",
                   "required: " + allowed + (path ? " (in " + *path + ")" : std::string()));
}

double as_number(const toml::node& n, const std::string& key, const std::string& allowed) {
  double v = 0;
  if (auto i = n.as_integer())
    v = static_cast<double>(i->get());
  else if (auto f = n.as_floating_point())
    v = f->get();
  else
    fail(key, n, "expected a number; " + allowed);
  if (!std::isfinite(v)) fail(key, n, "must be finite; " + allowed);
  return v;
}

bool as_bool(const toml::node& n, const std::string& key) {
  if (auto b = n.as_boolean()) return b->get();
  fail(key, n, "expected true or false");
}

std::string as_string(const toml::node& n, const std::string& key, const std::string& allowed) {
  if (auto s = n.as_string()) return s->get();
  fail(key, n, "expected a string; " + allowed);
}

Vec3 as_vec3(const toml::node& n, const std::string& key, const std::string& allowed) {
  const toml::array* a = n.as_array();
  if (!a || a->size() != 3) fail(key, n, "expected an array of 3 numbers [x, y, z]; " + allowed);
  Vec3 v;
  for (int c = 0; c < 3; ++c)
    v[c] = as_number((*a)[static_cast<std::size_t>(c)], fmt::format("{}[{}]", key, c), allowed);
  return v;
}

long as_integer(const toml::node& n, const std::string& key, const std::string& allowed) {
  if (auto i = n.as_integer()) return static_cast<long>(i->get());
  if (auto f = n.as_floating_point()) { // 1e5 is a float in TOML; accept whole numbers
    const double v = f->get();
    if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 9e15) return static_cast<long>(v);
  }
  fail(key, n, "expected a whole number; " + allowed);
}

const toml::table& as_table(const toml::node& n, const std::string& key, const std::string& what) {
  if (const toml::table* t = n.as_table()) return *t;
  fail(key, n, "expected a table: " + what);
}

std::string path_of(const std::string& table, std::string_view key) {
  return table.empty() ? std::string(key) : table + "." + std::string(key);
}

void check_keys(const toml::table& t, const std::string& path, const Keys& allowed,
                const std::function<std::string(std::string_view)>& hint) {
  for (auto&& [k, v] : t) {
    const std::string_view key = k.str();
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string msg = "unknown key";
    if (!path.empty()) msg += " in " + path;
    const std::string guess = did_you_mean(key, allowed);
    if (!guess.empty())
      msg += " (did you mean \"" + guess + "\"?)";
    else if (hint)
      msg += hint(key);
    msg += "; allowed keys: " + join(allowed);
    fail(path.empty() ? std::string(key) : path + "." + std::string(key), v, msg);
  }
}

std::string num(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::string s = fmt::format("{}", v);
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

std::string vec(const Vec3& v) {
  return fmt::format("[{}, {}, {}]", num(v.x), num(v.y), num(v.z));
}

std::string contact_inline(const ContactProperties& c) {
  std::string o = fmt::format("{{ model = \"{}\"", to_string(c.model));
  if (c.stiffness_method == StiffnessMethod::direct)
    o += fmt::format(", normal_stiffness_N_per_m = {}, shear_stiffness_N_per_m = {}",
                     num(c.normal_stiffness_N_per_m), num(c.shear_stiffness_N_per_m));
  else
    o += fmt::format(", effective_modulus_Pa = {}, stiffness_ratio = {}",
                     num(c.effective_modulus_Pa), num(c.stiffness_ratio));
  o += fmt::format(", friction = {}, rolling_friction = {}, attraction_force_N = {}, "
                   "attraction_range_m = {}, dashpot_normal_ratio = {}, dashpot_shear_ratio = {}, "
                   "dashpot_mode = {}, limits_use_net_force = {} }}",
                   num(c.friction), num(c.rolling_friction), num(c.attraction_force_N),
                   num(c.attraction_range_m), num(c.dashpot_normal_ratio),
                   num(c.dashpot_shear_ratio), c.dashpot_mode, c.limits_use_net_force);
  return o;
}

namespace {
void merge_into(toml::table& into, const toml::table& from) {
  for (const auto& [k, v] : from) {
    toml::node* here = into.get(k.str());
    const toml::table* sub = v.as_table();
    // A table written with dotted keys or [headers] merges; an inline table
    // given on the command line replaces the value, as any other value does.
    if (here && here->is_table() && sub && !sub->is_inline())
      merge_into(*here->as_table(), *sub);
    else
      into.insert_or_assign(k.str(), v);
  }
}
} // namespace

toml::table parse_document(std::string_view text, const std::string& source_name) {
  try {
    return toml::parse(text, source_name.empty() ? std::string_view("<scenario>")
                                                 : std::string_view(source_name));
  } catch (const toml::parse_error& e) {
    const toml::source_region& s = e.source();
    throw InputError(fmt::format("{}:{}:{}: TOML syntax error: {}", s.path ? *s.path : source_name,
                                 s.begin.line, s.begin.column, e.description()));
  }
}

std::string apply_overrides(std::string_view toml_text, const std::string& source_name,
                            const std::vector<std::string>& overrides) {
  if (overrides.empty()) return std::string(toml_text);
  toml::table root = parse_document(toml_text, source_name);
  for (const std::string& o : overrides) {
    toml::table t;
    try {
      t = toml::parse(std::string_view(o), std::string_view("--set"));
    } catch (const toml::parse_error& e) {
      throw InputError("--set", quote(o),
                       fmt::format("KEY = VALUE in TOML syntax, e.g. trial.max_time_s = 0.2 or "
                                   "trial.after_cut = {{ rolling_friction = 0 }} ({})",
                                   e.description()));
    }
    if (t.empty())
      throw InputError("--set", quote(o),
                       "KEY = VALUE in TOML syntax, e.g. trial.max_time_s = 0.2");
    merge_into(root, t);
  }
  std::ostringstream out;
  out << toml::toml_formatter{root};
  return out.str();
}

std::string density_warning(const std::string& key, double density_kg_m3) {
  if (density_kg_m3 >= 500 && density_kg_m3 <= 25000) return {};
  return fmt::format("{} = {:g} kg/m^3 is outside 500-25000 kg/m^3, where grains are (sand "
                     "2650, steel 7850): {}Everything is SI (kg/m^3); ignore this for density "
                     "scaling on purpose",
                     key, density_kg_m3, density_kg_m3 < 500 ? "in g/cm^3? " : "");
}

ScenarioText read_scenario_text(const std::string& path,
                                const std::vector<std::string>& overrides) {
  std::ifstream in(path, std::ios::binary);
  if (!in || std::filesystem::is_directory(path))
    throw InputError("scenario file", quote(path), "cannot be opened for reading");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::filesystem::path base = std::filesystem::path(path).parent_path();
  if (base.empty()) base = ".";
  return {apply_overrides(buffer.str(), path, overrides),
          overrides.empty() ? path : path + " (with --set)", base.string()};
}

} // namespace centridem::tomlread
