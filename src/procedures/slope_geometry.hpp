// Benched slope geometry (Tao et al. section 2.1 and 3.2; ../shared/REFERENCE.md
// "Benched slope geometry"; docs/slope.md "Geometry"): the section of one of
// the two slopes of the centrifuge chamber, the excavation that shapes it out
// of the foundation, its undeformed outline and named zones for reporting.
//
// Coordinates (DEM, metres): x along the section from the chamber's back wall
// (x = 0) towards the middle of the chamber (the end of the model, x = length),
// y across the breadth (0..breadth), z up from the chamber floor. The slope
// faces +x: crest plateau next to the back wall, faces descending towards the
// middle, the excavated floor beyond the toe.
//
// Inputs are given at model scale (the centrifuge model, metres) with the size
// reduction factor s; every function of SlopeGeometry works in DEM
// coordinates = model x s. Bench numbers count from the toe as the paper
// does: bench 1 is the first bench (lowest); 0 stands for the excavated floor
// beyond the toe.
#pragma once

#include "base/vec3.hpp"

#include <cstddef>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace centridem {

class World;

// One bench, listed from the toe upwards (scenario table `benches`).
struct Bench {
  double height_m = 0.0; // `height_m`: vertical height of the bench's face [m, model scale]
  // `width_m`: width of the bench top at its top [m, model scale]. Required
  // for every bench but the top one; for the top bench it is the crest
  // plateau, i.e. crest_to_wall_m, and may be left out (if given it must
  // equal crest_to_wall_m).
  std::optional<double> width_m;
  double face_angle_deg = 70.0; // `face_angle_deg`: face inclination from horizontal, (0, 90] [deg]
};

// The benched slope as a scenario states it (model scale, metres). Defaults
// are the paper's (REFERENCE.md); `benches` has no default (see the two
// factory functions for the paper's slopes).
struct BenchedSlope {
  double total_height_m = 0.18;         // `total_height_m`: model height, floor to crest [m]
  double foundation_height_m = 0.03;    // `foundation_height_m`: soil below the toe [m]
  std::vector<Bench> benches;           // `benches`: from the toe upwards
  double breadth_m = 0.20;              // `breadth_m`: across the section (y) [m]
  double crest_to_wall_m = 0.135;       // `crest_to_wall_m`: back wall to crest edge [m]
  double length_m = 0.301;              // `length_m`: back wall to end of model (half chamber) [m]
  double size_reduction_factor = 0.063; // `size_reduction_factor`: DEM = model x s [-]

  // The paper's right slope: first bench 3.75 cm, then 11.25 cm; 3 cm wide
  // first bench; both faces 70 degrees (REFERENCE.md: 69.5 derived, 70 assumed).
  static BenchedSlope paper_lower_first_bench();
  // The paper's left slope: first bench 7.5 cm, then 7.5 cm.
  static BenchedSlope paper_higher_first_bench();
};

// Throws InputError naming the key (`where`.total_height_m,
// `where`.benches[1].face_angle_deg, ...) for non-finite or negative sizes,
// angles outside (0, 90], bench heights that do not add up to
// total_height_m - foundation_height_m, a top-bench width that is not the
// crest plateau, benches that do not fit into length_m, a size reduction
// factor outside (0, 1].
void validate(const BenchedSlope& slope, const std::string& where = "slope");

// Named zones of the undeformed outline, for reporting where a slide starts.
enum class SlopeZone {
  crest,      // the crest plateau (top of the top bench, up to the back wall)
  upper_face, // the face of the top bench
  bench_top,  // the top of a lower bench (bench 1's top is the first bench)
  lower_face, // the face of a lower bench
  toe,        // the excavated floor beyond the toe
};
std::string_view to_string(SlopeZone zone);

// A zone and the bench it belongs to (1..N from the toe; 0 for the toe floor).
struct ZoneId {
  SlopeZone zone = SlopeZone::toe;
  int bench = 0;
  bool operator==(const ZoneId&) const = default;
};
std::string to_string(const ZoneId& zone); // "crest", "bench_top_1", "lower_face_1", ...

// One straight piece of the undeformed outline (DEM coordinates).
struct OutlineSegment {
  double x0, z0, x1, z1; // from (x0, z0) to (x1, z1), x0 <= x1 [m]
  ZoneId zone;
};

// A point of a section polyline (x, z) [m].
struct SectionPoint {
  double x = 0.0, z = 0.0;
};

// The resolved geometry in DEM coordinates. Constructed from a BenchedSlope
// (validated on construction).
class SlopeGeometry {
public:
  explicit SlopeGeometry(BenchedSlope slope);

  const BenchedSlope& input() const { return slope_; }
  double scale() const { return slope_.size_reduction_factor; } // s [-]
  int bench_count() const { return static_cast<int>(slope_.benches.size()); }

  // Model box in DEM coordinates [m].
  double length() const { return length_; }
  double breadth() const { return breadth_; }
  double height() const { return height_; }
  double toe_height() const { return toe_z_; } // = foundation height
  double crest_x() const { return crest_x_; }  // edge of the crest plateau
  double toe_x() const { return toe_x_; }      // foot of the first bench's face

  // Height of the undeformed slope surface above the floor at x (piecewise
  // linear; x is clamped to [0, length]; at a vertical face the upper value).
  double z_surface(double x) const;
  // Inside the model box and on or below the surface (particle centres).
  bool is_soil(const Vec3& point) const;
  // The excavation: a centre above the surface (the particles to delete after
  // the foundation has reached equilibrium; centre based, as PFC deletes).
  bool excavated(const Vec3& point) const;
  // Predicate for World::remove_particles (by current index).
  std::function<bool(std::size_t)> excavation_predicate(const World& world) const;
  // Deletes the excavation from `world`; returns how many particles went.
  std::size_t excavate(World& world) const;

  // The undeformed surface from the back wall to the end of the model, as
  // drawn in the paper's pictures (red lines): (0, H), crest edge, face feet
  // and bench edges, toe, (length, toe height) [m].
  std::vector<SectionPoint> outline() const;
  const std::vector<OutlineSegment>& segments() const { return segments_; }

  // Zone of the outline segment nearest to (x, z) (ties: the earlier segment
  // from the back wall). Points inside the soil get the zone of the surface
  // they lie under or behind.
  ZoneId classify(double x, double z) const;
  // Bench whose column holds x: bench k spans from the foot of bench k+1's
  // face (the back wall for the top bench) to the foot of its own face;
  // 0 beyond the toe.
  int bench_at(double x) const;
  // [x_begin, x_end] of bench k's column (k = 1..N; 0: the toe floor) [m].
  std::pair<double, double> bench_column(int bench) const;

  // Areas of the section (model scale, m^2): the model box, the soil that
  // stays, and the excavated part; their ratio is the particle fraction the
  // excavation removes from a uniform specimen.
  double section_area_model_m2() const { return slope_.length_m * slope_.total_height_m; }
  double soil_area_model_m2() const;
  double excavated_area_model_m2() const { return section_area_model_m2() - soil_area_model_m2(); }
  double excavated_fraction() const { return excavated_area_model_m2() / section_area_model_m2(); }

private:
  BenchedSlope slope_;
  double length_ = 0, breadth_ = 0, height_ = 0, toe_z_ = 0, crest_x_ = 0, toe_x_ = 0;
  std::vector<SectionPoint> outline_;
  std::vector<OutlineSegment> segments_;
  std::vector<double> face_foot_x_; // by bench number - 1: foot of that bench's face [m]
};

// Geometry summary for summary.json: inputs, DEM box, toe and crest, outline,
// zones and the excavated fraction.
nlohmann::json to_json(const SlopeGeometry& geometry);

} // namespace centridem
