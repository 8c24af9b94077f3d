#pragma once
// The point-to-point cost of the paper and its analytic gradient w.r.t. theta (eq. 5-7, Alg. 1
// lines 9-10), as a convenience over cost.hpp. For a pair (s, r) the residual is
// e = R s + t - r. The paper's update direction is g = 1/(2m) * sum_i J_i^T e_i with
// J = [I | dR/droll s, dR/dpitch s, dR/dyaw s]; it is the exact gradient of
// F(theta) = 1/(4m) * sum_i ||e_i||^2. With this normalisation a fixed step alpha = 2 is a unit
// Newton step in translation, which is why the paper's alpha = 2 works.
#include <Eigen/Core>

#include "sgdicp/core/pose.hpp"
#include "sgdicp/costs/cost.hpp"

namespace sgdicp {

/// Accumulates g, F (and on request the Gauss-Newton matrix) of point-to-point pairs for one
/// mini-batch at a fixed pose.
class PointToPointGradient {
 public:
  explicit PointToPointGradient(const PoseVector& theta, bool with_hessian = false)
      : pose_(theta), accumulator_(KernelType::none, 1.0, with_hessian) {}

  /// The source point moved by the current pose.
  [[nodiscard]] Eigen::Vector3d transform(const Eigen::Vector3d& s) const {
    return pose_.transform(s);
  }

  /// Adds the pair (s, r), where moved = transform(s).
  void add(const Eigen::Vector3d& s, const Eigen::Vector3d& moved, const Eigen::Vector3d& r) {
    accumulator_.add_point_to_point(pose_.jacobian(s), moved - r);
  }

  [[nodiscard]] PoseVector gradient(std::size_t batch_size) const {
    return accumulator_.gradient(batch_size);
  }
  [[nodiscard]] double cost(std::size_t batch_size) const { return accumulator_.cost(batch_size); }
  [[nodiscard]] PoseMatrix hessian(std::size_t batch_size) const {
    return accumulator_.hessian(batch_size);
  }

 private:
  EulerPoseJacobian pose_;
  CostAccumulator accumulator_;
};

}  // namespace sgdicp
