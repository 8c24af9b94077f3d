#pragma once
// The pose model of the paper: theta = (x, y, z, roll, pitch, yaw) and p' = R p + t with
// R = Rz(yaw) * Ry(pitch) * Rx(roll) (paper eq. 2; docs/design.md, "Pose model").
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>

namespace sgdicp {

/// Pose parameters (x, y, z, roll, pitch, yaw); translation in the unit of the points, angles in
/// rad.
using PoseVector = Eigen::Matrix<double, 6, 1>;

/// Wraps an angle to (-pi, pi].
[[nodiscard]] inline double wrap_angle(double a) {
  a = std::remainder(a, 2.0 * std::numbers::pi);  // [-pi, pi]
  return a <= -std::numbers::pi ? a + 2.0 * std::numbers::pi : a;
}

/// R = Rz(yaw) * Ry(pitch) * Rx(roll).
[[nodiscard]] inline Eigen::Matrix3d rotation_from_rpy(double roll, double pitch, double yaw) {
  const double cr = std::cos(roll), sr = std::sin(roll);
  const double cp = std::cos(pitch), sp = std::sin(pitch);
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  Eigen::Matrix3d r;
  r << cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,  //
      sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,   //
      -sp, cp * sr, cp * cr;
  return r;
}

/// The (roll, pitch, yaw) of a rotation, with pitch in [-pi/2, pi/2]. At gimbal lock
/// (|pitch| = pi/2) roll is set to 0 and yaw carries the remaining rotation.
[[nodiscard]] inline Eigen::Vector3d rpy_from_rotation(const Eigen::Matrix3d& r) {
  // atan2 of (sin, cos) keeps full precision near the lock, where asin(-r20) does not.
  const double cos_pitch = std::hypot(r(0, 0), r(1, 0));
  const double pitch = std::atan2(-r(2, 0), cos_pitch);
  if (cos_pitch < 1e-10) return {0.0, pitch, std::atan2(-r(0, 1), r(1, 1))};
  return {std::atan2(r(2, 1), r(2, 2)), pitch, std::atan2(r(1, 0), r(0, 0))};
}

/// dR/droll, dR/dpitch, dR/dyaw of rotation_from_rpy (the matrices of paper eq. 7).
[[nodiscard]] inline std::array<Eigen::Matrix3d, 3> rotation_derivatives(double roll, double pitch,
                                                                         double yaw) {
  const double cr = std::cos(roll), sr = std::sin(roll);
  const double cp = std::cos(pitch), sp = std::sin(pitch);
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  Eigen::Matrix3d rx, ry, rz, drx, dry, drz;
  rx << 1, 0, 0, 0, cr, -sr, 0, sr, cr;
  ry << cp, 0, sp, 0, 1, 0, -sp, 0, cp;
  rz << cy, -sy, 0, sy, cy, 0, 0, 0, 1;
  drx << 0, 0, 0, 0, -sr, -cr, 0, cr, -sr;
  dry << -sp, 0, cp, 0, 0, 0, -cp, 0, -sp;
  drz << -sy, -cy, 0, cy, -sy, 0, 0, 0, 0;
  return {rz * ry * drx, rz * dry * rx, drz * ry * rx};
}

[[nodiscard]] inline Eigen::Matrix4d transform_from_pose(const PoseVector& theta) {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t.topLeftCorner<3, 3>() = rotation_from_rpy(theta[3], theta[4], theta[5]);
  t.topRightCorner<3, 1>() = theta.head<3>();
  return t;
}

[[nodiscard]] inline PoseVector pose_from_transform(const Eigen::Matrix4d& t) {
  PoseVector theta;
  theta.head<3>() = t.topRightCorner<3, 1>();
  theta.tail<3>() = rpy_from_rotation(t.topLeftCorner<3, 3>());
  return theta;
}

/// True when t is finite, its last row is (0 0 0 1) and its 3x3 block is a rotation
/// (orthonormal within tol, determinant +1).
[[nodiscard]] inline bool is_rigid_transform(const Eigen::Matrix4d& t, double tol = 1e-4) {
  if (!t.allFinite()) return false;
  if ((t.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > tol) return false;
  const Eigen::Matrix3d r = t.topLeftCorner<3, 3>();
  return (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tol &&
         std::abs(r.determinant() - 1.0) <= tol;
}

/// The nearest rotation (in the Frobenius sense) to the 3x3 block of t, keeping its translation.
/// Used to clean up matrices read from text files with few digits.
[[nodiscard]] inline Eigen::Matrix4d orthonormalized(const Eigen::Matrix4d& t) {
  const Eigen::Matrix3d r = t.topLeftCorner<3, 3>();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  Eigen::Matrix4d out = t;
  out.topLeftCorner<3, 3>() = svd.matrixU() * d * svd.matrixV().transpose();
  out.row(3) << 0, 0, 0, 1;
  return out;
}

}  // namespace sgdicp
