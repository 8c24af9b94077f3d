// Odometry in a fixed map (Localizer, localizer.hpp): the map taken, built into the voxels at the
// first frame, and the starts before a frame is registered in it.
#include <algorithm>
#include <stdexcept>
#include <utility>

#include "sgdicp/core/error.hpp"
#include "sgdicp/odometry/localizer.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"
#include "util/stopwatch.hpp"

namespace sgdicp {

void Odometry::fix_map(PointCloud map, std::optional<Eigen::Matrix4d> T_map_first_frame) {
  if (!poses_.empty()) throw std::logic_error("Odometry::fix_map after the first frame");
  const bool any_finite = std::any_of(map.points.begin(), map.points.end(),
                                      [](const Eigen::Vector3f& p) { return p.allFinite(); });
  if (!any_finite) throw InvalidInputError("the map to localize in has no finite point");
  if (!map.origin_m.isZero()) {
    throw InvalidInputError(
        "the map to localize in is georeferenced (coordinates beyond 16 km): not supported yet; "
        "move it near its origin first");
  }
  if (T_map_first_frame && !T_map_first_frame->allFinite()) {
    throw InvalidInputError("the first frame's pose in the map is not finite");
  }
  fixed_map_ = std::move(map);
  T_map_first_frame_ = T_map_first_frame;
  localizing_ = true;
}

// The map's points into the voxels (the local map's admission rule: at most N per voxel, spaced),
// with the surfaces the cost reads, estimated on the whole map: built once, never changed.
void Odometry::build_fixed_map() {
  const detail::Stopwatch stopwatch;
  const PointCloud cloud = std::move(*fixed_map_);
  fixed_map_.reset();
  const bool covariances = needs_covariances(cost());
  if (!covariances && !needs_reference_normals(cost())) {
    map_->add(cloud);
  } else {
    NeighborhoodSettings surfaces = neighborhood();
    surfaces.num_threads = threads();
    map_->add(subset_with_surfaces(cloud, map_->admitted(cloud), surfaces, covariances));
  }
  fixed_map_build_ms_ = stopwatch.elapsed_ms();
}

// Every start, but in a fixed map before any frame is registered: there, without a pose to start
// from, the global registration alone; with one (fix_map), the frame from it, then the global one.
std::vector<FrameStart> Odometry::starts() const {
  if (!registered_any_ && localizing_) {
    if (T_map_first_frame_) return {FrameStart::prediction, FrameStart::global};
    return {FrameStart::global};
  }
  return {FrameStart::prediction, FrameStart::last_pose, FrameStart::global,
          FrameStart::wide_basin};
}

}  // namespace sgdicp
