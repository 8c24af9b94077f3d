#pragma once
// The point-to-point cost of the paper and its analytic gradient w.r.t. theta (eq. 5-7, Alg. 1
// lines 9-10). For a pair (s, r) the residual is e = R s + t - r. The paper's update direction
// is g = 1/(2m) * sum_i J_i^T e_i with J = [I | dR/droll s, dR/dpitch s, dR/dyaw s]; it is the
// exact gradient of F(theta) = 1/(4m) * sum_i ||e_i||^2. With this normalisation a fixed step
// alpha = 2 is a unit Newton step in translation, which is why the paper's alpha = 2 works.
#include <array>

#include <Eigen/Core>

#include "sgdicp/pose.hpp"

namespace sgdicp {

using PoseMatrix = Eigen::Matrix<double, 6, 6>;

/// Accumulates sum_i J_i^T e_i and sum_i ||e_i||^2 (and, on request, the Gauss-Newton matrix
/// sum_i J_i^T J_i) for one mini-batch at a fixed pose.
class PointToPointGradient {
 public:
  explicit PointToPointGradient(const PoseVector& theta, bool with_hessian = false)
      : with_hessian_(with_hessian),
        rotation_(rotation_from_rpy(theta[3], theta[4], theta[5])),
        translation_(theta.head<3>()),
        d_rotation_(rotation_derivatives(theta[3], theta[4], theta[5])) {}

  /// The source point moved by the current pose.
  [[nodiscard]] Eigen::Vector3d transform(const Eigen::Vector3d& s) const {
    return rotation_ * s + translation_;
  }

  /// Adds the pair (s, r), where moved = transform(s).
  void add(const Eigen::Vector3d& s, const Eigen::Vector3d& moved, const Eigen::Vector3d& r) {
    const Eigen::Vector3d e = moved - r;
    Eigen::Matrix<double, 3, 6> j;
    j.leftCols<3>().setIdentity();
    for (int k = 0; k < 3; ++k) j.col(3 + k) = d_rotation_[k] * s;
    jte_.noalias() += j.transpose() * e;
    if (with_hessian_) jtj_.noalias() += j.transpose() * j;
    squared_error_ += e.squaredNorm();
  }

  /// g = 1/(2m) sum J^T e, the gradient of F = 1/(4m) sum ||e||^2.
  [[nodiscard]] PoseVector gradient(std::size_t batch_size) const {
    return jte_ / (2.0 * static_cast<double>(batch_size));
  }
  /// F = 1/(4m) sum ||e||^2.
  [[nodiscard]] double cost(std::size_t batch_size) const {
    return squared_error_ / (4.0 * static_cast<double>(batch_size));
  }
  [[nodiscard]] double sum_squared_error() const noexcept { return squared_error_; }
  /// Gauss-Newton approximation of the Hessian of F: 1/(2m) sum J^T J (zero unless requested).
  [[nodiscard]] PoseMatrix hessian(std::size_t batch_size) const {
    return jtj_ / (2.0 * static_cast<double>(batch_size));
  }

 private:
  bool with_hessian_;
  Eigen::Matrix3d rotation_;
  Eigen::Vector3d translation_;
  std::array<Eigen::Matrix3d, 3> d_rotation_;
  PoseVector jte_ = PoseVector::Zero();
  PoseMatrix jtj_ = PoseMatrix::Zero();
  double squared_error_ = 0.0;
};

}  // namespace sgdicp
