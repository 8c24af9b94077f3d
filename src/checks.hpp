#pragma once
// Input checks shared by every solver (private to the library).
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include <Eigen/Core>

#include "sgdicp/error.hpp"
#include "sgdicp/point_cloud.hpp"
#include "sgdicp/pose.hpp"

namespace sgdicp::detail {

/// Throws InvalidInputError for an empty source, one with fewer than `min_points` points
/// (`what_min` says why that many), or one with a non-finite point.
inline void check_source(const PointCloud& source, std::size_t min_points,
                         const std::string& what_min) {
  if (source.empty()) throw InvalidInputError("source cloud is empty");
  if (source.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw InvalidInputError("source cloud has more than 2^32-1 points");
  }
  if (source.size() < min_points) {
    throw InvalidInputError("source cloud has " + std::to_string(source.size()) +
                            " points, fewer than " + what_min + " " + std::to_string(min_points));
  }
  for (std::size_t i = 0; i < source.size(); ++i) {
    if (!source.points[i].allFinite()) {
      throw InvalidInputError("source cloud has a non-finite point at index " + std::to_string(i));
    }
  }
}

inline void check_initial_transform(const Eigen::Matrix4d& T_init) {
  if (!is_rigid_transform(T_init, 1e-4)) {
    throw InvalidInputError(
        "initial transform is not a finite rigid transform (rotation part must be orthonormal "
        "with determinant 1, last row 0 0 0 1)");
  }
}

}  // namespace sgdicp::detail
