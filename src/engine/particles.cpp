#include "engine/particles.hpp"

#include <numbers>

namespace centridem {

void ParticleStore::reserve(std::size_t n) {
  for (auto* v : {&position, &velocity, &spin, &force, &moment, &applied_force, &applied_moment,
                  &displacement})
    v->reserve(n);
  radius.reserve(n), mass.reserve(n), inertia.reserve(n);
  id.reserve(n), group.reserve(n), flags.reserve(n);
}

std::size_t ParticleStore::add(std::int64_t pid, const Vec3& x, double radius_m,
                               double density_kg_m3, std::int32_t grp) {
  // Solid sphere: m = 4/3 pi R^3 rho, I = 2/5 m R^2.
  const double m = 4.0 / 3.0 * std::numbers::pi * radius_m * radius_m * radius_m * density_kg_m3;
  position.push_back(x);
  for (auto* v :
       {&velocity, &spin, &force, &moment, &applied_force, &applied_moment, &displacement})
    v->push_back({});
  radius.push_back(radius_m);
  mass.push_back(m);
  inertia.push_back(0.4 * m * radius_m * radius_m);
  id.push_back(pid);
  group.push_back(grp);
  flags.push_back(0);
  return size() - 1;
}

namespace {
template <class T> void reorder(std::vector<T>& v, std::span<const std::uint32_t> new_to_old) {
  std::vector<T> out(new_to_old.size());
  for (std::size_t k = 0; k < new_to_old.size(); ++k) out[k] = v[new_to_old[k]];
  v.swap(out);
}
} // namespace

void ParticleStore::apply_order(std::span<const std::uint32_t> new_to_old) {
  for (auto* v : {&position, &velocity, &spin, &force, &moment, &applied_force, &applied_moment,
                  &displacement})
    reorder(*v, new_to_old);
  reorder(radius, new_to_old), reorder(mass, new_to_old), reorder(inertia, new_to_old);
  reorder(id, new_to_old), reorder(group, new_to_old), reorder(flags, new_to_old);
}

} // namespace centridem
