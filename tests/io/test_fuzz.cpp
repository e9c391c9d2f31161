// Fuzz-style test of the input readers (acceptance: "A fuzz-style test feeds 1,000 mutated
// scenario files and CSVs: no crash, no hang, every rejection names the key or line").
//
// The seeds are the shipped examples (examples/*.toml, examples/paper, examples/specimens, the
// sieve table and the particle file in examples/data). Each case applies 1 to 3 random mutations
// that are meaningful for TOML or CSV (a line deleted, duplicated or swapped; a number replaced
// by a negative, zero, huge, nan, inf, -0, a string, an integer for a float; a key or a table
// header misspelt; an unknown key added; a byte inserted (quote, bracket, '=', '#', newline,
// 0xff); the file truncated; for CSVs a column dropped or added, the header renamed, a cell that
// is not a number, sizes that decrease) and feeds the text to the reader. The random numbers come
// from a std::mt19937_64 with a fixed seed, used through `rng() % n` only, so that every standard
// library runs the same cases.
//
// Each case must end in success (a mutation may be harmless) or in an InputError whose message
// says where the problem is:
//   - TOML readers: the message names `SOURCE:LINE` with a line of the mutated text (syntax
//     errors and every value the reader rejects carry "(at SOURCE:LINE:COLUMN)"), or
//     `FILE:LINE` with a line of a file the scenario refers to (the sieve table), or it starts
//     with the dotted key it rejects ("stages[1].contact.ball_ball.friction = ..."), every name
//     of which is a key of the readers (docs/scenario.md, specimens.md, shear.md) or a key
//     written in the mutated text;
//   - CSV and particle files: the message names `FILE:LINE` with a line of the file, or, for a
//     problem of the whole file (no header, fewer than two sieves, no particles), starts with the
//     file's name: "fuzz_hiroshima_sand_gsd.csv = 1 data rows: ...".
// Any other exception (a std::exception that is not an InputError, toml::parse_error escaping, a
// non-standard exception) fails the test with the mutated text; a crash ends the test binary.
#include "base/errors.hpp"
#include "io/particle_file.hpp"
#include "io/scenario.hpp"
#include "io/specimen_config.hpp"
#include "procedures/shear_config.hpp"
#include "procedures/slope_config.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <unistd.h>
#include <vector>

using namespace centridem;

namespace {

namespace fs = std::filesystem;

const fs::path kExamples = fs::path(CENTRIDEM_SOURCE_DIR) / "examples";

// Cases per reader: 3,800 in all (well under a second in a Release build).
constexpr int kScenarioCases = 800;
constexpr int kShearCases = 800;
constexpr int kSpecimenCases = 500;
constexpr int kSieveCases = 500;
constexpr int kParticleCases = 400;
constexpr int kSlopeCases = 800;
static_assert(kScenarioCases + kShearCases + kSpecimenCases + kSieveCases + kParticleCases +
                      kSlopeCases >=
                  1000,
              "the acceptance asks for 1,000 mutated files");

// No-hang guard: a case that takes longer than this is reported as a hang. The readers take
// well under a millisecond per case; this bounds runaway loops, it is not a speed assertion.
constexpr double kHangSeconds = 2.0;

// Failures printed in full per test (the count covers all of them).
constexpr int kMaxReported = 8;

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

long line_count(std::string_view text) {
  return static_cast<long>(std::count(text.begin(), text.end(), '\n')) + 1;
}

bool is_name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
}

// Every key of the TOML readers (scenario.cpp, specimen_config.cpp, shear_config.cpp): the public
// keys of docs/scenario.md, docs/specimens.md and docs/shear.md.
const std::set<std::string>& known_keys() {
  static const std::set<std::string> keys = {
      // scenario: top level, [simulation], [particles], [contact.*], [gravity], [[walls]]
      "description", "simulation", "particles", "contact", "walls", "gravity", "stages", "specimen",
      "timestep_s", "timestep_safety_factor", "timestep_growth_limit", "timestep_update_interval",
      "local_damping", "neighbour_skin_m", "max_overlap_fraction", "threads", "output_dir",
      "progress_interval_s", "file", "density_kg_m3", "group", "ball_ball", "ball_wall", "model",
      "effective_modulus_Pa", "stiffness_ratio", "normal_stiffness_N_per_m",
      "shear_stiffness_N_per_m", "friction", "rolling_friction", "attraction_force_N",
      "attraction_range_m", "dashpot_normal_ratio", "dashpot_shear_ratio", "dashpot_mode",
      "limits_use_net_force", "acceleration_m_per_s2", "g_level", "size_reduction_factor",
      "direction", "name", "type", "point_m", "normal", "velocity_m_per_s", "centre_m",
      "u_direction", "size_m",
      // [[stages]]
      "modify_contacts", "remove_walls", "remove_particles", "reset_displacements", "steps",
      "time_s", "until_equilibrium", "frames_every", "measure_every", "ratio", "max_steps",
      "check_interval", "region", "set", "outside", "lo", "hi",
      // [specimen]
      "gradation", "cutoff_m", "porosity", "seed", "brick", "periodic", "relax", "sieve_csv",
      "bins", "normalise", "d_min_m", "d_max_m", "volume_fraction", "lo_m", "hi_m",
      "max_overlap_ratio", "calm_interval", "contact_ratio", "contact_max_steps",
      // [shear]
      "shear", "box", "normal_stresses_Pa", "shear_rate_m_per_s", "max_shear_displacement_m",
      "strain", "during_shear", "servo_gain_factor", "servo_max_speed_m_per_s",
      "consolidation_ratio", "consolidation_stress_tolerance", "consolidation_max_steps",
      "record_interval_steps", "length_m", "width_m", "height_m", "plate_length_m",
      // slope scenario (docs/slope.md): [slope], [field], [moisture], [trial], [failure],
      // [campaign], [output]
      "slope", "field", "moisture", "trial", "failure", "campaign", "output", "total_height_m",
      "foundation_height_m", "benches", "breadth_m", "crest_to_wall_m", "attraction_divided_by_s",
      "face_angle_deg", "chamber", "end_wall", "end", "kind", "base_radius_m", "reference_radius_m",
      "axis", "coriolis", "top_factor", "bottom_factor", "bands", "equilibrium_ratio", "reference",
      "profile", "adhesion", "reference_water_content_percent", "table", "new_contacts",
      "foundation_max_steps", "check_interval_steps", "max_time_s", "min_time_s",
      "after_failure_time_s", "after_cut", "checkpoint_interval_min", "checkpoint_interval_steps",
      "displacement_threshold_d50", "displacement_threshold_m", "link_distance_factor",
      "min_particles", "min_volume_fraction", "moving_speed_factor", "moving_speed_m_s",
      "consecutive_checks", "failure_displacement_d50", "growth_tolerance", "slip_surface_bin_d50",
      "start_share", "bench_share", "g_levels", "search", "schedule", "jobs", "stable_g",
      "failed_g", "tolerance_g", "step_g", "max_g", "max_slides", "colour_range_m",
      "frame_interval_steps", "vtk", "picture_width_px",
      // [preparation] (shear and slope), [limit_equilibrium], [trial] rest_kinetic_ratio
      "preparation", "during_compaction", "compaction_g_level", "compaction_stress_Pa", "overfill",
      "limit_equilibrium", "cohesion_Pa", "friction_angle_deg", "bulk_density_kg_m3", "source",
      "rest_kinetic_ratio", "max_particles"};
  return keys;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string unquote(std::string_view s) {
  s = trim(s);
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front())
    s = s.substr(1, s.size() - 2);
  return std::string(s);
}

// The keys written in a TOML text: the names of [table] / [[array]] headers, the names on the
// left of '=' (dotted keys split) and the names followed by '=' inside inline tables.
std::set<std::string> keys_in(std::string_view text) {
  std::set<std::string> out;
  auto add_dotted = [&](std::string_view s) {
    std::size_t b = 0;
    for (;;) {
      const std::size_t d = s.find('.', b);
      const std::string k = unquote(s.substr(b, d == std::string_view::npos ? s.npos : d - b));
      if (!k.empty()) out.insert(k);
      if (d == std::string_view::npos) break;
      b = d + 1;
    }
  };
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t nl = text.find('\n', pos);
    const std::string_view line =
        trim(text.substr(pos, nl == std::string_view::npos ? text.npos : nl - pos));
    pos = nl == std::string_view::npos ? text.size() + 1 : nl + 1;
    if (!line.empty() && line.front() == '[') {
      std::string_view h = line;
      while (!h.empty() && h.front() == '[') h.remove_prefix(1);
      h = h.substr(0, h.find(']'));
      add_dotted(h);
      continue;
    }
    if (const std::size_t eq = line.find('='); eq != std::string_view::npos)
      add_dotted(line.substr(0, eq));
    for (std::size_t i = 0; i < line.size();) {
      if (!is_name_char(line[i])) {
        ++i;
        continue;
      }
      const std::size_t b = i;
      while (i < line.size() && is_name_char(line[i])) ++i;
      std::size_t j = i;
      while (j < line.size() && (line[j] == ' ' || line[j] == '\t')) ++j;
      if (j < line.size() && line[j] == '=' && (j + 1 >= line.size() || line[j + 1] != '='))
        out.insert(std::string(line.substr(b, i - b)));
    }
  }
  return out;
}

// The names of the dotted key a message starts with, indices dropped:
// "stages[1].contact.ball_ball.friction = 0.5: ..." gives {stages, contact, ball_ball,
// friction}. Empty when the message does not start with a key followed by " = " or ": ".
std::vector<std::string> leading_key(std::string_view msg) {
  std::vector<std::string> names;
  std::size_t i = 0;
  for (;;) {
    const std::size_t b = i;
    while (i < msg.size() && is_name_char(msg[i])) ++i;
    if (i == b) return {};
    names.emplace_back(msg.substr(b, i - b));
    while (i < msg.size() && msg[i] == '[') {
      std::size_t d = i + 1;
      while (d < msg.size() && std::isdigit(static_cast<unsigned char>(msg[d]))) ++d;
      if (d == i + 1 || d >= msg.size() || msg[d] != ']') return {};
      i = d + 1;
    }
    if (i < msg.size() && msg[i] == '.') {
      ++i;
      continue;
    }
    break;
  }
  const std::string_view rest = msg.substr(i);
  if (rest.starts_with(" = ") || rest.starts_with(": ")) return names;
  return {};
}

// True when `msg` names line N of `file` as "FILE:N" with 1 <= N <= lines.
bool names_line_of(std::string_view msg, std::string_view file, long lines) {
  if (file.empty()) return false;
  for (std::size_t at = msg.find(file); at != std::string_view::npos; at = msg.find(file, at + 1)) {
    std::size_t p = at + file.size();
    if (p >= msg.size() || msg[p] != ':') continue;
    ++p;
    long n = 0;
    std::size_t d = p;
    while (d < msg.size() && d - p < 9 && std::isdigit(static_cast<unsigned char>(msg[d])))
      n = n * 10 + (msg[d++] - '0');
    if (d > p && n >= 1 && n <= lines) return true;
  }
  return false;
}

// The files a scenario may refer to (examples/data), with their line counts, as the readers
// print their paths (lexically normal).
const std::map<std::string, long>& referenced_files() {
  static const std::map<std::string, long> files = [] {
    std::map<std::string, long> m;
    for (const auto& e : fs::directory_iterator(kExamples / "data"))
      if (e.is_regular_file())
        m[e.path().lexically_normal().string()] = line_count(read_text(e.path()));
    return m;
  }();
  return files;
}

// ------------------------------------------------------------------ mutations --

enum class Format { toml, sieve_csv, particles };

class Mutator {
public:
  Mutator(std::mt19937_64& rng, Format format) : rng_(rng), format_(format) {}

  // 1 to 3 mutations of `text`; `log` gets one line per mutation.
  std::string mutate(std::string text, std::string& log) {
    const std::size_t n = 1 + pick(3);
    for (std::size_t i = 0; i < n; ++i) text = once(std::move(text), log);
    return text;
  }

private:
  std::mt19937_64& rng_;
  Format format_;

  std::size_t pick(std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(rng_() % n); }
  template <class T> const T& pick_of(const std::vector<T>& v) { return v[pick(v.size())]; }

  static std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> out;
    std::size_t b = 0;
    for (;;) {
      const std::size_t nl = text.find('\n', b);
      out.push_back(text.substr(b, nl == std::string::npos ? std::string::npos : nl - b));
      if (nl == std::string::npos) break;
      b = nl + 1;
    }
    return out;
  }
  static std::string join(const std::vector<std::string>& lines) {
    std::string out;
    for (std::size_t i = 0; i < lines.size(); ++i) out += (i ? "\n" : "") + lines[i];
    return out;
  }

  // The spans [begin, end) of the numbers in `text`: digits with an optional sign, '.', and
  // exponent, not part of a name ("x1", "column_2k").
  static std::vector<std::pair<std::size_t, std::size_t>> numbers_in(const std::string& text) {
    std::vector<std::pair<std::size_t, std::size_t>> out;
    auto digit = [&](std::size_t i) {
      return i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]));
    };
    for (std::size_t i = 0; i < text.size();) {
      const bool starts =
          digit(i) ||
          ((text[i] == '-' || text[i] == '+' || text[i] == '.') &&
           (digit(i + 1) || (i + 1 < text.size() && text[i + 1] == '.' && digit(i + 2))));
      if (!starts || (i > 0 && (is_name_char(text[i - 1]) || text[i - 1] == '.'))) {
        ++i;
        continue;
      }
      std::size_t e = i + 1;
      while (e < text.size() &&
             (digit(e) || text[e] == '.' || text[e] == 'e' || text[e] == 'E' ||
              ((text[e] == '-' || text[e] == '+') && (text[e - 1] == 'e' || text[e - 1] == 'E'))))
        ++e;
      if (e < text.size() &&
          (std::isalpha(static_cast<unsigned char>(text[e])) || text[e] == '_')) {
        i = e;
        continue;
      }
      out.emplace_back(i, e);
      i = e;
    }
    return out;
  }

  // The spans of the TOML key names: names followed by '=' and the names in headers.
  static std::vector<std::pair<std::size_t, std::size_t>> keys_at(const std::string& text) {
    std::vector<std::pair<std::size_t, std::size_t>> out;
    bool line_start = true, in_header = false;
    for (std::size_t i = 0; i < text.size();) {
      const char c = text[i];
      if (c == '\n') line_start = true, in_header = false;
      if (line_start && c == '[') in_header = true;
      if (c != ' ' && c != '\t' && c != '\n') line_start = false;
      if (c == ']') in_header = false;
      if (!is_name_char(c)) {
        ++i;
        continue;
      }
      const std::size_t b = i;
      while (i < text.size() && is_name_char(text[i])) ++i;
      std::size_t j = i;
      while (j < text.size() && (text[j] == ' ' || text[j] == '\t')) ++j;
      if (in_header || (j < text.size() && (text[j] == '=' || text[j] == '.')))
        out.emplace_back(b, i);
    }
    return out;
  }

  std::string typo(std::string s) {
    static const std::string letters = "abcdefghijklmnopqrstuvwxyz_ABZ019";
    switch (pick(3)) {
    case 0:
      if (s.size() > 1) s.erase(pick(s.size()), 1);
      break;
    case 1:
      s.insert(pick(s.size() + 1), 1, letters[pick(letters.size())]);
      break;
    default:
      if (s.size() > 1) {
        const std::size_t i = pick(s.size() - 1);
        std::swap(s[i], s[i + 1]);
      }
    }
    return s;
  }

  std::string replacement_number(std::string_view old) {
    static const std::vector<std::string> toml_values = {"-1",
                                                         "0",
                                                         "-0",
                                                         "-0.0",
                                                         "1e308",
                                                         "-1e308",
                                                         "1e309",
                                                         "nan",
                                                         "-nan",
                                                         "inf",
                                                         "-inf",
                                                         "\"abc\"",
                                                         "abc",
                                                         "1",
                                                         "1.0",
                                                         "0.5",
                                                         "2",
                                                         "3",
                                                         "1e-320",
                                                         "4096",
                                                         "1_000",
                                                         "0x10",
                                                         "9223372036854775807",
                                                         "-9223372036854775808",
                                                         "99999999999999999999",
                                                         "true",
                                                         "[]",
                                                         "{}",
                                                         "[1, 2]",
                                                         "1e5",
                                                         "100.0",
                                                         "0.999",
                                                         "1.5e-3"};
    static const std::vector<std::string> csv_values = {
        "-1",    "0",     "-0", "1e308", "1e309", "nan", "inf",   "-inf",   "abc",
        "\"1\"", "",      " ",  "1",     "0.5",   "100", "100.5", "1e-320", "0x10",
        "1,5",   "2.5.1", "+1", "1e",    "--1",   "50",  "0.001"};
    const auto& values = format_ == Format::toml ? toml_values : csv_values;
    switch (pick(4)) {
    case 0: // integer <-> float
      if (old.find_first_of(".eE") != std::string_view::npos)
        return std::string(old.substr(0, old.find_first_of(".eE")));
      return std::string(old) + ".0";
    case 1: // off by a factor or a sign
      return pick(2) ? "-" + std::string(old) : std::string(old) + "0";
    default:
      return pick_of(values);
    }
  }

  std::string once(std::string text, std::string& log) {
    std::vector<std::string> lines = lines_of(text);
    const std::size_t nl = lines.size();
    auto note = [&](const std::string& s) { log += "  " + s + "\n"; };
    const int kinds_toml = 10, kinds_csv = 12, kinds_particles = 10;
    const int kinds = format_ == Format::toml        ? kinds_toml
                      : format_ == Format::sieve_csv ? kinds_csv
                                                     : kinds_particles;
    switch (static_cast<int>(pick(static_cast<std::size_t>(kinds)))) {
    case 0: { // delete a line
      const std::size_t i = pick(nl);
      note("delete line " + std::to_string(i + 1));
      lines.erase(lines.begin() + static_cast<long>(i));
      return join(lines);
    }
    case 1: { // duplicate a line
      const std::size_t i = pick(nl);
      note("duplicate line " + std::to_string(i + 1));
      lines.insert(lines.begin() + static_cast<long>(i), lines[i]);
      return join(lines);
    }
    case 2: { // swap two lines
      const std::size_t i = pick(nl), j = pick(nl);
      note("swap lines " + std::to_string(i + 1) + " and " + std::to_string(j + 1));
      std::swap(lines[i], lines[j]);
      return join(lines);
    }
    case 3: { // replace a number
      const auto nums = numbers_in(text);
      if (nums.empty()) return text;
      const auto [b, e] = pick_of(nums);
      const std::string old = text.substr(b, e - b);
      const std::string now = replacement_number(old);
      note("number " + old + " -> " + now);
      return text.replace(b, e - b, now);
    }
    case 4: { // delete a character
      if (text.empty()) return text;
      const std::size_t i = pick(text.size());
      note("delete character " + std::to_string(i));
      return text.erase(i, 1);
    }
    case 5: { // insert a byte
      static const std::string special = "\"'[]{}=#\n,.\\\t \xff\x01";
      const char c = pick(3) ? special[pick(special.size())]
                             : static_cast<char>(1 + pick(255)); // any byte but NUL
      const std::size_t i = pick(text.size() + 1);
      note("insert byte " + std::to_string(static_cast<unsigned char>(c)) + " at " +
           std::to_string(i));
      return text.insert(i, 1, c);
    }
    case 6: { // truncate
      const std::size_t i = pick(text.size() + 1);
      note("truncate at " + std::to_string(i));
      text.resize(i);
      return text;
    }
    default:
      break;
    }
    if (format_ == Format::toml) return toml_only(std::move(text), std::move(lines), note);
    return table_only(std::move(text), std::move(lines), note);
  }

  template <class Note>
  std::string toml_only(std::string text, std::vector<std::string> lines, Note note) {
    switch (pick(3)) {
    case 0: { // rename a key (a typo)
      const auto keys = keys_at(text);
      if (keys.empty()) return text;
      const auto [b, e] = pick_of(keys);
      const std::string old = text.substr(b, e - b), now = typo(old);
      note("key " + old + " -> " + now);
      return text.replace(b, e - b, now);
    }
    case 1: { // change a [table] header
      std::vector<std::size_t> headers;
      for (std::size_t i = 0; i < lines.size(); ++i)
        if (trim(lines[i]).starts_with("[")) headers.push_back(i);
      if (headers.empty()) return text;
      const std::size_t i = pick_of(headers);
      static const std::vector<std::string> tables = {
          "[simulation]",    "[particles]", "[contact]",        "[contact.ball_ball]",
          "[[walls]]",       "[gravity]",   "[[stages]]",       "[contact.ball_wall]",
          "[specimen]",      "[shear]",     "[specimen.relax]", "[[contact.ball_ball]]",
          "[walls.contact]", "[stages]",    "[unknown]",        "[shear.box]"};
      std::string now;
      switch (pick(3)) {
      case 0:
        now = pick_of(tables);
        break;
      case 1: { // [x] <-> [[x]]
        const std::string h(trim(lines[i]));
        now = h.starts_with("[[") ? h.substr(1, h.size() - 2) : "[" + h + "]";
        break;
      }
      default: {
        const std::string h(trim(lines[i]));
        const std::size_t b = h.find_first_not_of('['), e = h.find(']');
        now = e == std::string::npos || b >= e
                  ? h
                  : h.substr(0, b) + typo(h.substr(b, e - b)) + h.substr(e);
      }
      }
      note("header line " + std::to_string(i + 1) + " " + lines[i] + " -> " + now);
      lines[i] = now;
      return join(lines);
    }
    default: { // add a key (unknown, or known but in another table)
      static const std::vector<std::string> extra = {"unknown_key = 1",
                                                     "frobnicate = \"abc\"",
                                                     "steps = 10",
                                                     "model = \"linear\"",
                                                     "x = [1, 2, 3]",
                                                     "description = \"again\"",
                                                     "density = 2600.0",
                                                     "effective_modulus = 1e8",
                                                     "threads = 2",
                                                     "[unknown_table]",
                                                     "file = \"nope.txt\"",
                                                     "normal = [0.0, 0.0, 0.0]",
                                                     "name = \"bad name!\"",
                                                     "g_level = -1.0",
                                                     "contact = \"scenario\"",
                                                     "ratio = 0"};
      std::string line =
          pick(3) ? pick_of(extra)
                  : *std::next(known_keys().begin(), static_cast<long>(pick(known_keys().size()))) +
                        " = 1";
      const std::size_t i = pick(lines.size() + 1);
      note("add line " + std::to_string(i + 1) + ": " + line);
      lines.insert(lines.begin() + static_cast<long>(i), line);
      return join(lines);
    }
    }
  }

  // Data lines: not blank, not a comment.
  static std::vector<std::size_t> data_lines(const std::vector<std::string>& lines) {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const std::string_view t = trim(lines[i]);
      if (!t.empty() && t.front() != '#') out.push_back(i);
    }
    return out;
  }

  static std::vector<std::string> cells(const std::string& line, char sep) {
    std::vector<std::string> out;
    std::string cur;
    std::istringstream in(line);
    if (sep == ',') {
      while (std::getline(in, cur, ',')) out.push_back(cur);
    } else {
      while (in >> cur) out.push_back(cur);
    }
    return out;
  }
  static std::string uncells(const std::vector<std::string>& c, char sep) {
    std::string out;
    for (std::size_t i = 0; i < c.size(); ++i) out += (i ? std::string(1, sep) : "") + c[i];
    return out;
  }

  template <class Note>
  std::string table_only(std::string text, std::vector<std::string> lines, Note note) {
    const char sep = format_ == Format::sieve_csv ? ',' : ' ';
    const std::vector<std::size_t> rows = data_lines(lines);
    if (rows.empty()) return text;
    const bool all = pick(4) == 0; // a whole column, or one line
    const std::size_t choices = format_ == Format::sieve_csv ? 5 : 3;
    switch (pick(choices)) {
    case 0: { // drop a column
      const std::size_t col = pick(4);
      note(std::string("drop column ") + std::to_string(col + 1) + (all ? " everywhere" : ""));
      for (std::size_t r : rows) {
        if (!all && r != pick_of(rows)) continue;
        auto c = cells(lines[r], sep);
        if (col < c.size()) c.erase(c.begin() + static_cast<long>(col));
        lines[r] = uncells(c, sep);
      }
      return join(lines);
    }
    case 1: { // add a column
      static const std::vector<std::string> extra = {"1", "0.5", "abc", "", "-2", "nan", "1e400"};
      const std::string v = pick_of(extra);
      note("add column \"" + v + "\"" + (all ? " everywhere" : ""));
      const std::size_t only = pick_of(rows);
      for (std::size_t r : rows)
        if (all || r == only) lines[r] += std::string(1, sep) + v;
      return join(lines);
    }
    case 2: { // a cell that is not a number
      static const std::vector<std::string> words = {"abc", "x",        "1.2.3", "--", "\"0.5\"",
                                                     "NaN", "Infinity", "1e",    "0,5"};
      const std::size_t r = pick_of(rows);
      auto c = cells(lines[r], sep);
      if (c.empty()) return text;
      const std::size_t k = pick(c.size());
      const std::string w = pick_of(words);
      note("line " + std::to_string(r + 1) + " cell " + std::to_string(k + 1) + " -> " + w);
      c[k] = w;
      lines[r] = uncells(c, sep);
      return join(lines);
    }
    case 3: { // rename the header (sieve table)
      const std::size_t h = rows.front();
      static const std::vector<std::string> headers = {"percent_passing,sieve_mm",
                                                       "sieve,percent_passing",
                                                       "sieve_mm,passing",
                                                       "sieve_mm,percent_passing,extra",
                                                       "sieve_mm",
                                                       "sieve_mm,sieve_mm",
                                                       "Sieve_mm,Percent_passing",
                                                       "sieve_mm;percent_passing",
                                                       "0.075,6.0"};
      std::string now = pick(2) ? pick_of(headers) : typo(lines[h]);
      note("header " + lines[h] + " -> " + now);
      lines[h] = now;
      return join(lines);
    }
    default: { // decreasing sizes: a row's sieve size below the one before
      if (rows.size() < 3) return text;
      const std::size_t r = rows[1 + pick(rows.size() - 2)];
      auto c = cells(lines[r], sep);
      if (c.empty()) return text;
      c[0] = pick(2) ? "0.01" : c[0] + "0"; // smaller than the first, or larger than the next
      note("line " + std::to_string(r + 1) + " sieve -> " + c[0]);
      lines[r] = uncells(c, sep);
      return join(lines);
    }
    }
  }
};

// ---------------------------------------------------------------- the driver --

struct Seed {
  std::string name;     // file name, for messages
  std::string text;     // contents
  std::string base_dir; // its folder (relative paths in it resolve against it)
};

Seed seed_file(const fs::path& p) {
  return {p.filename().string(), read_text(p), p.parent_path().lexically_normal().string()};
}

struct Stats {
  int cases = 0, accepted = 0, rejected = 0;
  int by_line = 0, by_key = 0, by_file = 0; // how the rejections say where
  int unnamed = 0, other_exceptions = 0, hangs = 0;
  double slowest_s = 0;
};

// What a rejection names: "line", "key", "file" (a whole-file problem), or "" (nothing).
using Classify = std::function<std::string(const std::string& msg, const std::string& text,
                                           const std::string& source)>;
// Reads `text` (from `seed`) under the name `source`; throws on rejection.
using Read =
    std::function<void(const std::string& text, const std::string& source, const Seed& seed)>;

std::string toml_where(const std::string& msg, const std::string& text, const std::string& source) {
  if (names_line_of(msg, source, line_count(text))) return "line";
  for (const auto& [file, lines] : referenced_files())
    if (names_line_of(msg, file, lines)) return "line";
  const std::vector<std::string> key = leading_key(msg);
  if (key.empty()) return "";
  const std::set<std::string> written = keys_in(text);
  for (const std::string& k : key)
    if (!known_keys().contains(k) && !written.contains(k)) return "";
  return "key";
}

Stats fuzz(const char* reader, const std::vector<Seed>& seeds, Format format, int cases,
           std::uint64_t rng_seed, const Read& read, const Classify& classify) {
  // The fuzzing starts from valid files: each seed is read unchanged first.
  for (const Seed& seed : seeds) {
    try {
      read(seed.text, seed.name, seed);
    } catch (const std::exception& e) {
      ADD_FAILURE() << reader << ": the seed " << seed.name << " is rejected: " << e.what();
    }
  }
  std::mt19937_64 rng(rng_seed);
  Mutator mutator(rng, format);
  Stats st;
  int reported = 0;
  for (int c = 0; c < cases; ++c) {
    const Seed& seed = seeds[static_cast<std::size_t>(c) % seeds.size()];
    std::string log;
    const std::string text = mutator.mutate(seed.text, log);
    const std::string source = "fuzz_" + seed.name;
    auto report = [&](const std::string& what) {
      if (++reported > kMaxReported) return;
      ADD_FAILURE() << reader << " case " << c << " (seed " << seed.name << "): " << what
                    << "\nmutations:\n"
                    << log << "mutated text:\n-----\n"
                    << text << "\n-----";
    };
    ++st.cases;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      read(text, source, seed);
      ++st.accepted;
    } catch (const InputError& e) {
      ++st.rejected;
      const std::string msg = e.what();
      const std::string where = classify(msg, text, source);
      if (where == "line")
        ++st.by_line;
      else if (where == "key")
        ++st.by_key;
      else if (where == "file")
        ++st.by_file;
      else {
        ++st.unnamed;
        report("the rejection names neither a key nor a line: " + msg);
      }
    } catch (const std::exception& e) {
      ++st.other_exceptions;
      report(std::string("an exception that is not an InputError: ") + e.what());
    } catch (...) {
      ++st.other_exceptions;
      report("a non-standard exception");
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    st.slowest_s = std::max(st.slowest_s, s);
    if (s > kHangSeconds) {
      ++st.hangs;
      report("took " + std::to_string(s) + " s (hang guard " + std::to_string(kHangSeconds) +
             " s)");
    }
  }
  std::printf("[fuzz] %-22s %4d cases: %4d accepted, %4d rejected (%d name FILE:LINE, %d the "
              "key, %d the file); %d unnamed, %d other exceptions, %d hangs; slowest case %.1f "
              "ms\n",
              reader, st.cases, st.accepted, st.rejected, st.by_line, st.by_key, st.by_file,
              st.unnamed, st.other_exceptions, st.hangs, st.slowest_s * 1e3);
  std::fflush(stdout);
  EXPECT_EQ(st.cases, cases);
  EXPECT_EQ(st.unnamed, 0) << reader << ": rejections that name neither a key nor a line";
  EXPECT_EQ(st.other_exceptions, 0) << reader << ": exceptions other than InputError";
  EXPECT_EQ(st.hangs, 0) << reader << ": cases over the hang guard";
  // Sanity: the mutations do bite, and the seeds parse.
  EXPECT_GT(st.rejected, cases / 4) << reader;
  EXPECT_GT(st.accepted, 0) << reader;
  return st;
}

// A scratch folder for the particle files.
class ScratchDir {
public:
  ScratchDir()
      : path_(fs::path(testing::TempDir()) /
              ("centridem_fuzz_" + std::to_string(static_cast<long>(::getpid())))) {
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

private:
  fs::path path_;
};

} // namespace

// ---------------------------------------------------------------------- tests --

TEST(FuzzReaders, ScenarioFiles) {
  const std::vector<Seed> seeds = {seed_file(kExamples / "demo_settle.toml"),
                                   seed_file(kExamples / "settle_column.toml")};
  fuzz(
      "parse_scenario", seeds, Format::toml, kScenarioCases, 0xC3A1'0001,
      [](const std::string& text, const std::string& source, const Seed& seed) {
        parse_scenario(text, source, seed.base_dir);
      },
      toml_where);
}

TEST(FuzzReaders, ShearScenarioFiles) {
  const std::vector<Seed> seeds = {seed_file(kExamples / "shear_small.toml"),
                                   seed_file(kExamples / "paper" / "shear_dry.toml"),
                                   seed_file(kExamples / "paper" / "shear_humid.toml")};
  fuzz(
      "parse_shear_scenario", seeds, Format::toml, kShearCases, 0xC3A1'0002,
      [](const std::string& text, const std::string& source, const Seed& seed) {
        parse_shear_scenario(text, source, seed.base_dir);
      },
      toml_where);
}

TEST(FuzzReaders, SlopeScenarioFiles) {
  const std::vector<Seed> seeds = {seed_file(kExamples / "demo_slope.toml"),
                                   seed_file(kExamples / "paper" / "slope_lower_bench.toml"),
                                   seed_file(kExamples / "paper" / "slope_higher_bench.toml")};
  fuzz(
      "parse_slope_scenario", seeds, Format::toml, kSlopeCases, 0xC3A1'0006,
      [](const std::string& text, const std::string& source, const Seed& seed) {
        parse_slope_scenario(text, source, seed.base_dir);
      },
      toml_where);
}

TEST(FuzzReaders, SpecimenTables) {
  const std::vector<Seed> seeds = {seed_file(kExamples / "specimens" / "paper_shear_box.toml"),
                                   seed_file(kExamples / "specimens" / "paper_foundation.toml")};
  fuzz(
      "parse_specimen", seeds, Format::toml, kSpecimenCases, 0xC3A1'0003,
      [](const std::string& text, const std::string& source, const Seed& seed) {
        parse_specimen(text, source, seed.base_dir);
      },
      toml_where);
}

TEST(FuzzReaders, SieveCsvFiles) {
  const std::vector<Seed> seeds = {seed_file(kExamples / "data" / "hiroshima_sand_gsd.csv")};
  fuzz(
      "parse_sieve_csv", seeds, Format::sieve_csv, kSieveCases, 0xC3A1'0004,
      [](const std::string& text, const std::string& source, const Seed&) {
        parse_sieve_csv(text, source);
      },
      [](const std::string& msg, const std::string& text, const std::string& source) {
        if (names_line_of(msg, source, line_count(text))) return std::string("line");
        // A problem of the whole table (no header, fewer than two sieves) names the file.
        if (msg.starts_with(source + " = ")) return std::string("file");
        return std::string();
      });
}

TEST(FuzzReaders, ParticleFiles) {
  // The seed: the first 40 lines of the example particle file (its comment line and 39
  // particles), so that the mutations hit a good share of its lines.
  const std::string full = read_text(kExamples / "data" / "column_2k.xyzr");
  std::size_t cut = 0;
  for (int i = 0; i < 40 && cut != std::string::npos; ++i) cut = full.find('\n', cut + 1);
  ASSERT_NE(cut, std::string::npos);
  const std::vector<Seed> seeds = {
      {"column_2k.xyzr", full.substr(0, cut + 1), (kExamples / "data").string()}};
  ScratchDir scratch;
  const std::string file = (scratch.path() / "fuzz_column_2k.xyzr").string();
  fuzz(
      "read_particle_file", seeds, Format::particles, kParticleCases, 0xC3A1'0005,
      [&](const std::string& text, const std::string&, const Seed&) {
        // A new file each case: truncating a file in place makes ext4 flush it on close
        // (auto_da_alloc), which costs milliseconds per case.
        fs::remove(file);
        std::ofstream(file, std::ios::binary) << text;
        read_particle_file(file);
      },
      [&](const std::string& msg, const std::string& text, const std::string&) {
        if (names_line_of(msg, file, line_count(text))) return std::string("line");
        // No particle in the whole file names the file.
        if (msg.starts_with("particle file = \"" + file + "\"")) return std::string("file");
        return std::string();
      });
}
