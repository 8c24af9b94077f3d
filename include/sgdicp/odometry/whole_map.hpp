#pragma once
// The whole map of an odometry run: every registered frame's points in the first frame's
// coordinates, thinned to one centroid per voxel as they come in. Unlike the local VoxelMap, which
// the registration uses and which forgets what lies behind the sensor, it keeps everything; its
// memory grows with the space covered (the voxels it holds), not with the number of frames: a
// place seen again adds no voxel. docs/localization.md, "The whole map".
#include <cstddef>
#include <memory>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp {

class WholeMap {
 public:
  /// voxel_size_m > 0 and finite; InvalidSettingsError otherwise.
  explicit WholeMap(double voxel_size_m);
  ~WholeMap();
  WholeMap(const WholeMap& other);
  WholeMap& operator=(const WholeMap& other);
  WholeMap(WholeMap&&) noexcept;
  WholeMap& operator=(WholeMap&&) noexcept;

  /// Adds the points of `frame` moved by T_map_frame (its origin_m included), each into the
  /// centroid of its voxel. Non-finite points, and points so far out (beyond
  /// kLargestCoordinate_m) that they are no place, are skipped: a frame never fails here.
  void add(const PointCloud& frame, const Eigen::Matrix4d& T_map_frame);

  /// The same map on a coarser grid (the odometry's voxel grew): each centroid moves into the
  /// new voxel that holds it, weighted by the points it stands for. A finer size is refused
  /// (InvalidSettingsError): what was merged cannot be split.
  void regrid(double voxel_size_m);

  /// One point per voxel, the centroid of the points that fell in it, in the order the voxels
  /// were first reached; stored relative to a georeferencing_origin of the first point, so that
  /// a map kilometres wide keeps millimetres.
  [[nodiscard]] PointCloud cloud() const;

  [[nodiscard]] std::size_t size() const noexcept;  ///< voxels (= points of cloud())
  [[nodiscard]] bool empty() const noexcept { return size() == 0; }
  [[nodiscard]] double voxel_size_m() const noexcept { return voxel_size_m_; }
  /// Bytes held (the table and the centroids), for the docs' memory figures and the tests.
  [[nodiscard]] std::size_t memory_bytes() const noexcept;

 private:
  struct Voxels;
  double voxel_size_m_;
  std::unique_ptr<Voxels> voxels_;
};

}  // namespace sgdicp
