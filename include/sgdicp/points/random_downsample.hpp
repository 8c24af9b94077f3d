#pragma once
// Thinning a cloud to a random subset, seeded and reproducible. See docs/preprocessing.md.
#include <cstddef>
#include <cstdint>

#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp {

/// `count` distinct points chosen uniformly at random without replacement (every subset of
/// that size is equally likely), returned in input order with their normals and covariances
/// when the cloud has them. Seeded and reproducible on any standard library (std::mt19937_64 raw
/// output, our own bounded draws). count >= size returns a copy of the cloud; count = 0 returns
/// an empty cloud. Throws InvalidInputError when normals or covariances are present but not one
/// per point.
[[nodiscard]] PointCloud random_downsample(const PointCloud& cloud, std::size_t count,
                                           std::uint64_t seed);

/// random_downsample with count = round(ratio * size), at least 1 for a non-empty cloud.
/// Throws InvalidSettingsError unless ratio is in (0, 1].
[[nodiscard]] PointCloud random_downsample_ratio(const PointCloud& cloud, double ratio,
                                                 std::uint64_t seed);

}  // namespace sgdicp
