// The [preparation] table: how a specimen is made denser than the packing it
// was generated at, the same way for the shear box and the slope foundation
// (issue 16; docs/specimens.md "Preparation"). PFC practice, since the paper
// does not say how its specimens were packed:
//
//   compact  every ball-ball contact takes `during_compaction` (a patch over
//            the material: typically low friction, no rolling resistance, no
//            adhesion) while a load compacts the specimen: in the shear box
//            the servo on the bottom wall at the test's normal pressure; in
//            the slope's chamber gravity n g / s at `compaction_g_level`,
//            plus a top plate pressing at `compaction_stress_Pa` when given;
//   switch   every existing contact and the defaults become the material;
//   settle   the specimen cycles with the material under the same load until
//            the mean unbalanced-force ratio is below `ratio` (and, in the
//            chamber, the kinetic energy is small: trial.rest_kinetic_ratio).
//
// The slope's foundation is generated `overfill` times as high as the design
// so that the prepared surface stands above the crest; the excess is removed
// (centre based, as the excavation is) and the prepared foundation is cached.
#pragma once

#include "io/scenario.hpp"

#include <string>
#include <toml++/toml.h>

namespace centridem {

struct PreparationSpec {
  bool enabled = false;           // the scenario has a [preparation] table
  ContactPatch during_compaction; // `during_compaction`: patch over the material (required)
  double ratio = 1e-3;            // `ratio`: mean unbalanced-force ratio ending each phase [-]
  long max_steps = 400'000;       // `max_steps`: step limit of each phase
  // Slope foundation only:
  double compaction_g_level = 50.0; // `compaction_g_level`: gravity n g / s while preparing [-]
  double compaction_stress_Pa = 0;  // `compaction_stress_Pa`: top plate stress, 0 = none [Pa]
  double overfill = 1.3;            // `overfill`: generated height / design height [-]
  bool operator==(const PreparationSpec&) const = default;
};

// Reads root["preparation"] when present (else enabled = false), validating
// every key; `material` is the [contact.ball_ball] the patch goes over (the
// patched properties are validated too). Throws InputError naming the key.
PreparationSpec read_preparation(const toml::table& root, const ContactProperties& material);

// The resolved table ("" when not enabled), every default explicit.
std::string resolved_preparation_toml(const PreparationSpec& p);

} // namespace centridem
