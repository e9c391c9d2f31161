// Plain particle files: one particle per line, whitespace separated, SI.
// Reading accepts `x y z r` (extra columns are ignored only when they are
// numbers); '#' starts a comment. Writing gives `x y z r vx vy vz` in id order.
#pragma once

#include "base/vec3.hpp"

#include <string>
#include <vector>

namespace centridem {

class World;

struct ParticleRecord {
  Vec3 position; // [m]
  double radius; // [m]
  long line = 0; // line in the file it was read from (0: not from a file)
};

// Throws InputError naming the file, line and column on bad content.
std::vector<ParticleRecord> read_particle_file(const std::string& path);

// Refuses (InputError naming the file and both lines) two particles that
// overlap by more than `max_overlap_fraction` of the smaller radius: a line
// given twice (coincident: the overlap is the sum of the radii) or a packing
// that would trip the run's overlap guard at its first step.
void check_particle_overlaps(const std::vector<ParticleRecord>& records, const std::string& path,
                             double max_overlap_fraction);
void write_particle_file(const World& world, const std::string& path);

} // namespace centridem
