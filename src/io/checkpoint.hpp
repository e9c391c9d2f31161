// Checkpoints: the whole state of a World (particles, walls, contact history
// with each contact's properties, body field, periodic box, contact defaults,
// clock) plus an opaque blob for the procedure driving it (its progress, its
// random generator state), in one binary file with a format version and a
// checksum, written atomically (write aside, fsync, rename).
//
// Resuming reproduces a run bit for bit on the same thread count: the file
// holds the particles in their current order and what the neighbour lists
// were built from (World::BuildState), so the resumed World rebuilds exactly
// the lists the running one has. Writing a checkpoint does not perturb the
// run: a run that wrote checkpoints and one that did not are identical.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace centridem {

class World;

// 3: the neighbour-list state; 4: servo integral; 5: ball-ball defaults graded by height (a
// version-4 file is still read: it has no grading)
inline constexpr unsigned kCheckpointVersion = 5;

// FNV-1a, 64 bit: the checkpoint checksum (detects flipped bytes; with the
// stored length, truncation); also a cache key for recipes.
std::uint64_t fnv1a(std::string_view data);

// Writes `world` (and `procedure_state`, any bytes) to `path` atomically.
void write_checkpoint(const World& world, const std::string& path,
                      const std::string& procedure_state = {});

struct LoadedCheckpoint {
  std::string procedure_state;
};

// Replaces the content of `world` (which must be freshly constructed) by the
// checkpoint's. Throws InputError on a missing, truncated, corrupt (checksum)
// or incompatible (version) file, naming the file and the problem.
LoadedCheckpoint read_checkpoint(World& world, const std::string& path);

} // namespace centridem
