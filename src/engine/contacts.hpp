// Contact stores. Ball-ball contacts live in a half neighbour list (pairs
// i < j) in compressed rows by particle i; each neighbour entry carries the
// contact's history and this step's result, so history needs no hashing and
// survives rebuilds by a sorted merge (World::rebuild). Ball-wall contacts
// live in rows by particle too. An entry whose `properties` is kNoContact is
// a neighbour that is not touching.
#pragma once

#include "base/vec3.hpp"
#include "physics/contact_law.hpp"

#include <cstdint>
#include <vector>

namespace centridem {

inline constexpr std::uint16_t kNoContact = 0xFFFF;
// Touching ball-ball contacts the contact pass stages at once (contact_pass.cpp:
// 274 bytes each, 18 KB in all, a third of the 48 KB first-level cache, which
// also holds the particles and entries the find pass reads), and ball-wall
// contacts likewise (a stage of the same capacity, 210 bytes each, of which
// the few wall contacts of a block of rows touch only the first lines). A row
// with more entries of either kind than this goes through the stages in
// pieces. 64 against 128 on the shared packing, measured in an engine that
// adds the loads on end 2 in the contact pass (branch direct-scatter): x1.03
// on 1 thread, x1.08 on 2, the flowing column even (docs/results/bench.md).
inline constexpr std::uint32_t kContactStageSize = 64;

struct BallBallContacts {
  std::vector<std::uint32_t> row_offset; // size n+1
  std::vector<std::uint32_t> other;      // j of each entry (j > i)
  std::vector<std::uint16_t> properties; // property-set index, or kNoContact
  std::vector<ContactState> state;       // history
  std::vector<std::uint8_t> image;       // periodic image code of j (empty if not periodic)
  // This step's force [N] and total moment [N m] on j (zero when not
  // touching), side by side, one record per entry, in entry order: the
  // contact pass writes them in one forward run; integrate() adds them to
  // each j in increasing entry order (by entries with one thread, by the
  // transpose with more: the same order). The row owner i sums its own side
  // directly.
  struct LoadOn2 {
    Vec3 force, moment;
  };
  std::vector<LoadOn2> on_2;
  // Transpose: for particle j, the entries in which it is the second end
  // (in increasing entry order), and the particle j of each slot.
  std::vector<std::uint32_t> incoming_offset; // size n+1
  std::vector<std::uint32_t> incoming;        // entry indices
  std::vector<std::uint32_t> slot_owner;      // particle j of slot k (its second end)

  std::size_t entries() const { return other.size(); }
  static constexpr std::size_t bytes_per_entry() {
    return sizeof(std::uint32_t) * 3 + sizeof(std::uint16_t) + sizeof(ContactState) +
           sizeof(LoadOn2);
  }
};

struct BallWallContacts {
  std::vector<std::uint32_t> row_offset; // size n+1
  std::vector<std::uint16_t> wall;       // wall index of each entry
  std::vector<std::uint32_t> ball;       // ball index of each entry (for per-wall sums)
  std::vector<std::uint16_t> properties; // property-set index, or kNoContact
  std::vector<ContactState> state;       // history (end 1 = ball, end 2 = wall)
  std::vector<Vec3> force_on_wall;       // this step's force on the wall [N]

  std::size_t entries() const { return wall.size(); }
  static constexpr std::size_t bytes_per_entry() {
    return 2 * sizeof(std::uint32_t) + 2 * sizeof(std::uint16_t) + sizeof(ContactState) +
           sizeof(Vec3);
  }
};

} // namespace centridem
