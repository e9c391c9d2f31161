#include "engine/walls.hpp"

#include "base/errors.hpp"

#include <fmt/format.h>

namespace centridem {

namespace {
Vec3 unit(const Vec3& v, const std::string& key) {
  const double n = norm(v);
  if (!(n > 0.0) || !std::isfinite(n))
    throw InputError(key, fmt::format("[{}, {}, {}]", v.x, v.y, v.z), "must be a non-zero vector");
  return v / n;
}
} // namespace

Wall Wall::plane(std::string name, const Vec3& point, const Vec3& normal) {
  Wall w;
  w.normal = unit(normal, "walls." + name + ".normal");
  w.name = std::move(name);
  w.shape = WallShape::plane;
  w.point = point;
  return w;
}

Wall Wall::rectangle(std::string name, const Vec3& centre, const Vec3& normal,
                     const Vec3& u_direction, double length_u_m, double length_v_m) {
  Wall w;
  const std::string key = "walls." + name;
  w.normal = unit(normal, key + ".normal");
  Vec3 u = u_direction - dot(u_direction, w.normal) * w.normal; // make it in-plane
  w.axis_u = unit(u, key + ".u_direction (must not be parallel to the normal)");
  w.axis_v = cross(w.normal, w.axis_u);
  if (!(length_u_m > 0) || !(length_v_m > 0))
    throw InputError(key + ".size_m", fmt::format("[{}, {}]", length_u_m, length_v_m),
                     "both edge lengths must be > 0");
  w.half_u = 0.5 * length_u_m;
  w.half_v = 0.5 * length_v_m;
  w.name = std::move(name);
  w.shape = WallShape::rectangle;
  w.point = centre;
  return w;
}

} // namespace centridem
