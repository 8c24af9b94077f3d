#include "sgdicp/points/scaling.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace sgdicp {
namespace {

constexpr std::size_t kSamples = 4096;
constexpr double kLowQuantile = 0.01;
constexpr double kHighQuantile = 0.99;
// How far beyond the bulk, in bulk sizes, a point still counts as part of the scene. Measured
// over every cloud of ../shared/data: at most 0.88 bulk sizes (the bunny; KITTI 0.58), so real
// scenes keep their exact bounding box (docs/design.md).
constexpr double kMarginInBulkSizes = 2.0;

// The q-quantile of `values` (reordered), rounding the rank away from the median so that a
// cloud of a few points keeps its extremes.
float quantile(std::vector<float>& values, double q) {
  const double exact_rank = q * static_cast<double>(values.size() - 1);
  const auto rank =
      static_cast<std::ptrdiff_t>(q < 0.5 ? std::floor(exact_rank) : std::ceil(exact_rank));
  std::nth_element(values.begin(), values.begin() + rank, values.end());
  return values[static_cast<std::size_t>(rank)];
}

// The 1st-99th percentile box of a spread sample of the cloud.
BoundingBox percentile_box(const PointCloud& cloud) {
  const std::size_t n = cloud.size();
  const std::size_t count = std::min(n, kSamples);
  std::vector<float> coordinate(count);
  BoundingBox bulk;
  for (Eigen::Index axis = 0; axis < 3; ++axis) {
    for (std::size_t k = 0; k < count; ++k) coordinate[k] = cloud.points[k * n / count][axis];
    bulk.min[axis] = quantile(coordinate, kLowQuantile);
    bulk.max[axis] = quantile(coordinate, kHighQuantile);
  }
  return bulk;
}

}  // namespace

ScalingBox bulk_bounding_box(const PointCloud& cloud) {
  return bulk_bounding_box(cloud, BoundingBox::of(cloud));
}

ScalingBox bulk_bounding_box(const PointCloud& cloud, const BoundingBox& whole) {
  ScalingBox result;
  if (cloud.empty()) return result;
  const BoundingBox bulk = percentile_box(cloud);
  const double bulk_size = (bulk.max - bulk.min).maxCoeff();
  if (!(bulk_size > 0.0)) {  // the bulk is one point: no size to measure "far" by
    result.box = whole;
    return result;
  }
  const double margin = kMarginInBulkSizes * bulk_size;
  const Eigen::Vector3d low = bulk.min.array() - margin;
  const Eigen::Vector3d high = bulk.max.array() + margin;
  // Most clouds have no far point: their whole box is the answer (the per-point test below was
  // 3 % of a registration on a Kinect frame).
  if ((whole.min.array() >= low.array()).all() && (whole.max.array() <= high.array()).all()) {
    result.box = whole;
    return result;
  }
  for (const auto& point : cloud.points) {
    const Eigen::Vector3d p = point.cast<double>();
    if ((p.array() >= low.array()).all() && (p.array() <= high.array()).all()) {
      result.box.extend(p);
    } else {
      ++result.far_points;
    }
  }
  return result;
}

}  // namespace sgdicp
