#pragma once
// The local map of odometry: a hash map of cubic voxels, each holding at most a bounded number of
// points, updated incrementally (points added frame by frame, far voxels dropped), so its memory
// is bounded by the region around the sensor and not by the length of the sequence.
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp {

class VoxelMap {
 public:
  /// voxel_size_m > 0 and finite, max_points_per_voxel >= 1; InvalidSettingsError otherwise.
  VoxelMap(double voxel_size_m, std::size_t max_points_per_voxel);

  /// Adds the points of `cloud` (in the map frame): a point enters its voxel while the voxel
  /// holds fewer than max_points_per_voxel points, and is dropped otherwise (the first points
  /// of a voxel stay: a static world is seen again, not re-measured). Non-finite points are
  /// skipped. The points' normals and covariances, when the cloud has them, enter with them
  /// (estimated once per frame, not over the whole map each frame: docs/odometry.md).
  void add(const PointCloud& cloud);

  /// The indices of the points of `cloud` (in the map frame) that add(cloud) would keep, in
  /// order: what needs a normal before it enters (a frame's surfaces are estimated for these
  /// alone: on a slow Kinect walk most voxels are full and 5 % of a frame's points enter).
  [[nodiscard]] std::vector<std::uint32_t> admitted(const PointCloud& cloud) const;

  /// Drops every voxel whose first point lies farther than radius_m from `centre_m`.
  void remove_far_from(const Eigen::Vector3d& centre_m, double radius_m);

  /// Every point of the map, one cloud (the order of the voxels in the hash map), with normals
  /// (covariances) when every point of the map came with one.
  [[nodiscard]] PointCloud points() const;

  [[nodiscard]] std::size_t size() const noexcept { return points_; }
  [[nodiscard]] std::size_t voxels() const noexcept { return voxels_.size(); }
  [[nodiscard]] bool empty() const noexcept { return points_ == 0; }
  [[nodiscard]] double voxel_size_m() const noexcept { return voxel_size_m_; }
  [[nodiscard]] std::size_t max_points_per_voxel() const noexcept { return max_points_; }
  void clear();

 private:
  struct Key {
    std::int64_t x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const noexcept;
  };
  [[nodiscard]] Key key_of(const Eigen::Vector3f& p) const;

  double voxel_size_m_;
  std::size_t max_points_;
  struct Voxel {
    std::vector<Eigen::Vector3f> points;
    std::vector<Eigen::Vector3f> normals;
    std::vector<Eigen::Matrix3f> covariances;
  };
  std::size_t points_ = 0;
  std::size_t normals_ = 0;      ///< points that came with a normal
  std::size_t covariances_ = 0;  ///< ... with a covariance
  std::unordered_map<Key, Voxel, KeyHash> voxels_;
};

}  // namespace sgdicp
