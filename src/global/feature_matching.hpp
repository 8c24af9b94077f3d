#pragma once
// Putative correspondences between two clouds' FPFH descriptors: nearest neighbours in the
// 33-dimensional feature space, kept where the match is mutual.
#include <cstdint>
#include <utility>
#include <vector>

#include "sgdicp/global/fpfh.hpp"

namespace sgdicp::detail {

/// Source x reference descriptors up to which the nearest are found exhaustively (exact, by
/// blocks of a matrix product); beyond it by KD-trees (approximate: within twice the nearest's
/// distance). In 33 dimensions a tree visits most of its leaves: on the car scans' 3,145 x 2,877
/// descriptors its two searches took about 60 ms, the product 24 ms.
inline constexpr std::size_t kExhaustiveFeaturePairs = 40'000'000;

/// (source index, reference index) pairs. Mutual nearest neighbours when at least
/// `min_mutual` are, else every source point's nearest (a small or repetitive scene leaves too
/// few mutual matches to sample). Zero descriptors (no surface around the point) take no part.
[[nodiscard]] std::vector<std::pair<std::uint32_t, std::uint32_t>> match_features(
    const std::vector<Fpfh>& source, const std::vector<Fpfh>& reference, std::size_t min_mutual,
    std::size_t exhaustive_pairs = kExhaustiveFeaturePairs);

}  // namespace sgdicp::detail
