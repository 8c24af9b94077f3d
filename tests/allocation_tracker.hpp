#pragma once
// The largest single allocation through operator new since the last reset, for tests that a
// lying header is rejected before its claimed size is allocated. Linking allocation_tracker.cpp
// replaces the global operator new of the test binary.
#include <cstddef>

namespace sgdicp {

void reset_largest_allocation();
[[nodiscard]] std::size_t largest_allocation();

}  // namespace sgdicp
