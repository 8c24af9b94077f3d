#pragma once
// The weighted least-squares rigid transform taking points a_i onto b_i (Kabsch / Umeyama 1991
// without scale): both sets centred on their weighted means, the SVD of the weighted
// cross-covariance, a reflection turned into the nearest rotation. Private to the library: the
// batch ICP's point-to-point step and the global registration's RANSAC fit with it.
#include <cstddef>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SVD>

namespace sgdicp::detail {

struct FitPair {
  Eigen::Vector3d a;  ///< moved onto b
  Eigen::Vector3d b;
  double weight = 1.0;
};

/// T minimising sum_i w_i |b_i - T a_i|^2 over pair(0) ... pair(n - 1) (each a FitPair; called
/// twice per pair). The weights must not all be 0.
template <class PairAt>
[[nodiscard]] Eigen::Matrix4d rigid_fit(std::size_t n, PairAt pair) {
  double w_sum = 0.0;
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const FitPair p = pair(i);
    w_sum += p.weight;
    ca += p.weight * p.a;
    cb += p.weight * p.b;
  }
  ca /= w_sum;
  cb /= w_sum;
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const FitPair p = pair(i);
    cross.noalias() += p.weight * (p.b - cb) * (p.a - ca).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = svd.matrixU() * d * svd.matrixV().transpose();
  T.topRightCorner<3, 1>() = cb - T.topLeftCorner<3, 3>() * ca;
  return T;
}

}  // namespace sgdicp::detail
