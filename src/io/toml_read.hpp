// Reading TOML tables with checked keys and typed values: the helpers every
// scenario section uses (the scenario itself, [specimen], [shear]). Every
// failure is an InputError naming the full dotted key, the value as written,
// what is allowed, and FILE:LINE:COLUMN.
#pragma once

#include "base/vec3.hpp"
#include "physics/contact_properties.hpp"

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <toml++/toml.h>
#include <vector>

namespace centridem::tomlread {

using Keys = std::vector<std::string_view>;

std::string quote(std::string_view s);  // "..." with escapes
std::string join(const Keys& keys);     // a, b, c
std::string show(const toml::node& n);  // a value as written
std::string where(const toml::node& n); // " (at FILE:LINE:COLUMN)" or ""
[[noreturn]] void fail(const std::string& key, const toml::node& n, const std::string& allowed);
[[noreturn]] void missing(const std::string& key, const std::string& allowed);
// The same for a key missing from `within` (the document, a table): the
// message names the file, " (in FILE)", as a missing key has no line.
[[noreturn]] void missing(const std::string& key, const std::string& allowed,
                          const toml::node& within);
// Rejects keys of t not in `allowed`, suggesting the nearest allowed one;
// `hint(key)` may add advice for a key that belongs elsewhere.
void check_keys(const toml::table& t, const std::string& path, const Keys& allowed,
                const std::function<std::string(std::string_view)>& hint = {});
double as_number(const toml::node& n, const std::string& key, const std::string& allowed);
bool as_bool(const toml::node& n, const std::string& key);
std::string as_string(const toml::node& n, const std::string& key, const std::string& allowed);
Vec3 as_vec3(const toml::node& n, const std::string& key, const std::string& allowed);
// A whole number (an integer, or a float such as 1e5 with no fraction).
long as_integer(const toml::node& n, const std::string& key, const std::string& allowed);
const toml::table& as_table(const toml::node& n, const std::string& key, const std::string& what);
std::string path_of(const std::string& table, std::string_view key); // "table.key" or "key"

// A TOML document parsed, or an InputError "FILE:LINE:COLUMN: TOML syntax
// error: ..." (`source_name` names it; "" is "<scenario>").
toml::table parse_document(std::string_view text, const std::string& source_name);

// Command-line overrides (`--set KEY=VALUE`, TOML syntax, dotted keys:
// `trial.after_cut = { rolling_friction = 0 }`) merged into a scenario's text:
// tables merge key by key, any other value (an inline table too) replaces the
// one in the file. Returns the merged document as TOML text (the scenario
// reader then checks every key as usual). Throws InputError naming `--set`
// and the override for one that is not `KEY = VALUE`.
std::string apply_overrides(std::string_view toml_text, const std::string& source_name,
                            const std::vector<std::string>& overrides);

// A warning for a particle density outside where grains are (500 to 25,000
// kg/m^3: ice 917, sand 2650, steel 7850, tungsten 19300), e.g. 2.633 written
// in g/cm^3; "" when plausible. Not an error: density scaling is a deliberate
// technique in quasi-static DEM.
std::string density_warning(const std::string& key, double density_kg_m3);

// A scenario file ready for its parser: the text with the overrides merged,
// the name for messages ("PATH", or "PATH (with --set)") and the folder that
// relative paths in it start from. Throws InputError naming the file when it
// cannot be read.
struct ScenarioText {
  std::string text;
  std::string source;
  std::string base_dir;
};
ScenarioText read_scenario_text(const std::string& path, const std::vector<std::string>& overrides);

// t[k] when present, checked with ok(value); the key in messages is path.k.
template <class Ok>
std::optional<double> opt_number(const toml::table& t, const std::string& path, std::string_view k,
                                 Ok ok, const std::string& allowed) {
  const toml::node* n = t.get(k);
  if (!n) return std::nullopt;
  const std::string key = path_of(path, k);
  const double v = as_number(*n, key, allowed);
  if (!ok(v)) fail(key, *n, allowed);
  return v;
}
template <class Ok>
std::optional<long> opt_integer(const toml::table& t, const std::string& path, std::string_view k,
                                Ok ok, const std::string& allowed) {
  const toml::node* n = t.get(k);
  if (!n) return std::nullopt;
  const std::string key = path_of(path, k);
  const long v = as_integer(*n, key, allowed);
  if (!ok(v)) fail(key, *n, allowed);
  return v;
}

// Writing resolved tables: a float that reads back exactly and stays a float,
// a 3-vector, and complete contact properties as an inline table.
std::string num(double v);
std::string vec(const Vec3& v);
std::string contact_inline(const ContactProperties& c);

} // namespace centridem::tomlread
