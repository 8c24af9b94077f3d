#pragma once
// Thread counts of the settings (KD-tree build, normals, registration): one limit and one
// meaning of 0 for all of them.
#include <algorithm>
#include <cstddef>
#include <thread>

namespace sgdicp {

/// The largest thread count a setting accepts.
inline constexpr std::size_t kMaxThreads = 1024;

/// A setting's thread count as used: 0 means every core (std::thread::hardware_concurrency(),
/// at least 1).
[[nodiscard]] inline std::size_t resolve_thread_count(std::size_t requested) {
  if (requested != 0) return requested;
  return std::max<std::size_t>(std::thread::hardware_concurrency(), 1);
}

}  // namespace sgdicp
