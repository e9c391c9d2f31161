// Moisture-graded adhesion: the attraction F0 of a ball-ball contact from
// the water content at the height where the contact is (Tao et al. section
// 3.3 blame their DEM's uniform F0 for part of its mismatch with the
// centrifuge test, whose water content after the test was 5.5 % at the top,
// 7.3 % in the middle and 9.2 % at the bottom: the water drains outwards).
//
// Two steps, both data:
//  1. the water-content profile w(h) [%], h the height over the model's
//     height (0 at the floor, 1 at the crest): linear between the given points,
//     constant beyond the first and the last. Default: the test's three
//     measurements, read as taken at the floor, mid-height and crest (the paper
//     says "bottom", "middle", "top"; an assumption).
//  2. F0 against w, as a factor on the calibrated F0 (the shear box's, at
//     w = 6 %, Table 1):
//     - "proportional" (default): factor = w / w_ref. An assumption, the upper
//       bound of the dependence: for rough grains in the pendular regime the
//       bridges' force grows with the liquid held (Halsey & Levine, PRL 80,
//       3141, 1998; Mitarai & Nori, Adv. Phys. 55, 1, 2006, section 3).
//     - "constant": factor = 1. The other bound: between smooth spheres in
//       contact the bridge force 2 pi R gamma cos(theta) hardly depends on the
//       bridge's volume (Willett et al., Langmuir 16, 9396, 2000).
//     - "table": the factor linear between (w, factor) points, constant
//       beyond the ends (measured data, e.g. from humid shear boxes at several
//       water contents).
//  The older "linear_factor" reading (top_factor / bottom_factor: a factor
//  linear in height, no water contents) is kept beside them.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

namespace centridem {

// Piecewise-linear y(x) through points sorted by strictly increasing x,
// constant beyond the first and the last point. Points must not be empty.
inline double interpolate_clamped(const std::vector<std::array<double, 2>>& points, double x) {
  if (x <= points.front()[0]) return points.front()[1];
  if (x >= points.back()[0]) return points.back()[1];
  const auto hi =
      std::upper_bound(points.begin(), points.end(), x,
                       [](double v, const std::array<double, 2>& p) { return v < p[0]; });
  const auto lo = hi - 1;
  const double t = (x - (*lo)[0]) / ((*hi)[0] - (*lo)[0]);
  return (*lo)[1] + t * ((*hi)[1] - (*lo)[1]);
}

struct MoistureSpec {
  enum class Adhesion { proportional, constant, table, linear_factor };
  bool enabled = false;
  // `profile`: [height fraction (0 floor .. 1 crest), water content %], sorted.
  std::vector<std::array<double, 2>> profile = {{0.0, 9.2}, {0.5, 7.3}, {1.0, 5.5}};
  Adhesion adhesion = Adhesion::proportional;   // `adhesion`
  double reference_water_content_percent = 6.0; // `reference_water_content_percent`: w of F0 [%]
  std::vector<std::array<double, 2>> table;     // `table`: [water content %, factor on F0]
  double top_factor = 1.0;    // `top_factor` (linear_factor): factor at the crest [-]
  double bottom_factor = 1.0; // `bottom_factor` (linear_factor): factor at the floor [-]
  int bands = 10;             // `bands`: horizontal bands of one F0 each (1 .. 1000)
  // `new_contacts`: contacts made after the cut take the F0 of their height
  // too (otherwise the after-cut defaults, ungraded).
  bool new_contacts = true;
};

// Water content at height fraction h (0 floor, 1 crest) [%].
inline double water_content_percent(const MoistureSpec& m, double h) {
  return interpolate_clamped(m.profile, h);
}

// The factor on the calibrated F0 at height fraction h [-].
inline double attraction_factor(const MoistureSpec& m, double h) {
  switch (m.adhesion) {
  case MoistureSpec::Adhesion::linear_factor:
    return m.bottom_factor + (m.top_factor - m.bottom_factor) * h;
  case MoistureSpec::Adhesion::constant:
    return 1.0;
  case MoistureSpec::Adhesion::table:
    return interpolate_clamped(m.table, water_content_percent(m, h));
  case MoistureSpec::Adhesion::proportional:
    break;
  }
  return water_content_percent(m, h) / m.reference_water_content_percent;
}

} // namespace centridem
