// Classical limit equilibrium for slope stability: Bishop's simplified method
// of slices on circular slip surfaces, a search for the critical circle and the
// g-level at which a slope's minimum factor of safety reaches 1. A reference
// for the DEM centrifuge trials, independent of the particle code.
//
// Plane strain, per metre of breadth, dry / total stress (no pore pressure).
// x horizontal, z up, SI units. The section is a ground surface polyline with
// soil below it down to a rigid floor; the slope may face +x or -x: for every
// circle the sense of rotation is the one the weight drives.
//
// Bishop, A.W. (1955) The use of the slip circle in the stability analysis of
// slopes. Geotechnique 5(1):7-17. Duncan, J.M., Wright, S.G. & Brandon, T.L.
// (2014) Soil Strength and Slope Stability, 2nd ed., Wiley, ch. 6.
#pragma once

#include <optional>
#include <utility>
#include <vector>

namespace centridem {

struct LeSoil {
  double cohesion_Pa = 0.0;        // c >= 0 [Pa]
  double friction_angle_deg = 0.0; // 0 <= phi < 90 [deg]
  double unit_weight_N_m3 = 0.0;   // gamma > 0 [N/m^3]
};

struct LeCircle {
  double xc_m = 0.0, zc_m = 0.0, radius_m = 0.0;
};

// Ground surface: (x, z) points ordered along the surface with non-decreasing
// x; two points with the same x make a vertical face. Soil lies below the
// surface down to floor_z_m, a rigid base that slip surfaces may not cut.
struct LeSection {
  std::vector<std::pair<double, double>> surface;
  double floor_z_m = 0.0;
};

// Throw InputError naming the field (section.surface[2].x, soil.cohesion_Pa,
// ...) for non-finite numbers, c < 0, phi outside [0, 90), gamma <= 0, fewer
// than two surface points, decreasing x, no horizontal extent, or surface
// points below the floor.
void validate(const LeSection& section);
void validate(const LeSoil& soil);

// Bishop's simplified factor of safety of one circle, with `slices` slices of
// equal width between the two points where the surface enters and leaves the
// circle, iterated to 1e-10 relative. A circle that cuts the surface more than
// twice (a steep cut's toe circle passes under the toe and cuts the ground in
// front again) encloses several separate bodies; the heaviest is analysed.
// nullopt when the circle cuts the surface fewer than twice, an end of the
// surface lies inside it, the body's ends are not on the circle's lower half,
// it reaches below the floor, no weight drives it, or a slice has
// m_alpha < 0.2 (see limit_equilibrium.cpp). Throws InputError for bad input.
std::optional<double> bishop_factor_of_safety(const LeSection& section, const LeSoil& soil,
                                              const LeCircle& circle, int slices = 60);

struct LeSearchOptions {
  int centres_x = 20; // grid of centres over the section's x range ...
  int centres_z = 20; // ... and from the toe level to crest + centre_height_factor x height
  int radii = 20;     // radii per centre, between the nearest and farthest surface point
  double centre_height_factor = 2.0;
  int slices = 60;
  // Smallest admissible slip: the largest vertical depth of the slip surface
  // below the ground [m]; <= 0: 2 % of the surface's height range.
  double min_depth_m = 0.0;
  int refine_starts = 4; // best grid circles (distinct centres) refined by pattern search
};

struct LeSearchResult {
  double factor_of_safety = 0.0; // +infinity when no admissible circle was found
  LeCircle circle;
  double x_entry_m = 0.0, x_exit_m = 0.0; // ends of the slip surface, x_entry_m < x_exit_m
  std::vector<std::pair<double, double>> slip_surface; // points of the arc, for drawing
  int circles_tried = 0;
};

// The circle of least Bishop factor of safety: a grid of centres and radii,
// then a pattern search (centre and radius, shrinking steps) from the best
// few. Deterministic.
LeSearchResult critical_circle(const LeSection& section, const LeSoil& soil,
                               const LeSearchOptions& options = {});

struct LeCriticalGOptions {
  double n_lo = 1.0, n_hi = 1000.0; // g-levels bracketing the answer
  double fs_tolerance = 1e-4;       // stop at |FS - 1| <= this
  int max_iterations = 60;
  LeSearchOptions search;
};

struct LeCriticalG {
  double g_level = 0.0; // n: FS(n) = 1; n_lo or n_hi when not bracketed
  bool bracketed = false;
  LeSearchResult at_critical; // critical_circle at g_level
};

// The g-level n at which the minimum factor of safety of the section is 1 for a
// soil of unit weight bulk_density x g_n x n (g_n = 9.80665 m/s^2, as the DEM): Illinois (regula
// falsi) on ln FS against ln n, one critical_circle search per step (ln FS is linear in ln n for
// phi = 0). bracketed = false, g_level = n_lo when FS < 1 already at n_lo; g_level = n_hi when FS >
// 1 still at n_hi.
LeCriticalG critical_g_level(const LeSection& section, double cohesion_Pa,
                             double friction_angle_deg, double bulk_density_kg_m3,
                             const LeCriticalGOptions& options = {});

} // namespace centridem
