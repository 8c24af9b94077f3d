// Tests of the smallest eigenpair of a 3x3 covariance (src/surfaces/symmetric_eigen.hpp) against
// Eigen's iterative solver (an independent method: QR iterations on the tridiagonal form).
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "surfaces/symmetric_eigen.hpp"

namespace sgdicp::detail {
namespace {

// R diag(spread) R^T for a random rotation R, scaled by `scale`.
Eigen::Matrix3d covariance_of(const Eigen::Vector3d& spread, double scale, std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::Matrix3d r = Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng))
                                .normalized()
                                .toRotationMatrix();
  return scale * r * spread.asDiagonal() * r.transpose();
}

// The characteristic polynomial p's coefficients carry rounding errors of ~eps lambda2^3, which
// move its smallest root by ~eps lambda2^3 / p'(lambda0) = eps lambda2^3 / ((lambda1 - lambda0)
// (lambda2 - lambda0)), and by ~cbrt(eps) lambda2 at most (a triple root): the bound below, as
// for any closed form. The vector turns by that over the gap lambda1 - lambda0.
void expect_as_iterative(const Eigen::Matrix3d& a) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> reference(a);
  const SmallestEigenpair got = smallest_eigenpair(a);
  const Eigen::Vector3d& want = reference.eigenvalues();
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  const double slope = (want[1] - want[0]) * (want[2] - want[0]);
  const double smallest_error =
      64.0 * kEps * want[2] +
      std::min(4.0 * std::cbrt(kEps) * want[2], 64.0 * kEps * std::pow(want[2], 3) / slope);
  EXPECT_NEAR(got.values[0], want[0], smallest_error) << a;
  EXPECT_NEAR(got.values[1], want[1], smallest_error + 1e-7 * want[2]) << a;
  EXPECT_NEAR(got.values[2], want[2], smallest_error + 1e-7 * want[2]) << a;
  // The vector is defined (to sign) where the two smallest values are apart: where a caller
  // uses it (describe_covariance, a gap above 1e-3 of the largest).
  const double gap = want[1] - want[0];
  if (gap > 1e-3 * want[2]) {
    EXPECT_NEAR(got.vector.norm(), 1.0, 1e-12);
    const double sine = got.vector.cross(reference.eigenvectors().col(0)).norm();
    EXPECT_LT(sine, smallest_error / gap) << a;
  }
}

TEST(SymmetricEigen, SurfacesLinesAndBlobsAsTheIterativeSolver) {
  std::mt19937_64 rng(20261204);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 3000; ++i) {
    // Flat (a surface's neighbourhood), nearly flat, lines, blobs, from 1e-12 to 1e6.
    const double thin = std::pow(10.0, -8.0 * unit(rng));
    const double middle = i % 3 == 0 ? std::pow(10.0, -7.0 * unit(rng)) : 0.2 + unit(rng);
    const double scale = std::pow(10.0, -12.0 + 18.0 * unit(rng));
    expect_as_iterative(covariance_of({thin * middle, middle, 1.0}, scale, rng));
  }
}

TEST(SymmetricEigen, RepeatedValuesKeepTheirValues) {
  std::mt19937_64 rng(7);
  expect_as_iterative(covariance_of({1.0, 1.0, 1.0}, 2.0, rng));   // a sphere
  expect_as_iterative(covariance_of({0.0, 1.0, 1.0}, 1e-3, rng));  // a disc
  expect_as_iterative(covariance_of({0.0, 0.0, 1.0}, 1e3, rng));   // a line
  const SmallestEigenpair plane = smallest_eigenpair(Eigen::Vector3d(4.0, 0.0, 9.0).asDiagonal());
  EXPECT_LT((plane.values - Eigen::Vector3d(0.0, 4.0, 9.0)).norm(), 1e-14);
  EXPECT_DOUBLE_EQ(std::abs(plane.vector.y()), 1.0);
}

TEST(SymmetricEigen, ZeroAndNonFiniteMatrices) {
  const SmallestEigenpair zero = smallest_eigenpair(Eigen::Matrix3d::Zero());
  EXPECT_EQ(zero.values, Eigen::Vector3d::Zero());
  EXPECT_EQ(zero.vector, Eigen::Vector3d::Zero());
  Eigen::Matrix3d bad = Eigen::Matrix3d::Identity();
  bad(1, 2) = bad(2, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(smallest_eigenpair(bad).values.allFinite());
  bad(1, 2) = bad(2, 1) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(smallest_eigenpair(bad).values.allFinite());
}

}  // namespace
}  // namespace sgdicp::detail
