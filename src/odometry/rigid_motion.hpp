#pragma once
// Rigid-motion helpers of the odometry's parts (private).
#include <algorithm>
#include <cmath>

#include <Eigen/Core>

namespace sgdicp::detail {

/// The angle of T's rotation, radians (from its trace).
inline double rotation_angle_rad(const Eigen::Matrix4d& T) {
  const double c = std::clamp((T.topLeftCorner<3, 3>().trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

/// T^-1 of a rigid transform.
inline Eigen::Matrix4d rigid_inverse(const Eigen::Matrix4d& T) {
  Eigen::Matrix4d out = Eigen::Matrix4d::Identity();
  out.topLeftCorner<3, 3>() = T.topLeftCorner<3, 3>().transpose();
  out.topRightCorner<3, 1>() = -out.topLeftCorner<3, 3>() * T.topRightCorner<3, 1>();
  return out;
}

}  // namespace sgdicp::detail
