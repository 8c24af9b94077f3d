#pragma once
// Wall time of a run, for the results' *_ms fields (private to the library).
#include <chrono>

namespace sgdicp::detail {

/// Wall time since construction.
class Stopwatch {
 public:
  [[nodiscard]] double elapsed_ms() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_)
        .count();
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace sgdicp::detail
