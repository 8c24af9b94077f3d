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
/// (empty, or one per point): surfaces/normals.hpp estimates them for the plane-based costs.
struct PointCloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;      ///< unit normals, or empty
  std::vector<Eigen::Matrix3f> covariances;  ///< local covariances (m^2), or empty
  /// Each point's time within its sweep, seconds from the sweep's earliest point, or empty: when
  /// a moving sensor measured it (a spinning LiDAR takes 0.1 s a sweep), for motion compensation
  /// (registration/deskew.hpp). Readers store times relative to the earliest one, so that
  /// absolute clocks (1.7e9 s) keep their microseconds in float.
  std::vector<float> times_s;
  /// Where the stored points are measured from, metres, in the cloud's own frame: point k is at
  /// origin_m + points[k]. Zero for most data; georeferenced coordinates (UTM, survey data:
  /// millions of metres, which float would snap to a 0.25-0.5 m grid) keep their exactness by
  /// an origin near the cloud (readers and the Python bindings pick it: georeferencing_origin).
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();

  [[nodiscard]] bool has_normals() const noexcept {
    return !points.empty() && normals.size() == points.size();
  }
  [[nodiscard]] bool has_covariances() const noexcept {
    return !points.empty() && covariances.size() == points.size();
  }

  [[nodiscard]] bool has_times() const noexcept {
    return !points.empty() && times_s.size() == points.size();
  }

  [[nodiscard]] std::size_t size() const noexcept { return points.size(); }
  [[nodiscard]] bool empty() const noexcept { return points.empty(); }
};

/// The largest coordinate, metres from a cloud's origin, that is a place: no point on Earth is
/// farther from a georeferencing origin, and beyond it squared distances in single precision
/// come near overflow. georeferencing_origin leaves such coordinates alone and a registration
/// rejects a scene whose bulk lies beyond.
inline constexpr double kLargestCoordinate_m = 1e9;

/// The origin a cloud whose first point is `point_m` gets, per axis: 0 below 16 km, where float
/// resolves a coordinate to 1 mm or better (so sensor-frame and local-map clouds keep exactly
/// the floats they always had), else the coordinate rounded to the nearest kilometre, so that the
/// stored floats of a georeferenced cloud (UTM, survey data: millions of metres) stay within a
/// few km of 0, where float resolves 0.5 mm or better. Nearby clouds of one survey mostly share
/// an origin; registration re-bases the source when they do not. Coordinates beyond 1e9 m are no
/// place on Earth: origin 0 (and dropped as non-finite when beyond float's range).
[[nodiscard]] inline Eigen::Vector3d georeferencing_origin(const Eigen::Vector3d& point_m) {
  constexpr double kFloatIsEnough_m = 16384.0;  // float's spacing below: 2^-10 m (< 1 mm)
  constexpr double kGrid_m = 1000.0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (Eigen::Index axis = 0; axis < 3; ++axis) {
    const double magnitude = std::abs(point_m[axis]);
    if (magnitude >= kFloatIsEnough_m && magnitude <= kLargestCoordinate_m) {
      origin[axis] = std::round(point_m[axis] / kGrid_m) * kGrid_m;
    }
  }
  return origin;
}

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
    const BoundingBox box = of(cloud);
    min = min.cwiseMin(box.min);
    max = max.cwiseMax(box.max);
  }
  /// The box of a whole cloud (one pass the compiler vectorises; point_cloud.cpp).
  [[nodiscard]] static BoundingBox of(const PointCloud& cloud);
  [[nodiscard]] bool valid() const { return (min.array() <= max.array()).all(); }
};

/// The same cloud stored relative to another origin (the points re-computed in double; normals
/// and covariances do not depend on it).
[[nodiscard]] PointCloud rebased(const PointCloud& cloud, const Eigen::Vector3d& origin_m);

/// T_reference_source between the stored points of two clouds (source measured from o_s, the
/// reference from o_r), from the one between their frames: R stays, t' = t + R o_s - o_r.
[[nodiscard]] inline Eigen::Matrix4d between_stored(const Eigen::Matrix4d& T,
                                                    const Eigen::Vector3d& source_origin_m,
                                                    const Eigen::Vector3d& reference_origin_m) {
  Eigen::Matrix4d out = T;
  out.topRightCorner<3, 1>() += T.topLeftCorner<3, 3>() * source_origin_m - reference_origin_m;
  return out;
}

/// Undoes between_stored: t = t' - R o_s + o_r.
[[nodiscard]] inline Eigen::Matrix4d between_frames(const Eigen::Matrix4d& T_stored,
                                                    const Eigen::Vector3d& source_origin_m,
                                                    const Eigen::Vector3d& reference_origin_m) {
  Eigen::Matrix4d out = T_stored;
  out.topRightCorner<3, 1>() -=
      T_stored.topLeftCorner<3, 3>() * source_origin_m - reference_origin_m;
  return out;
}

/// The cloud moved into another frame by T (p' = R p + t, normals and covariances rotated),
/// stored relative to that frame's `origin_m`; computed in double.
[[nodiscard]] PointCloud transformed(const PointCloud& cloud, const Eigen::Matrix4d& T,
                                     const Eigen::Vector3d& origin_m = Eigen::Vector3d::Zero());

}  // namespace sgdicp
