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
// pieces. 64 against 128 on the shared packing: x1.03 on 1 thread, x1.08 on
// 2, the flowing column even (docs/results/bench.md).
inline constexpr std::uint32_t kContactStageSize = 64;

struct BallBallContacts {
  std::vector<std::uint32_t> row_offset; // size n+1
  std::vector<std::uint32_t> other;      // j of each entry (j > i)
  std::vector<std::uint16_t> properties; // property-set index, or kNoContact
  std::vector<ContactState> state;       // history
  std::vector<std::uint8_t> image;       // periodic image code of j (empty if not periodic)
  // The force [N] and total moment [N m] on j of a contact whose j lies
  // beyond the block of rows its thread had in the contact pass (zero when
  // not touching): integrate() adds them. Within a block the contact pass
  // adds them to j's sums directly, and keeps the force here only on the
  // last step of a cycle() call (the measurements read it then; two arrays,
  // so that the force alone streams through the cache).
  std::vector<Vec3> force_on_2, moment_on_2;
  // Transpose: for particle j, the entries in which it is the second end
  // (in increasing entry order, that is, increasing first end i), and the
  // first end i of each slot.
  std::vector<std::uint32_t> incoming_offset; // size n+1
  std::vector<std::uint32_t> incoming;        // entry indices
  std::vector<std::uint32_t> slot_row;        // particle i of slot k's entry (its first end)
  // For particle j: 1 when the contact pass left a record in force_on_2 /
  // moment_on_2 for it (a contact from an earlier block in force), so that
  // integrate() reads j's incoming slots only then; integrate() clears it.
  // An unflagged particle's slots all hold +0 (which changes a sum only when
  // it is -0); one thread, which leaves no records, adds none either.
  std::vector<std::uint8_t> record_waits; // size n

  std::size_t entries() const { return other.size(); }
  static constexpr std::size_t bytes_per_entry() {
    return sizeof(std::uint32_t) * 3 + sizeof(std::uint16_t) + sizeof(ContactState) +
           2 * sizeof(Vec3);
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
