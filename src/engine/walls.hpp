// Rigid walls: infinite planes (one-sided half-spaces) and finite rectangles
// (two-sided plates whose faces, edges and corners all make contacts). Walls
// move with a prescribed translational velocity; a wall is the
// infinite-radius, infinite-mass limit of a ball for the contact law.
#pragma once

#include "base/vec3.hpp"

#include <algorithm>
#include <cstdint>
#include <string>

namespace centridem {

enum class WallShape : std::uint8_t { plane, rectangle };

// Servo control of a wall along one direction (PFC's servo mechanism; PFC 7
// manual, "Servo-controlled walls"): each step the wall's speed along
// `direction` is set to alpha (F_target - F_measured) / (sum kn dt), so that
// in one step it would close the force error by the fraction alpha given the
// current contact stiffness, capped at max_speed. Velocity components across
// `direction` are left as prescribed.
// Optional integral term (not in PFC): with integral_time_s = Ti > 0 the force
// error closed is (error + integral(error dt) / Ti). A proportional servo that
// must follow a specimen which keeps contracting (or dilating) at a speed v
// lags by v (sum kn) dt / alpha; the integral removes that steady error. The
// integral is held while the speed is at its cap (no wind-up).
struct WallServo {
  bool active = false;
  Vec3 direction{0, 0, 1};         // unit: the way the wall moves to compress the specimen
  double target_force_N = 0.0;     // compressive force wanted on the wall [N]
  double gain_factor = 0.5;        // alpha, in (0, 1] [-]
  double max_speed_m_per_s = 1.0;  // speed cap [m/s]
  double integral_time_s = 0.0;    // Ti [s]; 0: proportional only (PFC's form)
  double error_integral_N_s = 0.0; // state: integral of the force error over time [N s]
};

struct Wall {
  std::string name;
  WallShape shape = WallShape::plane;
  Vec3 point;                        // plane: any point on it; rectangle: its centre [m]
  Vec3 normal{0, 0, 1};              // unit normal; for a plane, the side balls live on
  Vec3 axis_u, axis_v;               // rectangle: unit in-plane edge directions
  double half_u = 0.0, half_v = 0.0; // rectangle: half edge lengths [m]
  Vec3 velocity;                     // prescribed translational velocity [m/s]
  Vec3 force;                        // measured: total force the balls exert on the wall [N]
  std::uint16_t properties = 0;      // index of its current default contact properties
  std::uint32_t contact_count = 0;
  double normal_stiffness_N_per_m = 0.0; // measured: sum of kn over its contacts (servo walls)
  WallServo servo;                       // measured: active ball-wall contacts

  static Wall plane(std::string name, const Vec3& point, const Vec3& normal);
  // Rectangle from its centre, normal and one edge direction (u); v = n x u.
  static Wall rectangle(std::string name, const Vec3& centre, const Vec3& normal,
                        const Vec3& u_direction, double length_u_m, double length_v_m);
};

// Closest point of the wall's surface to x, and the vector from it to x.
struct WallProximity {
  Vec3 closest;    // on the wall surface [m]
  Vec3 to_centre;  // x - closest [m]
  double distance; // |x - closest|, signed for planes (negative behind) [m]
};

inline WallProximity wall_proximity(const Wall& w, const Vec3& x) {
  const Vec3 r = x - w.point;
  if (w.shape == WallShape::plane) {
    const double s = dot(r, w.normal);
    return {x - s * w.normal, s * w.normal, s};
  }
  const double a = std::clamp(dot(r, w.axis_u), -w.half_u, w.half_u);
  const double b = std::clamp(dot(r, w.axis_v), -w.half_v, w.half_v);
  const Vec3 q = w.point + a * w.axis_u + b * w.axis_v;
  const Vec3 d = x - q;
  return {q, d, norm(d)};
}

// Unit normal from a ball centre x towards the wall, given its proximity.
inline Vec3 ball_to_wall_normal(const Wall& w, const WallProximity& p) {
  if (w.shape == WallShape::plane) return -w.normal;
  if (p.distance > 0.0) return p.to_centre * (-1.0 / p.distance);
  return -w.normal; // centre exactly on the plate: push along the normal
}

} // namespace centridem
