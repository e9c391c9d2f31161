// Plain particle files: one particle per line, whitespace separated, SI.
// Reading accepts `x y z r` (extra columns are ignored only when they are
// numbers); '#' starts a comment. Writing gives `x y z r vx vy vz` in id order.
#pragma once

#include "core/vec3.hpp"

#include <string>
#include <vector>

namespace centridem {

class World;

struct ParticleRecord {
  Vec3 position; // [m]
  double radius; // [m]
};

// Throws InputError naming the file, line and column on bad content.
std::vector<ParticleRecord> read_particle_file(const std::string& path);
void write_particle_file(const World& world, const std::string& path);

} // namespace centridem
