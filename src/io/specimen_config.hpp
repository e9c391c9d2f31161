// The [specimen] table of a scenario (`centridem generate SCENARIO.toml`) and
// sieve tables (CSV). Reading validates every key (type, range, required,
// unknown keys with a did-you-mean suggestion) and throws InputError naming
// the full dotted key (or FILE:LINE for a CSV), the value and what is allowed.
// The keys are documented in docs/specimens.md; they are public API.
//
// A specimen is either
//   - distributed: a gradation (sieve table or explicit bins), a porosity,
//     a periodic brick that is distributed and relaxed (PFC `ball distribute`
//     + `calm` + cycling) and then copied side by side to fill a region; or
//   - read from a plain particle file (x y z r per line, SI).
// The procedures that make it are in procedures/specimen.hpp.
#pragma once

#include "base/vec3.hpp"
#include "engine/world.hpp"
#include "physics/contact_properties.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace centridem {

// One row of a sieve table: the sieve opening and the percentage by mass
// passing it.
struct SieveRow {
  double size_m = 0;          // sieve opening [m] (the CSV gives millimetres)
  double percent_passing = 0; // [%]
  long line = 0;              // line in the source, for messages
};

struct SieveTable {
  std::string source; // file name, for messages
  std::vector<SieveRow> rows;
};

// CSV with the header `sieve_mm,percent_passing` (columns in either order),
// '#' comment lines and blank lines allowed. Checks: both columns present and
// no other, every value a finite number >= 0, sieve sizes strictly
// increasing, percent passing never decreasing, at most 100, the largest
// sieve passing 100 %, at least two rows. Throws InputError naming FILE:LINE.
SieveTable parse_sieve_csv(std::string_view text, const std::string& source);
SieveTable read_sieve_csv(const std::string& path);

// An explicit size class: diameters [d_min_m, d_max_m] and its share of the
// solid volume. Within a bin radii are uniformly distributed (PFC's convention).
struct GradationBin {
  double d_min_m = 0;         // [m]
  double d_max_m = 0;         // [m]
  double volume_fraction = 0; // [-]
  bool operator==(const GradationBin&) const = default;
};

// specimen.relax: how a distributed brick is relaxed. Phase 1 (always):
// frictionless linear contacts (deformability method) with local damping,
// velocities and spins zeroed every `calm_interval` steps (PFC `calm`), until
// the mean unbalanced-force ratio is below `ratio` and the largest overlap is
// below `max_overlap_ratio` x the smaller radius, or (an assembly too loose to
// carry stress) the largest overlap is below 1e-6 x the smaller radius, or
// `max_steps`. Phase 2
// (when `contact` is set): every contact takes `contact` (e.g. the
// scenario's ball-ball properties), then cycles until `contact_ratio`.
struct RelaxSpec {
  double ratio = 1e-3;               // phase 1 target mean unbalanced-force ratio [-]
  double max_overlap_ratio = 0.02;   // phase 1 target largest overlap / smaller radius [-]
  long max_steps = 50'000;           // phase 1 step limit
  long calm_interval = 100;          // steps between velocity zeroing (PFC `calm`); 0 = never
  double local_damping = 0.7;        // Cundall local damping during relaxation [-]
  double effective_modulus_Pa = 1e8; // E* of the frictionless packing contacts [Pa]
  double stiffness_ratio = 1.5;      // kappa* of the packing contacts [-]
  std::optional<ContactProperties> contact; // phase 2 properties (complete)
  std::string contact_source;               // "", "scenario" or "table"
  double contact_ratio = 1e-4;              // phase 2 target ratio [-]
  long contact_max_steps = 50'000;          // phase 2 step limit
};

struct SpecimenSpec {
  enum class Source { distribute, file };
  Source source = Source::distribute;
  std::string scenario_path; // "" when parsed from text
  std::string base_dir;      // relative paths are resolved against it

  // --- gradation (distribute; optional with brick.file, for the report) ----
  std::string sieve_csv;           // as written
  std::string sieve_csv_path;      // resolved
  std::optional<SieveTable> sieve; // read from sieve_csv_path
  std::vector<GradationBin> bins;  // explicit bins as given
  bool normalise = false;          // gradation.normalise: scale explicit fractions to sum 1
  double cutoff_m = 0;             // truncation diameter (0 = none) [m]
  bool has_gradation() const { return sieve.has_value() || !bins.empty(); }
  // The generated gradation (truncated, checked) is procedures/gsd.hpp's
  // resolve_gradation(spec).

  double porosity = 0;      // target, ignoring overlaps (PFC `ball distribute`) [-]
  double density_kg_m3 = 0; // particle density [kg/m^3]
  int group = 0;            // group number of every particle
  std::uint64_t seed = 1;   // std::mt19937_64 seed
  // Refuse a region that would hold more particles than this (estimated from
  // the gradation and the porosity before anything is allocated): a region
  // given in mm instead of m asks for about 1e9 times too many.
  double max_particles = 2e7;
  std::vector<std::string> warnings; // plausibility warnings (printed by the command)
  Vec3 brick_size_m;                 // periodic cell size [m]
  std::string brick_file;            // as written: a saved brick to tile instead of generating
  std::string brick_file_path;       // resolved
  std::optional<Box> region;         // the box to fill (required for distribute) [m]
  std::array<bool, 3> periodic{false, false, false}; // assembly periodic along x, y, z
  RelaxSpec relax;

  // --- plain particle file --------------------------------------------------
  std::string file;      // as written
  std::string file_path; // resolved
};

// Reads [specimen] (and, when specimen.relax.contact = "scenario", the
// [contact.ball_ball] table) from a scenario's TOML text. Other top-level
// tables are left to the scenario parser. Reads the sieve CSV (relative to
// base_dir). Throws InputError.
// `default_region` fills a missing specimen.region (the slope's box).
SpecimenSpec parse_specimen(std::string_view toml_text, const std::string& source_name,
                            const std::string& base_dir,
                            const std::optional<Box>& default_region = std::nullopt);
// `overrides`: `KEY = VALUE` lines merged over the file (tomlread::apply_overrides).
SpecimenSpec load_specimen(const std::string& scenario_path,
                           const std::vector<std::string>& overrides = {});

// The specimen as TOML (every default explicit), for the run folder.
std::string resolved_specimen_toml(const SpecimenSpec& s);

} // namespace centridem
