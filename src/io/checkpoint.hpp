// Checkpoints: the whole state of a World (particles, walls, contact history
// with each contact's properties, body field, periodic box, contact defaults,
// clock) plus an opaque blob for the procedure driving it (its progress, its
// random generator state), in one binary file with a format version and a
// checksum, written atomically (write aside, fsync, rename).
//
// Resuming reproduces a run bit for bit on the same thread count: writing a
// checkpoint forces a neighbour rebuild of the running World, and reading one
// rebuilds the new World from the same state, so both continue from identical
// particle order and neighbour lists.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace centridem {

class World;

inline constexpr unsigned kCheckpointVersion = 1;

// FNV-1a, 64 bit: the checkpoint checksum (detects flipped bytes; with the
// stored length, truncation); also a cache key for recipes.
std::uint64_t fnv1a(std::string_view data);

// Writes `world` (and `procedure_state`, any bytes) to `path` atomically.
// Requests a rebuild of `world` (see above).
void write_checkpoint(World& world, const std::string& path,
                      const std::string& procedure_state = {});

struct LoadedCheckpoint {
  std::string procedure_state;
};

// Replaces the content of `world` (which must be freshly constructed) by the
// checkpoint's. Throws InputError on a missing, truncated, corrupt (checksum)
// or incompatible (version) file, naming the file and the problem.
LoadedCheckpoint read_checkpoint(World& world, const std::string& path);

} // namespace centridem
