#pragma once
// Putative correspondences between two clouds' FPFH descriptors: nearest neighbours in the
// 33-dimensional feature space, kept where the match is mutual.
#include <cstdint>
#include <utility>
#include <vector>

#include "sgdicp/global/fpfh.hpp"

namespace sgdicp::detail {

/// (source index, reference index) pairs. Mutual nearest neighbours when at least
/// `min_mutual` are, else every source point's nearest (a small or repetitive scene leaves too
/// few mutual matches to sample). Zero descriptors (no surface around the point) take no part.
[[nodiscard]] std::vector<std::pair<std::uint32_t, std::uint32_t>> match_features(
    const std::vector<Fpfh>& source, const std::vector<Fpfh>& reference, std::size_t min_mutual);

}  // namespace sgdicp::detail
