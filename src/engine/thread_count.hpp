// Threads for the engine's loops (engine-internal).
#pragma once

#include "engine/world.hpp"

#include <cstddef>
#include <cstdint>
#include <omp.h>

namespace centridem {
// Threads for a loop over n items: small loops run serially (a parallel
// region costs more than it saves there, and oversubscribed machines make
// waiting threads spin). Results do not depend on the thread count.
inline int thread_count(const WorldSettings& s, std::size_t n = SIZE_MAX) {
  if (n < 2000) return 1;
  return s.threads > 0 ? s.threads : omp_get_max_threads();
}
} // namespace centridem
