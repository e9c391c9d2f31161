// Direct shear scenarios (`centridem shear SCENARIO.toml`, docs/shear.md):
// a [specimen] table (docs/specimens.md) whose region is the shear box, the
// ball-ball contact defaults [contact.ball_ball] (keys as in docs/scenario.md)
// and a [shear] table with the box, the normal pressures and the test's
// settings. Reading validates every key (type, range, unknown keys with a
// did-you-mean suggestion) and throws InputError naming the dotted key, the
// value and what is allowed. The result is fully resolved: every default is
// explicit.
#pragma once

#include "io/preparation_config.hpp"
#include "io/scenario.hpp"
#include "io/specimen_config.hpp"
#include "physics/contact_properties.hpp"
#include "procedures/direct_shear.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace centridem {

struct ShearScenario {
  std::string source_path; // the scenario file ("" when parsed from text)
  std::string base_dir;    // folder that relative paths are resolved against
  std::string description;
  SpecimenSpec specimen;       // [specimen]; its region is the box [0, L]x[0, W]x[0, H]
  ContactProperties ball_ball; // [contact.ball_ball], complete
  ContactPatch during_shear;   // shear.during_shear: patch over ball_ball while shearing
  PreparationSpec preparation; // [preparation]: compaction properties, shared with the slope
  DirectShearSpec test;        // every [shear] setting; normal_stress_Pa unused
  std::vector<double> normal_stresses_Pa; // one run each [Pa]
  double local_damping = 0.7;             // Cundall local damping (Table 1) [-]
  double g_level = 1.0;                   // gravity n g along -z [-]
  int threads = 1;                        // OpenMP threads per run (0 = the OpenMP default)
  double checkpoint_interval_min = 10;    // wall-clock minutes between checkpoints (0 = none) [min]

  // The spec of one run at `normal_stress_Pa` (ball_ball_during_shear set
  // when during_shear names any key, ball_ball_during_consolidation when
  // the scenario has a [preparation] table).
  DirectShearSpec run_spec(double normal_stress_Pa) const;
};

// Reads and validates a shear scenario from text; `source_name` names it in
// messages and `base_dir` resolves relative paths (the sieve CSV).
ShearScenario parse_shear_scenario(std::string_view toml_text, const std::string& source_name,
                                   const std::string& base_dir);
ShearScenario load_shear_scenario(const std::string& path,
                                  const std::vector<std::string>& overrides = {});

// The resolved scenario as TOML (every default explicit); parsing it back
// gives the same scenario.
std::string resolved_shear_toml(const ShearScenario& s);

} // namespace centridem
