#pragma once
// Localization in a map made before: each frame registered to a fixed map (a cloud: an odometry
// run's --map-out, or any PLY/PCD map), never extended. The odometry's pipeline with its map
// fixed: the map's voxels and surfaces are built once, at the first frame; that frame is placed by
// the global registration (or from a given pose), every later one from the motion model's
// prediction, with the odometry's retries (the last pose, the global registration, the wide
// basin). A frame whose best registration overlaps the map doubtfully (the map does not cover
// what it sees) is lost, not placed, and the global registration re-localizes the frames after it
// once the map is seen again. docs/localization.md, "Localization".
#include <optional>
#include <string_view>
#include <utility>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/odometry/odometry.hpp"

namespace sgdicp {

/// An Odometry whose map is fixed: poses (FrameReport::T_first_frame, poses()) are T_map_frame,
/// in the map's coordinates. The settings are the odometry's; the voxel is derived from the first
/// frame's range as there (the map is thinned into it: at most max_points_per_voxel points per
/// voxel).
class Localizer : public Odometry {
 public:
  /// `map` in its own coordinates, metres. T_map_first_frame: where the first frame is in the map
  /// (none: the global registration places it). Throws InvalidInputError for a map without a
  /// point or georeferenced (not supported yet), or a non-finite pose; InvalidSettingsError as
  /// Odometry's constructor.
  explicit Localizer(PointCloud map,
                     std::optional<Eigen::Matrix4d> T_map_first_frame = std::nullopt,
                     const OdometrySettings& settings = {}, std::string_view method = "sgd",
                     std::optional<SgdSettings> sgd = std::nullopt,
                     std::optional<BatchSettings> batch = std::nullopt)
      : Odometry(settings, method, std::move(sgd), std::move(batch)) {
    fix_map(std::move(map), T_map_first_frame);
  }

  /// The time the map's voxels and surfaces took to build (at the first frame), ms; 0 before.
  [[nodiscard]] double map_build_ms() const noexcept { return fixed_map_build_ms(); }
};

}  // namespace sgdicp
