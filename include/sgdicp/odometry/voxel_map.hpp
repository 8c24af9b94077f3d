#pragma once
// The local map of odometry: cubic voxels, each holding at most a bounded number of points, no
// two closer than a spacing (its size follows the surface it covers, not the frames that saw it),
// updated in place (points added frame by frame, far cells dropped), so its memory is bounded by
// the region around the sensor and not by the length of the sequence. The map is its own
// nearest-neighbour index (a voxel hash of cells of 2x2x2 voxels, src/index/voxel_hash.hpp): a
// frame is registered against it as it stands, with no copy and no build
// (docs/odometry-results.md, *The map is its own index*).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"

namespace sgdicp {

class VoxelMap {
 public:
  /// voxel_size_m > 0 and finite, max_points_per_voxel >= 1; InvalidSettingsError otherwise.
  VoxelMap(double voxel_size_m, std::size_t max_points_per_voxel);
  ~VoxelMap();
  VoxelMap(const VoxelMap& other);
  VoxelMap& operator=(const VoxelMap& other);
  VoxelMap(VoxelMap&&) noexcept;
  VoxelMap& operator=(VoxelMap&&) noexcept;

  /// Adds the points of `cloud` (in the map frame): a point enters its voxel while the voxel
  /// holds fewer than max_points_per_voxel points and none closer to it than spacing_m(), and
  /// is dropped otherwise (the first points of a voxel stay: a static world is seen again, not
  /// re-measured, and a surface once covered takes no more, however often it is revisited).
  /// Non-finite points are skipped. The points' normals and covariances enter with them while every
  /// cloud added came with them (estimated once per frame, not over the whole map each frame:
  /// docs/odometry.md). Throws InvalidSettingsError for a coordinate too large for the voxel size.
  void add(const PointCloud& cloud);

  /// The indices of the points of `cloud` (in the map frame) that add(cloud) would keep, in
  /// order: what needs a normal before it enters (a frame's surfaces are estimated for these
  /// alone: on a slow Kinect walk most voxels are full or covered and a few % of a frame's points
  /// enter).
  [[nodiscard]] std::vector<std::uint32_t> admitted(const PointCloud& cloud) const;

  /// Drops every cell of 2x2x2 voxels whose first point lies farther than radius_m from
  /// `centre_m`.
  void remove_far_from(const Eigen::Vector3d& centre_m, double radius_m);

  /// Every point of the map, one cloud (in no particular order), with normals (covariances) when
  /// every point of the map came with one.
  [[nodiscard]] const PointCloud& points() const;

  /// A nearest-neighbour index over points(), read in place (ReferenceIndex::viewing): valid
  /// until the map changes. Throws InvalidInputError for an empty map.
  [[nodiscard]] ReferenceIndex index() const;

  [[nodiscard]] std::size_t size() const noexcept;
  [[nodiscard]] std::size_t voxels() const noexcept;
  [[nodiscard]] bool empty() const noexcept { return size() == 0; }
  [[nodiscard]] double voxel_size_m() const noexcept { return voxel_size_m_; }
  [[nodiscard]] std::size_t max_points_per_voxel() const noexcept { return max_points_; }
  /// The least distance between two points of a voxel: voxel_size_m / sqrt(max_points_per_voxel)
  /// (KISS-ICP's rule: N points spread over a voxel's surface lie about that far apart).
  [[nodiscard]] double spacing_m() const noexcept;
  void clear();

 private:
  double voxel_size_m_;
  std::size_t max_points_;
  std::unique_ptr<detail::VoxelHash> hash_;
};

}  // namespace sgdicp
