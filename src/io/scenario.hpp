// Scenario files (`centridem run SCENARIO.toml`): a TOML description of a
// staged DEM run, the way a PFC user scripts a test. Reading validates every
// key (type, range, required, unknown keys with a did-you-mean suggestion) and
// throws InputError naming the full dotted key path, the value and what is
// allowed. The result is a plain, fully resolved description: every default
// is explicit, every stage's contact defaults are complete tables. The keys
// are documented in docs/scenario.md; they are public API.
#pragma once

#include "base/vec3.hpp"
#include "engine/walls.hpp"
#include "engine/world.hpp"
#include "io/particle_file.hpp"
#include "physics/body_field.hpp"
#include "physics/contact_properties.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <toml++/toml.h>
#include <vector>

namespace centridem {

// [gravity] or a stage's `gravity`: an explicit acceleration, or n g / s along
// a direction (BodyField::scaled_gravity; paper section 3.2).
struct GravitySpec {
  enum class Form { acceleration, scaled };
  Form form = Form::acceleration;
  Vec3 acceleration_m_per_s2{};       // form acceleration [m/s^2]
  double g_level = 1.0;               // form scaled: n [-]
  double size_reduction_factor = 1.0; // form scaled: s [-]
  Vec3 direction{0, 0, -1};           // form scaled: unit vector "down" [-]

  BodyField field() const;
  bool operator==(const GravitySpec&) const = default;
};

// A partial contact table: only the keys that were named are set. A stage's
// `contact.ball_ball` and `modify_contacts.set` are patches applied over the
// current properties.
struct ContactPatch {
  std::optional<ContactModel> model;
  std::optional<double> effective_modulus_Pa;
  std::optional<double> stiffness_ratio;
  std::optional<double> normal_stiffness_N_per_m;
  std::optional<double> shear_stiffness_N_per_m;
  std::optional<double> friction;
  std::optional<double> rolling_friction;
  std::optional<double> attraction_force_N;
  std::optional<double> attraction_range_m;
  std::optional<double> dashpot_normal_ratio;
  std::optional<double> dashpot_shear_ratio;
  std::optional<int> dashpot_mode;
  std::optional<bool> limits_use_net_force;

  bool empty() const { return *this == ContactPatch{}; }
  bool operator==(const ContactPatch&) const = default;
};

// Applies the named keys of `patch` over `base`. Naming effective_modulus_Pa
// or stiffness_ratio selects the deformability method, naming a stiffness in
// N/m the direct method. Does not validate (see resolve in scenario.cpp).
ContactProperties apply(const ContactPatch& patch, ContactProperties base);
// Reads a contact-properties table (the keys of [contact.ball_ball]) at `path`,
// validating every key; used by every section that takes contact properties.
ContactPatch read_contact_patch(const toml::node& node, const std::string& path);
// The keys a patch sets, as a TOML inline table (resolved scenario files).
std::string inline_patch(const ContactPatch& patch);

struct SimulationSpec {
  WorldSettings world;                 // timestep_s 0 = "auto"
  std::string output_dir;              // run folder (relative: to the working directory)
  double progress_interval_s = 10.0;   // seconds between progress lines on stderr
  double checkpoint_interval_min = 10; // wall-clock minutes between checkpoints (0 = not by time)
  long checkpoint_interval_steps = 0;  // steps between checkpoints (0 = not by steps)
};

struct ParticlesSpec {
  std::string file;         // as written in the scenario
  std::string path;         // resolved (relative to the scenario file's folder)
  double density_kg_m3 = 0; // [kg/m^3]
  int group = 0;            // group number given to every particle
  std::vector<ParticleRecord> records;
};

struct WallSpec {
  std::string name;
  WallShape shape = WallShape::plane;
  Vec3 point;                        // plane: point_m; rectangle: centre_m [m]
  Vec3 normal{0, 0, 1};              // [-]
  Vec3 u_direction{1, 0, 0};         // rectangle only [-]
  double size_u_m = 0, size_v_m = 0; // rectangle only: size_m = [lu, lv] [m]
  Vec3 velocity;                     // [m/s]
  ContactProperties contact;         // ball-wall contact defaults of this wall

  Wall make() const;
};

struct RegionSpec {
  Box box;              // lo, hi [m]
  bool outside = false; // remove_particles: select outside the box instead
};

struct WallChange {
  std::string name;
  std::optional<Vec3> velocity;             // new prescribed velocity [m/s]
  std::optional<ContactProperties> contact; // new defaults (resolved, complete)
  ContactPatch contact_patch;               // what the stage named
};

struct ModifyContactsSpec {
  std::optional<Box> region; // both particle centres inside; none = every contact
  ContactPatch set;          // applied over each selected contact's properties
};

enum class StageEnd { steps, time, equilibrium };

struct StageSpec {
  std::string name;
  // Changes applied at the start of the stage, in this order.
  std::vector<std::string> remove_walls;
  std::optional<RegionSpec> remove_particles;
  std::vector<WallChange> walls;
  std::optional<GravitySpec> gravity;
  std::optional<ContactProperties> ball_ball; // new ball-ball defaults (resolved, complete)
  ContactPatch ball_ball_patch;               // what the stage named
  std::optional<ModifyContactsSpec> modify_contacts;
  std::optional<double> local_damping;
  bool reset_displacements = false;
  // How long it cycles: exactly one of these.
  StageEnd end = StageEnd::steps;
  long steps = 0;
  double time_s = 0;
  double equilibrium_ratio = 1e-4;
  long equilibrium_max_steps = 1'000'000;
  long equilibrium_check_interval = 100;
  // Output cadence in steps (0 = none).
  long frames_every = 0;
  long measure_every = 1000;
};

struct Scenario {
  std::string source_path; // the scenario file ("" when parsed from text)
  std::string base_dir;    // folder that relative paths are resolved against
  std::string description;
  SimulationSpec simulation;
  ParticlesSpec particles;
  ContactProperties ball_ball;
  std::optional<ContactProperties> ball_wall; // [contact.ball_wall]: base for walls' contact
  std::vector<WallSpec> walls;
  GravitySpec gravity;
  std::vector<StageSpec> stages;
  bool has_specimen = false; // a [specimen] table (for `centridem generate`; not used by run)
  std::vector<std::string> warnings; // plausibility warnings (printed by the command)
};

// Reads, validates and resolves a scenario file, and reads its particle
// file. Throws InputError (TOML syntax errors as FILE:LINE:COLUMN).
Scenario load_scenario(const std::string& path, const std::vector<std::string>& overrides = {});
// The same from text; `source_name` names it in messages and `base_dir`
// resolves relative paths.
Scenario parse_scenario(std::string_view toml_text, const std::string& source_name,
                        const std::string& base_dir);

// The resolved scenario as TOML (every default explicit). Reading it back
// with parse_scenario gives the same scenario.
std::string resolved_toml(const Scenario& s);

// The key among `allowed` nearest to `key` by edit distance, or "" when none
// is close enough to be a likely typo.
std::string did_you_mean(std::string_view key, const std::vector<std::string_view>& allowed);

std::string_view to_string(StageEnd e);

} // namespace centridem
