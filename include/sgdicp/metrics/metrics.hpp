#pragma once
// Registration errors as the paper measures them (Section IV) and as the field reports them.
#include <cmath>

#include <Eigen/Core>

#include "sgdicp/core/pose.hpp"

namespace sgdicp {

/// ||t_est - t_gt||, in the unit of the transforms (metres).
[[nodiscard]] inline double translation_error(const Eigen::Matrix4d& T_est,
                                              const Eigen::Matrix4d& T_gt) {
  return (T_est.topRightCorner<3, 1>() - T_gt.topRightCorner<3, 1>()).norm();
}

/// The paper's rotational error: |d roll| + |d pitch| + |d yaw|, each wrapped to (-pi, pi], rad.
[[nodiscard]] inline double rotation_error_euler_sum(const Eigen::Matrix4d& T_est,
                                                     const Eigen::Matrix4d& T_gt) {
  const Eigen::Vector3d a = rpy_from_rotation(T_est.topLeftCorner<3, 3>());
  const Eigen::Vector3d b = rpy_from_rotation(T_gt.topLeftCorner<3, 3>());
  double sum = 0.0;
  for (int i = 0; i < 3; ++i) sum += std::abs(wrap_angle(a[i] - b[i]));
  return sum;
}

/// Geodesic angle of R_est^T R_gt (relative rotation error, RRE), rad in [0, pi].
[[nodiscard]] inline double rotation_error_geodesic(const Eigen::Matrix4d& T_est,
                                                    const Eigen::Matrix4d& T_gt) {
  const Eigen::Matrix3d d = T_est.topLeftCorner<3, 3>().transpose() * T_gt.topLeftCorner<3, 3>();
  // atan2 of (sin, cos) is accurate near 0 and pi where acos of the trace is not.
  const Eigen::Vector3d axis_sin(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));
  return std::atan2(0.5 * axis_sin.norm(), 0.5 * (d.trace() - 1.0));
}

}  // namespace sgdicp
