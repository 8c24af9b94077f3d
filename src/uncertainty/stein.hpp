#pragma once
// The kernel of Stein variational gradient descent (uncertainty.hpp's stein_descent), shared
// with the modes of svgd's particles in uncertainty.cpp.
#include <vector>

#include "sgdicp/core/pose.hpp"

namespace sgdicp::detail {

/// The distance within which two particles of `z` belong to one mode (kModeLinkDistance, or
/// kModeLinkBandwidth times the median heuristic's bandwidth of the particles).
[[nodiscard]] double particle_link(const std::vector<PoseVector>& z);

}  // namespace sgdicp::detail
