#include "sgdicp/core/point_cloud.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "core/checks.hpp"

namespace sgdicp {

namespace {

// The box of a whole cloud. The points as one flat array of x, y, z, read twelve floats (four
// points) at a time: Eigen's packet min and max keep twelve running extremes, lane j holding
// axis j % 3, folded per axis at the end. Per point with extend() it was 40 instructions per
// point (3 % of a registration on a Kinect frame). kCheck: `finite` says whether every
// coordinate is finite, from a sum of coordinate * 0 (NaN for an infinite or NaN one), in the
// same pass rather than a second one over the cloud.
template <bool kCheck>
BoundingBox box_of(const PointCloud& cloud, bool& finite) {
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  using Lanes = Eigen::Array<float, 12, 1>;
  Lanes low = Lanes::Constant(std::numeric_limits<float>::infinity());
  Lanes high = Lanes::Constant(-std::numeric_limits<float>::infinity());
  Lanes zero = Lanes::Zero();
  const float* coordinates = cloud.points.empty() ? nullptr : cloud.points.front().data();
  const std::size_t count = 3 * cloud.size();
  const std::size_t whole = count - count % Lanes::SizeAtCompileTime;
  for (std::size_t k = 0; k < whole; k += Lanes::SizeAtCompileTime) {
    const Eigen::Map<const Lanes> block(coordinates + k);
    low = low.min(block);
    high = high.max(block);
    if constexpr (kCheck) zero += block * 0.0F;
  }
  float tail_zero = 0.0F;
  for (std::size_t k = whole; k < count; ++k) {  // whole is a multiple of 3: lane k % 3
    const auto axis = static_cast<Eigen::Index>(k % 3);
    low[axis] = std::min(low[axis], coordinates[k]);
    high[axis] = std::max(high[axis], coordinates[k]);
    if constexpr (kCheck) tail_zero += coordinates[k] * 0.0F;
  }
  if constexpr (kCheck) finite = zero.isFinite().all() && std::isfinite(tail_zero);
  BoundingBox box;  // lanes no point reached hold +-inf, which the fold leaves out
  for (Eigen::Index j = 0; j < Lanes::SizeAtCompileTime; ++j) {
    box.min[j % 3] = std::min(box.min[j % 3], static_cast<double>(low[j]));
    box.max[j % 3] = std::max(box.max[j % 3], static_cast<double>(high[j]));
  }
  return box;
}

}  // namespace

BoundingBox BoundingBox::of(const PointCloud& cloud) {
  bool unused = true;
  return box_of<false>(cloud, unused);
}

namespace detail {

CloudExtent extent_of(const PointCloud& cloud, const char* what) {
  bool finite = true;
  CloudExtent extent{box_of<true>(cloud, finite), 0.0F};
  // The slow pass only to name the first non-finite point (it throws).
  if (!finite) (void)largest_coordinate(cloud, what);
  if (!cloud.empty()) {
    extent.largest = static_cast<float>(
        std::max(extent.box.min.cwiseAbs().maxCoeff(), extent.box.max.cwiseAbs().maxCoeff()));
  }
  return extent;
}

}  // namespace detail

PointCloud rebased(const PointCloud& cloud, const Eigen::Vector3d& origin_m) {
  // The identity between the frames: only the origin the points are stored from changes.
  return transformed(cloud, Eigen::Matrix4d::Identity(), origin_m);
}

PointCloud transformed(const PointCloud& cloud, const Eigen::Matrix4d& T,
                       const Eigen::Vector3d& origin_m) {
  const Eigen::Matrix4d T_stored = between_stored(T, cloud.origin_m, origin_m);
  const Eigen::Matrix3d r = T_stored.topLeftCorner<3, 3>();
  const Eigen::Vector3d t = T_stored.topRightCorner<3, 1>();
  const Eigen::Matrix3f r_f = r.cast<float>();
  PointCloud out = cloud;
  out.origin_m = origin_m;
  for (auto& p : out.points) {
    const Eigen::Vector3d moved = r * p.cast<double>() + t;
    p = {to_float_saturating(moved.x()), to_float_saturating(moved.y()),
         to_float_saturating(moved.z())};
  }
  for (auto& n : out.normals) n = r_f * n;
  for (auto& c : out.covariances) c = r_f * c * r_f.transpose();
  return out;
}

}  // namespace sgdicp
