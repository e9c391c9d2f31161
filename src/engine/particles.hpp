// Particle store: structure of arrays, one contiguous array per field (the
// layout LAMMPS and Cabana use), so loops over particles stream memory and
// arrays can later live on a device. All SI.
#pragma once

#include "base/vec3.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace centridem {

// Per-particle motion flags (PFC `ball fix`).
enum ParticleFlag : std::uint8_t {
  fix_translation = 1, // velocity stays as set (prescribed), position follows it
  fix_rotation = 2,    // spin stays as set
};

struct ParticleStore {
  std::vector<Vec3> position;       // [m]
  std::vector<Vec3> velocity;       // [m/s], at t - dt/2 between steps
  std::vector<Vec3> spin;           // angular velocity [rad/s]
  std::vector<Vec3> force;          // unbalanced force (contacts + body + applied) [N]
  std::vector<Vec3> moment;         // unbalanced moment [N m]
  std::vector<Vec3> applied_force;  // user-applied extra force (PFC `force_app`) [N]
  std::vector<Vec3> applied_moment; // user-applied extra moment [N m]
  std::vector<Vec3> displacement;   // accumulated displacement since last reset [m]
  std::vector<double> radius;       // [m]
  std::vector<double> mass;         // [kg]
  std::vector<double> inertia;      // moment of inertia 2/5 m R^2 [kg m^2]
  std::vector<std::int64_t> id;     // user-visible, stable across re-sorting
  std::vector<std::int32_t> group;  // user group number
  std::vector<std::uint8_t> flags;  // ParticleFlag bits

  std::size_t size() const { return position.size(); }
  void reserve(std::size_t n);
  // Appends a solid sphere of the given density; returns its index.
  std::size_t add(std::int64_t id, const Vec3& x, double radius_m, double density_kg_m3,
                  std::int32_t group = 0);
  // Reorders every field so that new index k holds old index new_to_old[k]
  // (drops particles that do not appear).
  void apply_order(std::span<const std::uint32_t> new_to_old);
  // Bytes held per particle by the store itself.
  static constexpr std::size_t bytes_per_particle() {
    return 8 * sizeof(Vec3) + 3 * sizeof(double) + sizeof(std::int64_t) + sizeof(std::int32_t) +
           sizeof(std::uint8_t);
  }
};

} // namespace centridem
