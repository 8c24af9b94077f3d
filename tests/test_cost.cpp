// Costs and robust kernels: every gradient equals a finite difference of its cost, every kernel
// weight equals the derivative of its rho and matches its textbook definition.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "sgdicp/costs/cost.hpp"
#include "sgdicp/costs/robust_kernel.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

using test::random_rotation;
using test::uniform;

constexpr KernelType kKernels[] = {KernelType::none, KernelType::huber, KernelType::cauchy,
                                   KernelType::geman_mcclure, KernelType::welsch};
constexpr CostType kCosts[] = {CostType::point_to_point, CostType::point_to_plane,
                               CostType::plane_to_plane};

TEST(RobustKernel, WeightIsTheDerivativeOfRho) {
  for (const KernelType k : kKernels) {
    for (const double c : {0.1, 1.0, 3.0}) {
      for (const double s : {1e-4, 0.005, 0.05, 0.5, 2.0, 9.0, 40.0}) {
        const double h = 1e-6 * std::max(1.0, s);
        const double numeric = (kernel_rho(k, s + h, c) - kernel_rho(k, s - h, c)) / (2.0 * h);
        EXPECT_NEAR(kernel_weight(k, s, c), numeric, 1e-6 * std::max(1.0, numeric))
            << to_string(k) << " s=" << s << " c=" << c;
      }
    }
  }
}

TEST(RobustKernel, MatchesTheDefinitions) {
  const double c = 0.7;
  for (const double r : {0.01, 0.3, 0.7, 1.5, 6.0}) {  // residual length; s = r^2
    const double s = r * r;
    EXPECT_DOUBLE_EQ(kernel_weight(KernelType::none, s, c), 1.0);
    EXPECT_NEAR(kernel_weight(KernelType::huber, s, c), r <= c ? 1.0 : c / r, 1e-15);
    EXPECT_NEAR(kernel_weight(KernelType::cauchy, s, c), 1.0 / (1.0 + r * r / (c * c)), 1e-15);
    EXPECT_NEAR(kernel_weight(KernelType::geman_mcclure, s, c),
                std::pow(c * c / (c * c + r * r), 2), 1e-15);
    EXPECT_NEAR(kernel_weight(KernelType::welsch, s, c), std::exp(-r * r / (c * c)), 1e-15);
    // rho ~ s for small residuals, and robust kernels grow slower than s beyond c.
    if (r > c) {
      for (const KernelType k :
           {KernelType::huber, KernelType::cauchy, KernelType::geman_mcclure, KernelType::welsch}) {
        EXPECT_LT(kernel_rho(k, s, c), s) << to_string(k);
      }
    }
  }
  for (const KernelType k : kKernels) {
    EXPECT_NEAR(kernel_rho(k, 1e-8, 1.0), 1e-8, 1e-12) << to_string(k);
    EXPECT_EQ(kernel_from_string(to_string(k)), k);
  }
  EXPECT_THROW((void)kernel_from_string("tukey"), InvalidSettingsError);
}

// A fixed set of pairs with everything each cost needs.
struct Pairs {
  std::vector<Eigen::Vector3d> s, r;
  std::vector<Eigen::Vector3f> normals;
  std::vector<Eigen::Matrix3f> ref_cov, src_cov;
};

Eigen::Matrix3f random_plane_covariance(std::mt19937_64& rng) {
  const Eigen::Matrix3d v = random_rotation(rng);
  return (v * Eigen::Vector3d(1e-3, 1.0, 1.0).asDiagonal() * v.transpose()).cast<float>();
}

Pairs random_pairs(std::mt19937_64& rng, int n) {
  Pairs p;
  for (int i = 0; i < n; ++i) {
    p.s.emplace_back(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5));
    p.r.emplace_back(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5));
    p.normals.push_back(random_rotation(rng).col(0).cast<float>());
    p.ref_cov.push_back(random_plane_covariance(rng));
    p.src_cov.push_back(random_plane_covariance(rng));
  }
  return p;
}

// Omega is frozen at the rotation of theta0 (as the solvers do within an iteration).
CostAccumulator accumulate(CostType cost, KernelType kernel, const PoseVector& theta,
                           const Eigen::Matrix3d& omega_rotation, const Pairs& p) {
  const EulerPoseJacobian pose(theta);
  CostAccumulator acc(kernel, 0.2, true);
  for (std::size_t i = 0; i < p.s.size(); ++i) {
    const Eigen::Vector3d e = pose.transform(p.s[i]) - p.r[i];
    if (cost == CostType::point_to_plane) {  // the registration's path for this cost
      acc.add(acc.plane_term(pose.jacobian(p.s[i]), e, p.normals[i].cast<double>()));
      continue;
    }
    const Eigen::Matrix3d omega =
        information_matrix(cost, p.normals[i], p.ref_cov[i], p.src_cov[i], omega_rotation);
    acc.add(pose.jacobian(p.s[i]), e, omega);
  }
  return acc;
}

TEST(Cost, PlaneTermIsTheGeneralTermWithOmegaNNT) {
  std::mt19937_64 rng(33);
  Pairs p = random_pairs(rng, 30);
  p.normals[3].setZero();  // a point without a plane: no information
  PoseVector theta;
  for (int i = 0; i < 6; ++i) theta[i] = uniform(rng, -0.6, 0.6);
  const EulerPoseJacobian pose(theta);
  for (const KernelType kernel : kKernels) {
    for (const bool with_hessian : {true, false}) {
      const CostAccumulator acc(kernel, 0.2, with_hessian);
      for (std::size_t i = 0; i < p.s.size(); ++i) {
        const PoseJacobianMatrix j = pose.jacobian(p.s[i]);
        const Eigen::Vector3d e = pose.transform(p.s[i]) - p.r[i];
        const Eigen::Vector3d n = p.normals[i].cast<double>();
        const auto fast = acc.plane_term(j, e, n);
        const auto general = acc.term(j, e, n * n.transpose());
        EXPECT_LT((fast.jte - general.jte).norm(), 1e-12) << to_string(kernel) << " pair " << i;
        EXPECT_NEAR(fast.rho, general.rho, 1e-12) << to_string(kernel) << " pair " << i;
        if (with_hessian) {
          EXPECT_LT((fast.jtj - general.jtj).norm(), 1e-12) << to_string(kernel) << " pair " << i;
        }
      }
      const auto none = acc.plane_term(pose.jacobian(p.s[3]), pose.transform(p.s[3]) - p.r[3],
                                       Eigen::Vector3d::Zero());
      EXPECT_EQ(none.jte, PoseVector::Zero());
      EXPECT_EQ(none.rho, 0.0);
    }
  }
}

TEST(Cost, GradientMatchesFiniteDifferencesForEveryCostAndKernel) {
  std::mt19937_64 rng(31);
  const Pairs p = random_pairs(rng, 40);
  for (int trial = 0; trial < 5; ++trial) {
    PoseVector theta;
    for (int i = 0; i < 6; ++i) theta[i] = uniform(rng, -0.6, 0.6);
    const Eigen::Matrix3d r0 = rotation_from_rpy(theta[3], theta[4], theta[5]);
    for (const CostType cost : kCosts) {
      for (const KernelType kernel : kKernels) {
        const PoseVector g = accumulate(cost, kernel, theta, r0, p).gradient(p.s.size());
        for (int k = 0; k < 6; ++k) {
          const double h = 1e-6;
          PoseVector plus = theta, minus = theta;
          plus[k] += h;
          minus[k] -= h;
          const double numeric = (accumulate(cost, kernel, plus, r0, p).cost(p.s.size()) -
                                  accumulate(cost, kernel, minus, r0, p).cost(p.s.size())) /
                                 (2.0 * h);
          EXPECT_NEAR(g[k], numeric, 1e-6 * std::max(1.0, std::abs(numeric)))
              << to_string(cost) << " " << to_string(kernel) << " parameter " << k;
        }
      }
    }
  }
}

TEST(Cost, GaussNewtonMatrixIsJTOmegaJ) {
  // Without a kernel and with zero residuals the Gauss-Newton matrix is the exact Hessian of F:
  // check it against finite differences of the gradient.
  std::mt19937_64 rng(32);
  Pairs p = random_pairs(rng, 30);
  PoseVector theta;
  for (int i = 0; i < 6; ++i) theta[i] = uniform(rng, -0.4, 0.4);
  const EulerPoseJacobian pose(theta);
  for (std::size_t i = 0; i < p.s.size(); ++i) p.r[i] = pose.transform(p.s[i]);  // e = 0
  const Eigen::Matrix3d r0 = pose.rotation();
  for (const CostType cost : kCosts) {
    const PoseMatrix h = accumulate(cost, KernelType::none, theta, r0, p).hessian(p.s.size());
    for (int k = 0; k < 6; ++k) {
      const double step = 1e-6;
      PoseVector plus = theta, minus = theta;
      plus[k] += step;
      minus[k] -= step;
      const PoseVector column =
          (accumulate(cost, KernelType::none, plus, r0, p).gradient(p.s.size()) -
           accumulate(cost, KernelType::none, minus, r0, p).gradient(p.s.size())) /
          (2.0 * step);
      EXPECT_LT((h.col(k) - column).norm(), 1e-6 * std::max(1.0, column.norm()))
          << to_string(cost) << " column " << k;
    }
  }
}

TEST(Cost, InformationMatricesAreWhatEachCostMeans) {
  const Eigen::Vector3f n(0, 0, 1);
  const Eigen::Matrix3f cov = Eigen::Vector3f(1, 1, 1e-3).asDiagonal();
  const Eigen::Matrix3d rot = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d in_plane(0.3, -0.2, 0.0), along_normal(0, 0, 0.1);
  // Point-to-point: the squared distance.
  const Eigen::Matrix3d pp = information_matrix(CostType::point_to_point, n, cov, cov, rot);
  EXPECT_DOUBLE_EQ((in_plane + along_normal).dot(pp * (in_plane + along_normal)), 0.14);
  // Point-to-plane: only the distance along the normal counts.
  const Eigen::Matrix3d pl = information_matrix(CostType::point_to_plane, n, cov, cov, rot);
  EXPECT_NEAR(in_plane.dot(pl * in_plane), 0.0, 1e-15);
  EXPECT_NEAR(along_normal.dot(pl * along_normal), 0.01, 1e-12);
  // Plane-to-plane: sliding along matching planes costs ~nothing, leaving them costs a lot.
  const Eigen::Matrix3d gg = information_matrix(CostType::plane_to_plane, n, cov, cov, rot);
  EXPECT_LT(in_plane.dot(gg * in_plane), 0.1);
  EXPECT_GT(along_normal.dot(gg * along_normal), 4.0);
}

}  // namespace
}  // namespace sgdicp
