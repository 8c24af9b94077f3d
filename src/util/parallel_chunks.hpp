#pragma once
// Contiguous chunks of a loop over points on the calling thread and its helpers
// (helper_thread.hpp), for the passes of the voxel grids and the surfaces (private to the library).
#include <algorithm>
#include <cstddef>
#include <vector>

#include "sgdicp/core/threads.hpp"
#include "util/helper_thread.hpp"

namespace sgdicp::detail {

/// Fewer points per thread than this are not worth a thread start (~tens of microseconds).
inline constexpr std::size_t kMinPointsPerThread = 512;

/// The threads worth using for `num_points` points when `requested` are asked for (0 = every
/// core): at most one per kMinPointsPerThread points, at least one.
[[nodiscard]] inline std::size_t resolve_threads(std::size_t requested, std::size_t num_points) {
  const std::size_t threads = resolve_thread_count(requested);
  const std::size_t useful = (num_points + kMinPointsPerThread - 1) / kMinPointsPerThread;
  return std::clamp<std::size_t>(useful, 1, threads);
}

/// Runs body(begin, end) over contiguous chunks of [0, n) on `threads` threads (the calling
/// thread takes the first chunk, its helpers the others: run_ranges) and rethrows the first
/// exception after all have ended.
template <class Body>
void parallel_chunks(std::size_t n, std::size_t threads, const Body& body) {
  std::vector<std::size_t> bounds(threads + 1);
  for (std::size_t t = 0; t <= threads; ++t) bounds[t] = n * t / threads;
  run_ranges(bounds, body);
}

/// body(part) for every part of `parts`, on up to `threads` threads (0 = every core).
template <class Body>
void for_parts(std::size_t parts, std::size_t threads, const Body& body) {
  parallel_chunks(parts, std::min(resolve_thread_count(threads), parts),
                  [&](std::size_t begin, std::size_t end) {
                    for (std::size_t part = begin; part < end; ++part) body(part);
                  });
}

}  // namespace sgdicp::detail
