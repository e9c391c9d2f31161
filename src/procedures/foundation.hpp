// The benched slope's foundation (Tao et al. section 3.2: "following the
// sample generation method used in the NDST"; docs/slope.md "Foundation";
// issue 16):
//
//   build     the chamber walls and the specimen (a cached brick tiled into
//             the chamber), fitted into the walls;
//   prepare   ([preparation], io/preparation_config.hpp) generated
//             `overfill` times as high as the design, compacted with the
//             preparation's contact properties under gravity at the
//             preparation's g-level (and a top plate, when a compaction
//             stress is given), every contact switched to the soil, settled
//             until at rest, the top plate lifted, and everything whose centre
//             lies above the design height removed (the physical model was
//             trimmed the same way); homogeneity measured in three layers;
//   cache     the prepared foundation saved as a checkpoint keyed by
//             everything that changes it, so a campaign prepares it once.
//
// The trial (procedures/slope_trial.hpp) then re-equilibrates the foundation
// at its own g-level before the cut.
#pragma once

#include "procedures/slope_config.hpp"
#include "procedures/slope_geometry.hpp"

#include <array>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace centridem {

class World;
struct ParticleStore;
struct Box;

struct FoundationResult {
  std::size_t particles = 0; // at the cut's start (the paper: 47,070 before the cut)
  long steps = 0;            // the trial's re-equilibration
  double ratio = 0;          // mean unbalanced-force ratio at the end [-]
  double kinetic_ratio = 0;  // kinetic energy / (weight x d50) at the end [-]
  bool converged = false;    // at rest (ratio and kinetic energy) within the step limit
  double box_top_m = 0;      // the design height (the crest) [m, DEM]
  double surface_min_m = 0, surface_mean_m = 0;   // settled surface, columns of 2 d50 [m]
  double porosity_before = 0, porosity_after = 0; // of the soil below the surface [-]
  double coordination_number = 0;                 // (2 Nbb + Nbw) / N before the cut [-]
  std::size_t brick_particles = 0;
  bool brick_from_cache = false;
  std::string brick_file;
  // Prepared foundations only ([preparation]).
  bool prepared = false;
  std::size_t generated_particles = 0; // before trimming
  long compaction_steps = 0, settle_steps = 0;
  double compaction_g_level = 0;
  double prepared_surface_min_m = 0;      // lowest column top before trimming [m]
  std::size_t trimmed = 0;                // particles above the design removed
  std::array<double, 3> layer_porosity{}; // bottom, middle, top third (walls left out) [-]
  bool from_cache = false;
  std::string cache_file;
};

nlohmann::json to_json(const FoundationResult& f);
FoundationResult foundation_from_json(const nlohmann::json& j);

using FoundationLog = std::function<void(std::string_view)>;

// The chamber's walls and the specimen tiled into them (brick from
// `cache_dir` when one is cached there, made and cached otherwise; no cache
// when cache_dir is ""), fitted into the walls. `height_factor` scales the
// specimen's region height (the overfill). Fills the build fields of `f`.
void build_foundation(World& world, const SlopeScenario& sc, const SlopeGeometry& geometry,
                      const std::string& cache_dir, double height_factor, FoundationResult& f,
                      const FoundationLog& log = {}, int threads = 1);

// Compacts, switches, settles and trims a built foundation (see the file
// comment); fills the preparation fields of `f`. Throws InputError
// (preparation.overfill) when the prepared surface stays below the design.
void prepare_foundation(World& world, const SlopeScenario& sc, const SlopeGeometry& geometry,
                        FoundationResult& f, const FoundationLog& log = {});

// Where the prepared foundation of `sc` is cached in `cache_dir` (a
// checkpoint named by the hash of everything that changes it).
std::string prepared_foundation_path(const SlopeScenario& sc, const std::string& cache_dir);

// The cached prepared foundation of `sc` in `cache_dir`, made (with `threads`
// threads; the result does not depend on them) when missing.
struct PreparedFoundationFile {
  std::string path;        // the checkpoint (procedure blob: the FoundationResult as JSON)
  FoundationResult result; // its preparation report
  bool made_now = false;   // false: it was in the cache
};
// The report of the cached prepared foundation (read from the JSON beside the
// checkpoint, without loading the World: no OpenMP in a process that forks
// trials afterwards); nullopt when it is not cached.
std::optional<FoundationResult> cached_foundation_result(const SlopeScenario& sc,
                                                         const std::string& cache_dir);

PreparedFoundationFile ensure_prepared_foundation(const SlopeScenario& sc,
                                                  const std::string& cache_dir,
                                                  const FoundationLog& log = {}, int threads = 1);

// Porosity of three equal horizontal layers of `box`, leaving out `margin_m`
// inside each of its faces (walls, floor, and the rough top); exact in z (each
// sphere's slice of a layer), centre based in x and y [-].
std::array<double, 3> layer_porosities(const World& world, const Box& box, double margin_m);

// The same measurement in `layers` equal horizontal layers: a porosity
// profile (bottom first) [-].
std::vector<double> porosity_layers(const World& world, const Box& box, double margin_m,
                                    int layers);

// A foundation's porosity against height in its design box (the chamber up
// to the design height): layers about 2 d50 thick between one d_max above the
// floor and one d_max below the top, one d_max left out inside every side
// wall (as for the thirds); at least 3 layers.
struct PorosityProfile {
  double margin_m = 0;            // d_max [m]
  double layer_m = 0;             // layer thickness [m]
  std::vector<double> z_bottom_m; // each layer's bottom [m]
  std::vector<double> porosity;   // [-]
};
PorosityProfile foundation_porosity_profile(const World& world, const Box& design_box);
nlohmann::json to_json(const PorosityProfile& p);

// The surface of a foundation: the highest particle top (z + r) in columns
// 2 d50 wide along x (over the whole breadth); min and mean over the columns [m].
std::pair<double, double> foundation_surface(const ParticleStore& particles, double length_m,
                                             double d50_m);

// Translational kinetic energy over the weight of the particles times d50
// under the current field at the floor's centre: a packing at rest has a
// small value, one falling under gravity a large one [-]. Rotation is left
// out: a grain spinning about its contact normal (twist, which neither
// friction nor rolling resistance resists, as in PFC) keeps its spin with no
// force on it and moves nothing (seen: 235 rad/s on the floor for 10^5 steps).
double kinetic_energy_ratio(const World& world, const Vec3& reference_point, double d50_m);

} // namespace centridem
