// The numerical direct shear test (Tao et al. section 3.1; DESIGN.md
// "Procedures"): a box of 12 rectangular walls — 5 for the lower half
// (bottom + 4 sides), 5 for the upper half (top + 4 sides), and 2 plates at the
// shear plane that keep particles from escaping where the halves no longer
// overlap. Consolidation by a servo on the bottom wall with the upper box
// fixed; then the servo holds the normal stress while the upper box moves in
// -x at the shear rate. Coordinates: the box spans [0, L] x [0, W] x [0, H],
// shear plane at z = H/2.
#pragma once

#include "engine/world.hpp"
#include "physics/contact_properties.hpp"
#include "procedures/checkpointed_cycling.hpp"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace centridem {

struct ShearBox {
  double length_m = 0.0132; // L, along the shear direction x [m]
  double width_m = 0.0132;  // W, along y [m]
  double height_m = 0.0044; // H, specimen height at the start [m]
  // Length of the two shear-plane plates; at least the largest shear
  // displacement [m]. 0 = the largest shear displacement + 10 %.
  double plate_length_m = 0.0;
};

enum class StrainDefinition { height, length }; // shear displacement / H or / L

struct DirectShearSpec {
  ShearBox box;
  double normal_stress_Pa = 100e3;
  double shear_rate_m_per_s = 0.2e-3 / 60.0 * 1000.0; // the test's 0.2 mm/min x 1000 [m/s]
  double max_shear_displacement_m = 0.0013;           // stop at this displacement [m]
  StrainDefinition strain = StrainDefinition::height;
  ContactProperties ball_wall; // friction 0: smooth box (paper)
  // Specimen preparation (not the paper's; docs/shear.md "Preparation"): when
  // set, consolidation runs with these ball-ball properties (typically reduced
  // friction, the usual way to reach a denser packing in PFC), and at the end
  // of consolidation every existing ball-ball contact and the defaults become
  // `ball_ball`, the material under test, and the specimen settles with it
  // under the servo (same criteria) before shearing. Unset: consolidation
  // with whatever the World holds.
  std::optional<ContactProperties> ball_ball_during_consolidation;
  ContactProperties ball_ball; // the material; used only with ball_ball_during_consolidation
  std::optional<ContactProperties>
      ball_ball_during_shear;            // defaults for contacts made while shearing
  double servo_gain_factor = 0.5;        // alpha of the bottom-wall servo [-]
  double servo_max_speed_m_per_s = 0.05; // [m/s]
  double servo_integral_time_s = 0.0;    // Ti of the servo's integral term; 0: off [s]
  double consolidation_ratio = 1e-3;     // mean unbalanced-force ratio to end consolidation [-]
  double consolidation_stress_tolerance = 0.01; // and |sigma - target| / target below this [-]
  long consolidation_max_steps = 400'000;
  // An unload-reload loop after consolidation (an oedometer's elastic branch;
  // docs/shear.md "Unload-reload"): when in (0, 1), the servo lowers the
  // normal stress to this fraction of the target and raises it back, each
  // leg ending on the consolidation criteria, before shearing. 0: none [-].
  double unload_reload_fraction = 0.0;
  long record_interval_steps = 1000; // steps between curve points
};

struct ShearPoint {
  long step = 0;
  double time_s = 0;                  // since shearing began
  double shear_displacement_m = 0;    // upper box travel
  double shear_strain = 0;            // per `strain`
  double shear_stress_Pa = 0;         // x-force on the upper box / (L W)
  double normal_stress_Pa = 0;        // bottom-wall force / (L W)
  double vertical_displacement_m = 0; // specimen height change since shearing began (+ dilation)
  double porosity = 0;                // centre-based, inside the box
};

// The unload-reload loop's three states (heights between the walls, bottom-
// wall stresses) and its constrained moduli. With linear contacts the
// unloading branch is nearly elastic, so its modulus scales with the contact
// stiffness, which the consolidated height and the shear curves hardly see
// (docs/results/calibrate.md).
struct UnloadReload {
  bool done = false;
  double loaded_height_m = 0, loaded_normal_stress_Pa = 0;     // consolidated, before unloading
  double unloaded_height_m = 0, unloaded_normal_stress_Pa = 0; // at the lowered stress
  double reloaded_height_m = 0, reloaded_normal_stress_Pa = 0; // back at the target
  long steps = 0;                                              // both legs [-]
  // Unloading: (sigma_loaded - sigma_unloaded) / ((h_unloaded - h_loaded) / h_loaded) [Pa].
  double unloading_modulus_Pa() const;
  // Reloading: (sigma_reloaded - sigma_unloaded) / ((h_unloaded - h_reloaded) / h_unloaded) [Pa].
  double reloading_modulus_Pa() const;
};

struct DirectShearResult {
  double target_normal_stress_Pa = 0;
  long consolidation_steps = 0;
  double consolidated_height_m = 0;
  double consolidated_normal_stress_Pa = 0;    // bottom-wall stress when consolidation ended
  double consolidated_porosity = 0;            // centre-based, inside the box, then [-]
  double consolidated_coordination_number = 0; // (2 Nbb + Nbw) / N, then [-]
  // The contact network's affine vertical modulus then (World::affine_modulus_Pa over the box
  // between the walls): what a uniform vertical strain would meet before any grain moves [Pa]
  double consolidated_affine_modulus_Pa = 0;
  // Prepared specimens: steps to settle with the material after the packing
  // (included in consolidation_steps) [-]
  long settling_steps = 0;
  UnloadReload unload_reload; // when DirectShearSpec::unload_reload_fraction > 0
  std::vector<ShearPoint> curve;
  double peak_shear_stress_Pa = 0;
  double peak_strain = 0;
  double residual_shear_stress_Pa = 0;      // mean over the last 20 % of the displacement
  double worst_normal_stress_deviation = 0; // max |sigma - target| / target while shearing
  std::size_t particles_lost = 0;           // outside the box at the end
  double wall_seconds = 0;         // consolidation and shearing, over every resumed part [s]
  double particle_steps_per_s = 0; // while cycling
  bool resumed = false;            // continued from a checkpoint
};

using ShearProgress = std::function<void(const ShearPoint&, const DirectShearResult&)>;

// Consolidation (and the unload-reload loop's legs), at each check: steps so
// far since consolidation began, bottom-wall stress [Pa] and the mean
// unbalanced-force ratio [-].
struct ConsolidationState {
  long steps = 0;
  double normal_stress_Pa = 0;
  double unbalanced_force_ratio = 0;
};

// Adds the 12 walls around the box; returns nothing the caller needs: walls
// are named bottom, lower_x0, lower_x1, lower_y0, lower_y1, top, upper_x0,
// upper_x1, upper_y0, upper_y1, plate_lower, plate_upper.
void add_shear_box(World& world, const ShearBox& box, const ContactProperties& ball_wall,
                   double max_shear_displacement_m);

// Checkpoints of a direct shear test (see procedures/checkpointed_cycling.hpp):
// written by time or steps, at the start of shearing, and on SIGINT / SIGTERM
// (then Interrupted is thrown). A finished test removes its checkpoint.
struct DirectShearCheckpoints {
  std::string path; // checkpoint file; empty = no checkpoints
  CheckpointPolicy policy;
  std::function<void(const ConsolidationState&)> consolidation_progress; // optional
};

// Runs consolidation and shearing on `world`, which holds the specimen inside
// the box (walls added here). If `checkpoints.path` names an existing file,
// `world` must be freshly constructed instead: the World and the test's
// progress are read from the checkpoint and the test goes on from there, bit
// for bit as if it had never stopped (same thread count). Throws InputError
// for bad spec values or an unreadable checkpoint.
DirectShearResult run_direct_shear(World& world, const DirectShearSpec& spec,
                                   const ShearProgress& progress = {},
                                   const DirectShearCheckpoints& checkpoints = {});

void validate(const DirectShearSpec& spec);

// Mohr-Coulomb fit tau = c + sigma tan(phi) by least squares over points.
struct MohrCoulombFit {
  double cohesion_Pa = 0;
  double friction_angle_deg = 0;
  double r_squared = 0;
};
MohrCoulombFit fit_mohr_coulomb(const std::vector<double>& normal_stress_Pa,
                                const std::vector<double>& shear_stress_Pa);

} // namespace centridem
