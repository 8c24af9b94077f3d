#pragma once
// The point cloud type used throughout: metric x y z, single precision (as sensors deliver it).
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include <Eigen/Core>

namespace sgdicp {

/// A set of 3D points in one frame, in metres. Float storage halves memory and cache traffic;
/// all accumulations of the method are done in double. Normals and covariances are optional
/// (empty, or one per point): preprocessing.hpp estimates them for the plane-based costs.
struct PointCloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;      ///< unit normals, or empty
  std::vector<Eigen::Matrix3f> covariances;  ///< local covariances (m^2), or empty

  [[nodiscard]] bool has_normals() const noexcept {
    return !points.empty() && normals.size() == points.size();
  }
  [[nodiscard]] bool has_covariances() const noexcept {
    return !points.empty() && covariances.size() == points.size();
  }

  [[nodiscard]] std::size_t size() const noexcept { return points.size(); }
  [[nodiscard]] bool empty() const noexcept { return points.empty(); }
};

/// double -> float without the undefined behaviour of converting an out-of-range value: what
/// would round beyond FLT_MAX becomes infinite (and is then dropped or rejected as non-finite).
/// Used by the file readers and the Python bindings alike.
[[nodiscard]] inline float to_float_saturating(double value) {
  constexpr double kRoundsToInfinity = 0x1.ffffffp127;  // halfway between FLT_MAX and 2^128
  if (std::isnan(value)) return std::numeric_limits<float>::quiet_NaN();
  if (value >= kRoundsToInfinity) return std::numeric_limits<float>::infinity();
  if (value <= -kRoundsToInfinity) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(value);
}

/// Axis-aligned bounding box of a cloud. Undefined (min > max) for an empty cloud.
struct BoundingBox {
  Eigen::Vector3d min{Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity())};
  Eigen::Vector3d max{Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity())};

  void extend(const Eigen::Vector3d& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void extend(const PointCloud& cloud) {
    for (const auto& p : cloud.points) extend(p.cast<double>());
  }
  /// The box of a whole cloud.
  [[nodiscard]] static BoundingBox of(const PointCloud& cloud) {
    BoundingBox box;
    box.extend(cloud);
    return box;
  }
  [[nodiscard]] bool valid() const { return (min.array() <= max.array()).all(); }
};

}  // namespace sgdicp
