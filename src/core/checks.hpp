#pragma once
// Input checks shared by every solver (private to the library).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include <Eigen/Core>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/pose.hpp"

namespace sgdicp::detail {

/// The largest |coordinate| of a cloud; InvalidInputError "`what` has a non-finite point at
/// index i" for a non-finite point. Non-negative floats order as their bit patterns, and inf and
/// NaN lie above every finite value, so one integer maximum over the coordinates' magnitude bits
/// both finds the largest and detects a non-finite one: a loop the compiler vectorises (~3
/// instructions per coordinate; a per-point allFinite() test took 16 per point, 2 % of a
/// default registration on a Kinect frame).
inline float largest_coordinate(const PointCloud& cloud, const char* what = "cloud") {
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  const float* coordinates = cloud.points.empty() ? nullptr : cloud.points.front().data();
  const std::size_t count = 3 * cloud.size();
  std::uint32_t largest_bits = 0;
  for (std::size_t k = 0; k < count; ++k) {
    largest_bits =
        std::max(largest_bits, std::bit_cast<std::uint32_t>(coordinates[k]) & 0x7FFFFFFFU);
  }
  if (largest_bits >= std::bit_cast<std::uint32_t>(std::numeric_limits<float>::infinity())) {
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (!cloud.points[i].allFinite()) {
        throw InvalidInputError(std::string(what) + " has a non-finite point at index " +
                                std::to_string(i));
      }
    }
  }
  return std::bit_cast<float>(largest_bits);
}

/// A cloud's bounding box and its largest |coordinate|, from one pass over it (point_cloud.cpp);
/// InvalidInputError for a non-finite point as largest_coordinate. The thinning and the voxel
/// size search read both: one pass, not two or three (~2 % of a registration on a Kinect frame).
struct CloudExtent {
  BoundingBox box;
  float largest = 0.0F;
};
[[nodiscard]] CloudExtent extent_of(const PointCloud& cloud, const char* what = "cloud");

/// Throws InvalidInputError for an empty source, one with fewer than `min_points` points
/// (`what_min` says why that many), or (unless `finite_checked_later`: a thinning that checks it
/// follows) one with a non-finite point.
inline void check_source(const PointCloud& source, std::size_t min_points,
                         const std::string& what_min, bool finite_checked_later = false) {
  if (source.empty()) throw InvalidInputError("source cloud is empty");
  if (source.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw InvalidInputError("source cloud has more than 2^32-1 points");
  }
  if (source.size() < min_points) {
    throw InvalidInputError("source cloud has " + std::to_string(source.size()) +
                            " points, fewer than " + what_min + " " + std::to_string(min_points));
  }
  if (!finite_checked_later) (void)largest_coordinate(source, "source cloud");
}

inline void check_initial_transform(const Eigen::Matrix4d& T_init) {
  if (!is_rigid_transform(T_init, 1e-4)) {
    throw InvalidInputError(
        "initial transform is not a finite rigid transform (rotation part must be orthonormal "
        "with determinant 1, last row 0 0 0 1)");
  }
}

}  // namespace sgdicp::detail
