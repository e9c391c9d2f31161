#include "io/specimen_config.hpp"
#include "io/toml_read.hpp"

#include "base/errors.hpp"
#include "io/csv.hpp"
#include "io/scenario.hpp" // did_you_mean (read-only use)

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <sstream>
#include <toml++/toml.h>

namespace centridem {

namespace fs = std::filesystem;

// ---------------------------------------------------------------- sieve CSV --

SieveTable parse_sieve_csv(std::string_view text, const std::string& source) {
  SieveTable t;
  t.source = source;
  int size_col = -1, pass_col = -1;
  long lineno = 0;
  bool header = false;
  auto at = [&](long line) { return fmt::format("{}:{}", source, line); };
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    const std::string_view raw = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++lineno;
    const std::string_view line = trim_blanks(raw);
    if (line.empty() || line.front() == '#') continue;
    const std::vector<std::string_view> cols = split_commas(line);
    if (!header) {
      for (std::size_t k = 0; k < cols.size(); ++k) {
        if (cols[k] == "sieve_mm" && size_col < 0)
          size_col = static_cast<int>(k);
        else if (cols[k] == "percent_passing" && pass_col < 0)
          pass_col = static_cast<int>(k);
        else
          throw InputError(at(lineno) + " header", "\"" + std::string(line) + "\"",
                           fmt::format("unexpected column \"{}\"; the header must be "
                                       "sieve_mm,percent_passing",
                                       cols[k]));
      }
      if (size_col < 0 || pass_col < 0)
        throw InputError(at(lineno) + " header", "\"" + std::string(line) + "\"",
                         fmt::format("missing column {}; the header must be "
                                     "sieve_mm,percent_passing",
                                     size_col < 0 ? "sieve_mm" : "percent_passing"));
      header = true;
      continue;
    }
    if (cols.size() != 2)
      throw InputError(
          at(lineno), "\"" + std::string(line) + "\"",
          fmt::format("expected 2 values (sieve_mm,percent_passing), found {}", cols.size()));
    double v[2];
    const char* names[2] = {"sieve_mm", "percent_passing"};
    for (int k = 0; k < 2; ++k) {
      const int c = k == 0 ? size_col : pass_col;
      const std::string_view s = cols[static_cast<std::size_t>(c)];
      const double x = parse_finite_number(s, fmt::format("{} column {}", at(lineno), names[k]));
      if (x < 0)
        throw InputError(fmt::format("{} column {}", at(lineno), names[k]), fmt::format("{:g}", x),
                         "must be >= 0");
      v[k] = x;
    }
    if (!(v[0] > 0))
      throw InputError(at(lineno) + " column sieve_mm", fmt::format("{:g}", v[0]),
                       "a sieve opening must be > 0 [mm]");
    if (v[1] > 100.0 + 1e-9)
      throw InputError(at(lineno) + " column percent_passing", fmt::format("{:g}", v[1]),
                       "must be at most 100 [%]");
    if (!t.rows.empty()) {
      const SieveRow& prev = t.rows.back();
      if (!(v[0] * 1e-3 > prev.size_m))
        throw InputError(at(lineno) + " column sieve_mm", fmt::format("{:g}", v[0]),
                         fmt::format("sieve sizes must increase down the table: must be > {:g} "
                                     "(line {})",
                                     prev.size_m * 1e3, prev.line));
      if (v[1] < prev.percent_passing)
        throw InputError(at(lineno) + " column percent_passing", fmt::format("{:g}", v[1]),
                         fmt::format("percent passing must not decrease as the sieves grow: "
                                     "must be >= {:g} (line {})",
                                     prev.percent_passing, prev.line));
    }
    t.rows.push_back({v[0] * 1e-3, v[1], lineno});
  }
  if (!header)
    throw InputError(source, "no header",
                     "a sieve table starts with the header "
                     "sieve_mm,percent_passing");
  if (t.rows.size() < 2)
    throw InputError(source, fmt::format("{} data rows", t.rows.size()),
                     "a sieve table needs at least two sieves");
  const SieveRow& last = t.rows.back();
  if (std::abs(last.percent_passing - 100.0) > 1e-4)
    throw InputError(fmt::format("{}:{} column percent_passing", source, last.line),
                     fmt::format("{:g}", last.percent_passing),
                     "the largest sieve must pass 100 % (sizes above it would be unknown)");
  t.rows.back().percent_passing = 100.0;
  return t;
}

SieveTable read_sieve_csv(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in || fs::is_directory(path))
    throw InputError("sieve table", "\"" + path + "\"", "cannot be opened for reading");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse_sieve_csv(buffer.str(), path);
}

// ------------------------------------------------------------ TOML reading --

namespace {

using Keys = tomlread::Keys;
using tomlread::as_bool;
using tomlread::as_number;
using tomlread::as_string;
using tomlread::as_vec3;
using tomlread::check_keys;
using tomlread::fail;
using tomlread::join;
using tomlread::missing;
using tomlread::show;

const Keys kSpecimenKeys = {"file",          "gradation", "cutoff_m", "porosity",
                            "density_kg_m3", "group",     "seed",     "brick",
                            "region",        "periodic",  "relax",    "max_particles"};
const Keys kGradationKeys = {"sieve_csv", "bins", "normalise"};
const Keys kBinKeys = {"d_min_m", "d_max_m", "volume_fraction"};
const Keys kBrickKeys = {"size_m", "file"};
const Keys kRegionKeys = {"lo_m", "hi_m"};
const Keys kRelaxKeys = {
    "ratio",         "max_overlap_ratio",    "max_steps",       "calm_interval",
    "local_damping", "effective_modulus_Pa", "stiffness_ratio", "contact",
    "contact_ratio", "contact_max_steps"};

const toml::table& as_table(const toml::node& n, const std::string& key, const std::string& what) {
  if (const toml::table* t = n.as_table()) return *t;
  fail(key, n, "expected a table: " + what);
}

template <class Ok>
double number(const toml::node& n, const std::string& key, Ok ok, const std::string& allowed) {
  const double v = as_number(n, key, allowed);
  if (!ok(v)) fail(key, n, allowed);
  return v;
}

template <class Ok>
void opt_number(const toml::table& t, const std::string& path, std::string_view k, double& out,
                Ok ok, const std::string& allowed) {
  if (const toml::node* n = t.get(k)) out = number(*n, path + "." + std::string(k), ok, allowed);
}

template <class Ok>
long integer(const toml::node& n, const std::string& key, Ok ok, const std::string& allowed) {
  auto i = n.as_integer();
  if (!i) fail(key, n, "expected an integer; " + allowed);
  const long v = static_cast<long>(i->get());
  if (!ok(v)) fail(key, n, allowed);
  return v;
}

template <class Ok>
void opt_integer(const toml::table& t, const std::string& path, std::string_view k, long& out,
                 Ok ok, const std::string& allowed) {
  if (const toml::node* n = t.get(k)) out = integer(*n, path + "." + std::string(k), ok, allowed);
}

// The file a key names, resolved against base_dir; must exist.
std::string resolve_file(const toml::node& n, const std::string& key, const std::string& base_dir,
                         std::string& as_written, const std::string& what) {
  as_written = as_string(n, key, what);
  if (as_written.empty()) fail(key, n, "must not be empty");
  fs::path p(as_written);
  if (p.is_relative()) p = fs::path(base_dir) / p;
  const std::string resolved = p.lexically_normal().string();
  std::error_code ec;
  if (!fs::is_regular_file(p, ec))
    fail(key, n,
         fmt::format("file not found (looked for {}); relative paths are relative to the "
                     "scenario file's folder",
                     resolved));
  return resolved;
}

auto positive = [](double v) { return v > 0; };
auto non_negative = [](double v) { return v >= 0; };

ContactProperties read_contact(const toml::table& t, const std::string& path) {
  // The keys and ranges of [contact.ball_ball] (scenario parser), complete:
  // a stiffness must be given.
  const ContactPatch patch = read_contact_patch(t, path);
  if (!patch.effective_modulus_Pa && !patch.normal_stiffness_N_per_m)
    missing(path + ".effective_modulus_Pa",
            "the effective modulus E* > 0 [Pa] (or normal_stiffness_N_per_m and "
            "shear_stiffness_N_per_m)");
  ContactProperties c = apply(patch, ContactProperties{});
  validate(c, path);
  return c;
}

RelaxSpec read_relax(const toml::node& node, const toml::table& root) {
  const std::string p = "specimen.relax";
  const toml::table& t = as_table(node, p, "{ ratio, max_steps, ... }");
  check_keys(t, p, kRelaxKeys);
  RelaxSpec r;
  opt_number(t, p, "ratio", r.ratio, positive, "mean unbalanced-force ratio to reach: > 0 [-]");
  opt_number(t, p, "max_overlap_ratio", r.max_overlap_ratio, positive,
             "largest overlap / smaller radius to reach: > 0 [-]");
  auto pos_int = [](long v) { return v > 0; };
  auto nonneg_int = [](long v) { return v >= 0; };
  opt_integer(t, p, "max_steps", r.max_steps, pos_int, "a step limit > 0");
  opt_integer(t, p, "calm_interval", r.calm_interval, nonneg_int,
              "steps between velocity zeroing (PFC calm): >= 0 (0 = never)");
  opt_number(
      t, p, "local_damping", r.local_damping, [](double v) { return v >= 0 && v < 1; },
      "Cundall local damping in [0, 1)");
  opt_number(t, p, "effective_modulus_Pa", r.effective_modulus_Pa, positive,
             "E* of the frictionless packing contacts: > 0 [Pa]");
  opt_number(t, p, "stiffness_ratio", r.stiffness_ratio, positive, "kappa* > 0 [-]");
  opt_number(t, p, "contact_ratio", r.contact_ratio, positive,
             "mean unbalanced-force ratio to reach with relax.contact: > 0 [-]");
  opt_integer(t, p, "contact_max_steps", r.contact_max_steps, pos_int, "a step limit > 0");
  if (const toml::node* n = t.get("contact")) {
    const std::string key = p + ".contact";
    if (const auto s = n->as_string()) {
      if (s->get() != "scenario")
        fail(key, *n,
             "expected \"scenario\" (the scenario's [contact.ball_ball]) or a table of contact "
             "properties { model, effective_modulus_Pa, friction, ... }");
      const toml::table* contact = root["contact"].as_table();
      const toml::node* bb = contact ? contact->get("ball_ball") : nullptr;
      if (!bb)
        fail(key, *n,
             "relax.contact = \"scenario\" needs a [contact.ball_ball] table in the "
             "scenario");
      r.contact = read_contact(as_table(*bb, "contact.ball_ball", "contact properties"),
                               "contact.ball_ball");
      r.contact_source = "scenario";
    } else {
      r.contact = read_contact(as_table(*n, key, "contact properties or \"scenario\""), key);
      r.contact_source = "table";
    }
  }
  return r;
}

} // namespace

SpecimenSpec parse_specimen(std::string_view text, const std::string& source_name,
                            const std::string& base_dir, const std::optional<Box>& default_region) {
  const toml::table root = tomlread::parse_document(text, source_name);
  SpecimenSpec s;
  s.scenario_path = source_name;
  s.base_dir = base_dir;
  const std::string p = "specimen";
  const toml::node* node = root.get(p);
  if (!node)
    missing(p,
            "a [specimen] table: a gradation, porosity, density_kg_m3, brick and region "
            "(docs/specimens.md), or file = \"PATH\" (x y z r per line, SI)",
            root);
  const toml::table& t = as_table(*node, p, "the specimen (docs/specimens.md)");
  check_keys(t, p, kSpecimenKeys);

  if (const toml::node* n = t.get("density_kg_m3")) {
    s.density_kg_m3 =
        number(*n, p + ".density_kg_m3", positive, "the particle density > 0 [kg/m^3]");
    if (auto w = tomlread::density_warning(p + ".density_kg_m3", s.density_kg_m3); !w.empty())
      s.warnings.push_back(w);
  } else
    missing(p + ".density_kg_m3", "the particle density > 0 [kg/m^3] (the paper: 2633)");
  if (const toml::node* n = t.get("group"))
    s.group = static_cast<int>(integer(
        *n, p + ".group", [](long v) { return v >= INT32_MIN && v <= INT32_MAX; },
        "a 32-bit group number"));
  if (const toml::node* n = t.get("region")) {
    const std::string k = p + ".region";
    const toml::table& rt = as_table(*n, k, "{ lo_m = [x, y, z], hi_m = [x, y, z] }");
    check_keys(rt, k, kRegionKeys);
    const toml::node* lo = rt.get("lo_m");
    const toml::node* hi = rt.get("hi_m");
    if (!lo) missing(k + ".lo_m", "the lower corner [x, y, z] of the box to fill [m]");
    if (!hi) missing(k + ".hi_m", "the upper corner [x, y, z] of the box to fill [m]");
    Box b{as_vec3(*lo, k + ".lo_m", "[m]"), as_vec3(*hi, k + ".hi_m", "[m]")};
    for (int a = 0; a < 3; ++a)
      if (!(b.hi[a] > b.lo[a]))
        fail(k + ".hi_m", *hi, fmt::format("must exceed lo_m along {} [m]", "xyz"[a]));
    s.region = b;
  } else {
    s.region = default_region;
  }

  if (const toml::node* n = t.get("file")) {
    s.source = SpecimenSpec::Source::file;
    s.file_path = resolve_file(*n, p + ".file", base_dir, s.file,
                               "a plain particle file, x y z r per line, SI");
    for (std::string_view k : {"gradation", "cutoff_m", "porosity", "seed", "brick", "periodic",
                               "relax", "max_particles"})
      if (const toml::node* other = t.get(k))
        fail(p + "." + std::string(k), *other,
             "not used with specimen.file (the particles come from the file): remove it, or "
             "remove file to distribute a specimen");
    return s;
  }

  // --- distribute -------------------------------------------------------------
  if (const toml::node* n = t.get("gradation")) {
    const std::string k = p + ".gradation";
    const toml::table& g = as_table(*n, k,
                                    "{ sieve_csv = \"PATH\" } or { bins = [{ d_min_m, d_max_m, "
                                    "volume_fraction }, ...] }");
    check_keys(g, k, kGradationKeys);
    const toml::node* csv = g.get("sieve_csv");
    const toml::node* bins = g.get("bins");
    if (csv && bins) fail(k + ".bins", *bins, "give either sieve_csv or bins, not both");
    if (!csv && !bins)
      missing(k + ".sieve_csv", "a sieve table (CSV sieve_mm,percent_passing) or bins = "
                                "[{ d_min_m, d_max_m, volume_fraction }, ...]");
    if (const toml::node* nn = g.get("normalise")) {
      s.normalise = as_bool(*nn, k + ".normalise");
      if (csv && s.normalise)
        fail(k + ".normalise", *nn, "applies to explicit bins only (a sieve table ends at 100 %)");
    }
    if (csv) {
      s.sieve_csv_path = resolve_file(*csv, k + ".sieve_csv", base_dir, s.sieve_csv,
                                      "a sieve table, CSV with header sieve_mm,percent_passing");
      s.sieve = read_sieve_csv(s.sieve_csv_path);
    } else {
      const toml::array* a = bins->as_array();
      if (!a || a->empty())
        fail(k + ".bins", *bins,
             "expected a non-empty array of tables [{ d_min_m, d_max_m, volume_fraction }, ...]");
      for (std::size_t i = 0; i < a->size(); ++i) {
        const std::string bk = fmt::format("{}.bins[{}]", k, i);
        const toml::table& bt = as_table((*a)[i], bk, "{ d_min_m, d_max_m, volume_fraction }");
        check_keys(bt, bk, kBinKeys);
        GradationBin b;
        for (std::string_view key : kBinKeys)
          if (!bt.get(key))
            missing(bk + "." + std::string(key), "each bin gives d_min_m, d_max_m [m] and "
                                                 "volume_fraction [-]");
        b.d_min_m = as_number(*bt.get("d_min_m"), bk + ".d_min_m", "a diameter [m]");
        b.d_max_m = as_number(*bt.get("d_max_m"), bk + ".d_max_m", "a diameter [m]");
        b.volume_fraction =
            as_number(*bt.get("volume_fraction"), bk + ".volume_fraction", "a share [-]");
        s.bins.push_back(b);
      }
    }
  }
  opt_number(t, p, "cutoff_m", s.cutoff_m, non_negative, "truncation diameter >= 0 [m] (0 = none)");
  if (const toml::node* n = t.get("porosity"))
    s.porosity = number(
        *n, p + ".porosity", [](double v) { return v > 0 && v < 1; },
        "target porosity ignoring overlaps, in (0, 1)");
  if (const toml::node* n = t.get("max_particles"))
    s.max_particles = number(
        *n, p + ".max_particles", [](double v) { return v >= 1; },
        "the most particles the region may hold: >= 1 (default 2e7)");
  if (const toml::node* n = t.get("seed"))
    s.seed = static_cast<std::uint64_t>(integer(
        *n, p + ".seed", [](long v) { return v >= 0; }, "an integer >= 0 (std::mt19937_64 seed)"));
  if (const toml::node* n = t.get("brick")) {
    const std::string k = p + ".brick";
    const toml::table& bt = as_table(*n, k, "{ size_m = [x, y, z] } or { file = \"PATH\" }");
    check_keys(bt, k, kBrickKeys);
    if (const toml::node* sz = bt.get("size_m")) {
      s.brick_size_m = as_vec3(*sz, k + ".size_m", "the periodic cell size [m]");
      for (int a = 0; a < 3; ++a)
        if (!(s.brick_size_m[a] > 0)) fail(k + ".size_m", *sz, "every size must be > 0 [m]");
    }
    if (const toml::node* f = bt.get("file")) {
      if (bt.get("size_m"))
        fail(k + ".size_m", *bt.get("size_m"),
             "not used with brick.file (the saved brick has its own cell size): remove one");
      s.brick_file_path = resolve_file(*f, k + ".file", base_dir, s.brick_file,
                                       "a brick saved by `centridem generate` (brick.json)");
    }
    if (!bt.get("size_m") && !bt.get("file"))
      missing(k + ".size_m", "the periodic cell size [x, y, z] in metres, or file = \"PATH\"");
  } else {
    missing(p + ".brick", "brick = { size_m = [x, y, z] }: the periodic cell that is "
                          "distributed, relaxed and copied to fill the region (each side at "
                          "least 3 x (largest diameter + skin))");
  }
  if (const toml::node* n = t.get("periodic")) {
    const toml::array* a = n->as_array();
    if (!a || a->size() != 3)
      fail(p + ".periodic", *n, "expected [x, y, z] booleans: which axes of the assembly wrap");
    for (std::size_t k = 0; k < 3; ++k)
      s.periodic[k] = as_bool((*a)[k], fmt::format("{}.periodic[{}]", p, k));
  }
  if (const toml::node* n = t.get("relax")) s.relax = read_relax(*n, root);

  const bool from_brick_file = !s.brick_file.empty();
  if (!from_brick_file) {
    if (!s.has_gradation())
      missing(p + ".gradation", "gradation = { sieve_csv = \"PATH\" } or { bins = [...] }");
    if (!t.get("porosity"))
      missing(p + ".porosity", "the target porosity ignoring overlaps, in (0, 1) (PFC `ball "
                               "distribute`; the paper's specimens: 0.52)");
  } else if (const toml::node* r = t.get("relax")) {
    fail(p + ".relax", *r, "not used with brick.file (the saved brick is already relaxed)");
  }
  if (!s.region)
    missing(p + ".region", "region = { lo_m = [x, y, z], hi_m = [x, y, z] }: the box to fill");
  return s;
}

SpecimenSpec load_specimen(const std::string& path, const std::vector<std::string>& overrides) {
  const tomlread::ScenarioText t = tomlread::read_scenario_text(path, overrides);
  return parse_specimen(t.text, t.source, t.base_dir);
}

// ------------------------------------------------------------ TOML writing --

namespace {
using tomlread::contact_inline;
using tomlread::num;
using tomlread::vec;
// Absolute, so that the resolved table reads back from any folder.
std::string abs_path(const std::string& p) {
  std::error_code ec;
  const fs::path a = fs::absolute(p, ec);
  return ec ? p : a.lexically_normal().string();
}
std::string qt(const std::string& s) {
  std::string out = "\"";
  for (char c : s) out += (c == '"' || c == '\\') ? std::string("\\") + c : std::string(1, c);
  return out + "\"";
}
} // namespace

std::string resolved_specimen_toml(const SpecimenSpec& s) {
  std::string o = "[specimen]\n";
  o += fmt::format("density_kg_m3 = {}\ngroup = {}\n", num(s.density_kg_m3), s.group);
  if (s.region)
    o += fmt::format("region = {{ lo_m = {}, hi_m = {} }}\n", vec(s.region->lo), vec(s.region->hi));
  if (s.source == SpecimenSpec::Source::file) {
    o += fmt::format("file = {}\n", qt(abs_path(s.file_path)));
    return o;
  }
  if (s.sieve) {
    o += fmt::format("gradation = {{ sieve_csv = {} }}\n", qt(abs_path(s.sieve_csv_path)));
  } else if (!s.bins.empty()) {
    o +=
        "gradation = { normalise = " + std::string(s.normalise ? "true" : "false") + ", bins = [\n";
    for (const GradationBin& b : s.bins)
      o += fmt::format("  {{ d_min_m = {}, d_max_m = {}, volume_fraction = {} }},\n",
                       num(b.d_min_m), num(b.d_max_m), num(b.volume_fraction));
    o += "] }\n";
  }
  o += fmt::format("cutoff_m = {}\n", num(s.cutoff_m));
  if (s.porosity > 0) o += fmt::format("porosity = {}\n", num(s.porosity));
  o += fmt::format("seed = {}\n", s.seed);
  // Written only when changed: the resolved text is the key of cached bricks
  // and foundations (procedures/foundation.cpp), which the default keeps.
  if (s.max_particles != SpecimenSpec{}.max_particles)
    o += fmt::format("max_particles = {}\n", num(s.max_particles));
  if (!s.brick_file.empty())
    o += fmt::format("brick = {{ file = {} }}\n", qt(abs_path(s.brick_file_path)));
  else
    o += fmt::format("brick = {{ size_m = {} }}\n", vec(s.brick_size_m));
  o += fmt::format("periodic = [{}, {}, {}]\n", s.periodic[0], s.periodic[1], s.periodic[2]);
  if (s.brick_file.empty()) {
    const RelaxSpec& r = s.relax;
    o += fmt::format("\n[specimen.relax]\nratio = {}\nmax_overlap_ratio = {}\nmax_steps = {}\n"
                     "calm_interval = {}\nlocal_damping = {}\neffective_modulus_Pa = {}\n"
                     "stiffness_ratio = {}\n",
                     num(r.ratio), num(r.max_overlap_ratio), r.max_steps, r.calm_interval,
                     num(r.local_damping), num(r.effective_modulus_Pa), num(r.stiffness_ratio));
    if (r.contact)
      o += fmt::format("contact = {}  # from: {}\ncontact_ratio = {}\ncontact_max_steps = {}\n",
                       contact_inline(*r.contact), r.contact_source, num(r.contact_ratio),
                       r.contact_max_steps);
  }
  return o;
}

} // namespace centridem
