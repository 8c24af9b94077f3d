#pragma once
// The eigenvalues and the smallest eigenvector of a symmetric positive semi-definite 3x3 matrix:
// what a surface's normal needs (private to the library).
//
// Written here because Eigen's closed form (SelfAdjointEigenSolver::computeDirect) finds the roots
// with atan2, cos and sin and then every eigenvector: ~155 ns a matrix, against ~75 ns for this
// (a loop over 200k surface covariances; 8-10 % of a Kinect registration before, 5 % after),
// and the block surfaces solve one matrix per voxel (~20k on a dense frame). The smallest
// root comes from Newton's method on the characteristic
// polynomial started at 0, the other two from the remaining quadratic, the eigenvector from the
// largest cross product of two rows of A - lambda_0 I.
#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sgdicp::detail {

struct SmallestEigenpair {
  Eigen::Vector3d values;  ///< ascending
  Eigen::Vector3d vector;  ///< unit, for values[0]; zero when the matrix has no clear null line
};

/// For a symmetric positive semi-definite `a`. The characteristic polynomial's rounding moves
/// the smallest eigenvalue by ~eps l2^3 / ((l1 - l0) (l2 - l0)) (l0 <= l1 <= l2 the values): a
/// few ulps of l2 on a surface's covariance, ~sqrt(eps) l2 where l0 = l1 (a line) and ~cbrt(eps)
/// l2 where all three are equal (a sphere). The other two follow it, and where they are nearly
/// equal carry ~sqrt(eps) l2 more. The vector turns by ~(that error) / (l1 - l0) radians:
/// callers that need it where the two smallest values are close solve those matrices
/// iteratively (describe_covariance). A non-finite entry gives NaN values.
inline SmallestEigenpair smallest_eigenpair(const Eigen::Matrix3d& a) {
  if (!a.allFinite()) {
    return {Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()),
            Eigen::Vector3d::Zero()};
  }
  // Scaled to a largest entry of 1, so that the cubic's coefficients neither overflow nor
  // underflow.
  const double scale = a.cwiseAbs().maxCoeff();
  if (scale == 0.0) return {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  const Eigen::Matrix3d m = a * (1.0 / scale);
  const double xx = m(0, 0), xy = m(0, 1), xz = m(0, 2), yy = m(1, 1), yz = m(1, 2), zz = m(2, 2);
  // det(lambda I - m) = lambda^3 - c2 lambda^2 + c1 lambda - c0.
  const double c2 = xx + yy + zz;
  const double c1 = xx * yy - xy * xy + xx * zz - xz * xz + yy * zz - yz * yz;
  const double c0 = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
  // Left of its smallest root the cubic rises and is concave (its roots are real and >= 0, and
  // lambda0 <= c2 / 3 where the second derivative changes sign): Newton's steps from 0 never pass
  // the root and shrink quadratically near a simple one (three on a surface's covariance).
  double lambda0 = 0.0;
  for (int step = 0; step < 100; ++step) {
    const double p = ((lambda0 - c2) * lambda0 + c1) * lambda0 - c0;
    const double slope = (3.0 * lambda0 - 2.0 * c2) * lambda0 + c1;
    if (!(slope > 0.0)) break;  // a multiple root at lambda0, or rounding past it
    const double delta = -p / slope;
    if (!(delta > 0.0)) break;
    lambda0 += delta;
    if (!(delta > 1e-15 * c2)) break;
  }
  // The other two from the remaining quadratic: lambda1 + lambda2 = c2 - lambda0 and
  // lambda1 lambda2 = c1 - lambda0 (lambda1 + lambda2); the smaller as product / larger, without
  // the cancellation of a difference.
  const double sum = c2 - lambda0;
  const double product = std::max(0.0, c1 - lambda0 * sum);
  const double lambda2 = 0.5 * sum + std::sqrt(std::max(0.0, 0.25 * sum * sum - product));
  const double lambda1 = lambda2 > 0.0 ? std::clamp(product / lambda2, lambda0, lambda2) : lambda0;

  Eigen::Matrix3d shifted = m;
  shifted.diagonal().array() -= lambda0;
  const Eigen::Vector3d r0 = shifted.row(0).transpose();
  const Eigen::Vector3d r1 = shifted.row(1).transpose();
  const Eigen::Vector3d r2 = shifted.row(2).transpose();
  const Eigen::Vector3d c01 = r0.cross(r1);
  const Eigen::Vector3d c02 = r0.cross(r2);
  const Eigen::Vector3d c12 = r1.cross(r2);
  const double n01 = c01.squaredNorm();
  const double n02 = c02.squaredNorm();
  const double n12 = c12.squaredNorm();
  const Eigen::Vector3d& largest = n01 >= n02 && n01 >= n12 ? c01 : (n02 >= n12 ? c02 : c12);
  const double norm = largest.norm();
  const Eigen::Vector3d vector =
      norm > 0.0 ? Eigen::Vector3d(largest / norm) : Eigen::Vector3d::Zero();
  return {Eigen::Vector3d(lambda0, lambda1, lambda2) * scale, vector};
}

}  // namespace sgdicp::detail
