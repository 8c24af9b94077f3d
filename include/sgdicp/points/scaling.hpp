#pragma once
// The paper's scaling of both clouds into [0, 1] (Section III-B, docs/design.md, "Scaling"): one
// common map p_s = (p - o) / k for both clouds, with o the lower corner of their joint bounding box
// and k its largest side, so rotations stay rotations and one step size fits every sensor.
#include <array>
#include <cmath>
#include <cstddef>

#include <Eigen/Core>

#include "sgdicp/core/enum_names.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp {

/// Where the scaled space has its origin, which is also the pivot of the rotation parameters.
enum class ScalingOrigin {
  lower_corner,  ///< the paper: points land in [0, 1]
  center,        ///< the centre of the joint box: points land in [-0.5, 0.5]
};

inline constexpr std::array<EnumName<ScalingOrigin>, 3> kScalingOriginNames{{
    {ScalingOrigin::lower_corner, "lower-corner"},
    {ScalingOrigin::center, "center"},
    {ScalingOrigin::lower_corner, "corner"},
}};
constexpr const auto& enum_names(ScalingOrigin) {
  return kScalingOriginNames;
}
constexpr std::string_view enum_noun(ScalingOrigin) {
  return "scaling origin";
}

/// The box of a cloud that sets the scale, and how many of its points it leaves out.
struct ScalingBox {
  BoundingBox box;
  std::size_t far_points = 0;  ///< points outside `box`
};

/// The box of the bulk of a cloud, robust to a few far points (spurious returns, sky points,
/// bad depth pixels) that would otherwise shrink everything else in the scaled space: the
/// bounding box of the points that lie near the bulk, where the bulk is the
/// box between the 1st and 99th percentiles of each coordinate (estimated on at most 4096
/// points spread over the cloud) and the bulk size its largest side, within two bulk sizes. A cloud
/// without far points gets its exact bounding box (docs/design.md, "Robust scaling").
[[nodiscard]] ScalingBox bulk_bounding_box(const PointCloud& cloud);
/// The same, given the cloud's whole box (BoundingBox::of), which a caller may have already.
[[nodiscard]] ScalingBox bulk_bounding_box(const PointCloud& cloud, const BoundingBox& whole);

class UnitCubeScaling {
 public:
  /// The map for the union of two boxes. Throws InvalidInputError if the union has zero extent.
  static UnitCubeScaling from_boxes(const BoundingBox& a, const BoundingBox& b,
                                    ScalingOrigin origin = ScalingOrigin::lower_corner) {
    BoundingBox joint = a;
    joint.extend(b.min);
    joint.extend(b.max);
    if (!joint.valid()) throw InvalidInputError("cannot scale: empty bounding box");
    const double side = (joint.max - joint.min).maxCoeff();
    if (!(side > 0.0) || !std::isfinite(side)) {
      throw InvalidInputError("cannot scale: the clouds have zero or non-finite extent");
    }
    const Eigen::Vector3d offset = origin == ScalingOrigin::lower_corner
                                       ? joint.min
                                       : Eigen::Vector3d(0.5 * (joint.min + joint.max));
    return UnitCubeScaling(offset, side);
  }

  UnitCubeScaling(const Eigen::Vector3d& offset, double scale) : offset_(offset), scale_(scale) {}

  [[nodiscard]] const Eigen::Vector3d& offset() const noexcept { return offset_; }
  /// Metres per scaled unit.
  [[nodiscard]] double scale() const noexcept { return scale_; }

  [[nodiscard]] Eigen::Vector3d to_scaled(const Eigen::Vector3d& p) const {
    return (p - offset_) / scale_;
  }
  /// A stored (single-precision) point, mapped in double.
  [[nodiscard]] Eigen::Vector3d to_scaled(const Eigen::Vector3f& p) const {
    return (p.cast<double>() - offset_) / scale_;
  }
  [[nodiscard]] Eigen::Vector3d to_metric(const Eigen::Vector3d& q) const {
    return scale_ * q + offset_;
  }

  /// A metric transform expressed in scaled space: R stays, t_s = (t + R o - o) / k.
  [[nodiscard]] Eigen::Matrix4d to_scaled(const Eigen::Matrix4d& T_metric) const {
    Eigen::Matrix4d out = T_metric;
    const Eigen::Matrix3d r = T_metric.topLeftCorner<3, 3>();
    out.topRightCorner<3, 1>() = (T_metric.topRightCorner<3, 1>() + r * offset_ - offset_) / scale_;
    return out;
  }
  /// Undoes the scaling on a transform found in scaled space: t = k t_s + o - R o.
  [[nodiscard]] Eigen::Matrix4d to_metric(const Eigen::Matrix4d& T_scaled) const {
    Eigen::Matrix4d out = T_scaled;
    const Eigen::Matrix3d r = T_scaled.topLeftCorner<3, 3>();
    out.topRightCorner<3, 1>() = scale_ * T_scaled.topRightCorner<3, 1>() + offset_ - r * offset_;
    return out;
  }

 private:
  Eigen::Vector3d offset_;
  double scale_;
};

}  // namespace sgdicp
