// Benched slope scenarios (`centridem slope SCENARIO.toml`, docs/slope.md):
//   [specimen]           the foundation (docs/specimens.md); its region may be
//                        left out: it is then the slope's DEM box
//   [preparation]        optional: compaction, switch, settle and trim of the
//                        foundation (io/preparation_config.hpp), shared with
//                        the shear examples
//   [contact.ball_ball]  the soil's contact properties (Table 1); F0 as
//                        calibrated in the laboratory (divided by s in the
//                        slope when slope.attraction_divided_by_s)
//   [slope]              the geometry (BenchedSlope keys, model scale) and
//                        the chamber walls
//   [field]              uniform n g / s, or a true radial centrifuge field
//   [moisture]           optional: F0 graded with height (drier crest)
//   [limit_equilibrium]  optional: c and phi for Bishop's critical-g estimate
//   [trial]              one trial's stages and limits
//   [failure]            failure detection (FailureCriteria keys)
//   [campaign]           g-levels, a critical-g search or a stepped schedule
//   [output]             pictures and ParaView frames
// Reading validates every key (type, range, unknown keys with a did-you-mean
// suggestion) and throws InputError naming the dotted key, the value and what
// is allowed. The result is fully resolved: every default is explicit.
#pragma once

#include "io/preparation_config.hpp"
#include "io/scenario.hpp"
#include "io/specimen_config.hpp"
#include "physics/contact_properties.hpp"
#include "physics/moisture.hpp"
#include "procedures/failure.hpp"
#include "procedures/slope_geometry.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace centridem {

// The chamber's walls: floor, back wall and the two side walls (glass) with
// the chamber's friction; the end of the model (the middle of the chamber,
// where the mirror-image slope would be) as a frictionless symmetry wall.
struct ChamberWalls {
  ContactProperties chamber; // `slope.walls.chamber`: patch over Table 1's ball-wall, mu = 0.2
  bool end_wall = true;      // `slope.walls.end_wall`: a wall at x = length
  ContactProperties end;     // `slope.walls.end`: patch over the same, mu = 0 (symmetry)
};

enum class FieldKind { uniform, centrifuge };
// Where the g-level n is reached in the centrifuge field (`field.reference`).
enum class FieldReference {
  base,        // "base": at the model's base (the chamber floor)
  third_depth, // "third_depth": one third of the model's depth below its top, the effective
               // radius R_top + H / 3 that centrifuge practice quotes the g-level at (it
               // minimises the error of the vertical stress over the depth; Taylor,
               // Geotechnical Centrifuge Technology, 1995, ch. 2)
  radius       // `field.reference_radius_m`: a radius given [m, real scale]
};

// The body field of a trial at g-level n (physics/body_field.hpp).
struct FieldSpec {
  FieldKind kind = FieldKind::uniform; // `field.kind`: "uniform" (n g / s down) or "centrifuge"
  // centrifuge: radius of the model's base (the chamber floor) from the axis
  // [m, real scale]. The paper does not give it: 2.5 m (REFERENCE.md).
  double base_radius_m = 2.5;
  // Where the g-level is n: default one third of the depth (the paper and the
  // test do not say where theirs was measured).
  FieldReference reference = FieldReference::third_depth;
  double reference_radius_m = 0.0; // reference = radius: that radius [m, real scale]
  // Rotation axis: "y" (the section x-z is the plane of rotation, the field
  // fans out along the section) or "x" (it fans out across the breadth).
  char axis = 'y';
  bool coriolis = false; // add -2 omega x v
  // The radius where the g-level is n, for a model of height H [m, real scale].
  double reference_radius(double model_height_m) const {
    switch (reference) {
    case FieldReference::base:
      return base_radius_m;
    case FieldReference::third_depth:
      return base_radius_m - 2.0 * model_height_m / 3.0;
    case FieldReference::radius:
      break;
    }
    return reference_radius_m;
  }
};

// Moisture-graded adhesion ([moisture]): MoistureSpec in physics/moisture.hpp.

// `[limit_equilibrium]`: the soil's strength for the classical estimate of
// the critical g beside the DEM (procedures/slope_stability.hpp): c and phi
// from the shear box run on the slope's own material (F0 / s) at the slope's
// stresses (docs/slope.md "Limit equilibrium").
struct LimitEquilibriumSpec {
  bool enabled = false;
  double cohesion_Pa = 0;        // `cohesion_Pa`: c >= 0 [Pa]
  double friction_angle_deg = 0; // `friction_angle_deg`: phi in (0, 90) [deg]
  // `bulk_density_kg_m3`: the soil's bulk density; 0 = from the prepared
  // foundation (particle density x (1 - porosity)) [kg/m^3]
  double bulk_density_kg_m3 = 0;
  std::string source; // `source`: where c and phi come from (free text, for the summary)
};

struct TrialSpec {
  double local_damping = 0.7;         // Cundall local damping (Table 1) [-]
  double equilibrium_ratio = 1e-4;    // foundation: mean unbalanced-force ratio [-]
  long foundation_max_steps = 400000; // step limit of the foundation's equilibrium
  // At rest also means little motion: kinetic energy / (weight x d50) below
  // this (a packing without contacts falling freely is not at rest) [-].
  double rest_kinetic_ratio = 1e-6;
  long check_interval_steps = 1000; // steps between failure checks
  double max_time_s = 0.15;         // trial time after the cut [s, DEM]
  // The slope is not called stable before this trial time after the cut,
  // however still it stands (it is watched on; a slide may still start) [s,
  // DEM]. At rest early is not stable: a cohesive slope stands still for a
  // while after the cut and may fail later (the paper's slopes were watched
  // 0.023-0.032 s before being called stable).
  double min_time_s = 0.0;
  double after_failure_time_s = 0.05; // extra time to watch a slide after onset [s, DEM]
  // Contact defaults for contacts made after the cut (patch over the soil's):
  // mu_r = 0 (paper section 3.3: "mu_r was set to zero for all new ball-ball
  // contact established during the sliding process"). The stricter rule of
  // the shear box (no adhesion on new contacts either) is the option
  // { rolling_friction = 0, attraction_force_N = 0 }.
  ContactPatch after_cut;
  // `trial.at_cut`: a patch applied to every contact that exists at the cut
  // (default: none), e.g. a strength reduction of the whole slope.
  ContactPatch at_cut;
  int threads = 1;                     // OpenMP threads per trial (0 = OpenMP default)
  double checkpoint_interval_min = 10; // wall-clock minutes between checkpoints (0 = none)
  long checkpoint_interval_steps = 0;  // steps between checkpoints (0 = none)
};

enum class CampaignKind { list, search, schedule };

struct CampaignSpec {
  CampaignKind kind = CampaignKind::list;
  std::vector<double> g_levels; // list: independent trials; schedule: the steps given
  // search: bisection between a stable and a failing level
  double stable_g = 0, failed_g = 0, tolerance_g = 2.5;
  // schedule: after g_levels, + step_g until max_g
  double step_g = 10, max_g = 100;
  int max_slides = 3; // schedule: stop after this many slides
  int jobs = 1;       // trials at once (child processes)
};

struct SlopeOutput {
  double colour_min_m = 1.2e-4; // displacement colour range (log) [m]
  double colour_max_m = 5e-3;
  long frame_interval_steps = 100000; // pictures every N steps (paper: 1e5); 0 = start and end only
  bool vtk = true;                    // ParaView series of the same frames
  int picture_width_px = 1400;
};

struct SlopeScenario {
  std::string source_path;
  std::string base_dir;
  std::string description;
  std::string name; // `slope.name`: label on pictures ("lower first bench")
  SpecimenSpec specimen;
  PreparationSpec preparation; // [preparation]: the foundation is prepared (and cached) when set
  ContactProperties ball_ball; // [contact.ball_ball] as given (laboratory F0)
  BenchedSlope slope;
  bool attraction_divided_by_s = true; // `slope.attraction_divided_by_s`
  ChamberWalls walls;
  FieldSpec field;
  MoistureSpec moisture;
  LimitEquilibriumSpec limit_equilibrium;
  TrialSpec trial;
  FailureCriteria failure;
  CampaignSpec campaign;
  SlopeOutput output;

  // The soil's contact properties in the slope: F0 / s when
  // attraction_divided_by_s (paper: 1.2e-4 N / 0.063 = 1.905e-3 N).
  ContactProperties soil() const;
  // The defaults for contacts made after the cut: after_cut over soil().
  ContactProperties soil_after_cut() const;
  // The properties of the contacts that exist at the cut: at_cut over soil()
  // (before the moisture grading of F0).
  ContactProperties soil_at_cut() const;
};

SlopeScenario parse_slope_scenario(std::string_view toml_text, const std::string& source_name,
                                   const std::string& base_dir);
// `overrides`: `KEY = VALUE` lines merged over the file (tomlread::apply_overrides).
SlopeScenario load_slope_scenario(const std::string& path,
                                  const std::vector<std::string>& overrides = {});

// The same slope at another size reduction factor `s` (`--scale`): the DEM
// box (the specimen's region) scales with it and the brick is cut to fit. The
// soil stays the scenario's: when the scenario divides F0 by its own s (the
// paper's rule), that F0 is kept, not divided by the new s, so stresses
// (n g / s x s) and the cohesion (F0 / d^2, the same grains) do not change.
// Throws InputError naming `key` unless 0 < s <= 1.
void apply_scale(SlopeScenario& sc, double s, const std::string& key = "--scale");

// The resolved scenario as TOML (every default explicit); parsing it back
// gives the same scenario.
std::string resolved_slope_toml(const SlopeScenario& s);

} // namespace centridem
