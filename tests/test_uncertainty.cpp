// Tests of the pose uncertainty (uncertainty.hpp): the Jacobians against finite differences, the
// Laplace covariance against the analytic covariance of a problem with known noise, SGLD's
// reproducibility and its agreement with Laplace, SVGD (one particle = Adam descent, the kernel's
// spread, the modes of a symmetric object), the free directions of degenerate scenes, and the
// settings' checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <numeric>
#include <random>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include "sgdicp/costs/cost.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/registration/settings.hpp"
#include "sgdicp/uncertainty/uncertainty.hpp"
#include "test_support.hpp"

namespace {

using namespace sgdicp;
using sgdicp::test::box_surface;
using sgdicp::test::make_transform;
using sgdicp::test::uniform;

constexpr double kNoise_m = 0.001;

PoseVector random_pose(std::mt19937_64& rng) {
  PoseVector theta;
  for (int k = 0; k < 6; ++k) theta[k] = uniform(rng, -0.8, 0.8);
  return theta;
}

TEST(UncertaintyJacobian, EulerJacobianMatchesFiniteDifferences) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseVector theta = random_pose(rng);
    const Eigen::Vector3d s(uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -2, 2));
    const PoseJacobianMatrix j = EulerPoseJacobian(theta).jacobian(s);
    for (int k = 0; k < 6; ++k) {
      PoseVector up = theta, down = theta;
      up[k] += 1e-6;
      down[k] -= 1e-6;
      const Eigen::Vector3d fd =
          (EulerPoseJacobian(up).transform(s) - EulerPoseJacobian(down).transform(s)) / 2e-6;
      EXPECT_LT((j.col(k) - fd).norm(), 1e-8) << "column " << k;
    }
  }
}

// xi = Log(T_hat^-1 T(theta)), translation first, by the exact SO(3) logarithm.
PoseVector right_log(const PoseVector& hat, const PoseVector& theta) {
  const Eigen::Matrix4d d = transform_from_pose(hat).inverse() * transform_from_pose(theta);
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(d.topLeftCorner<3, 3>()));
  PoseVector xi;
  xi.head<3>() = d.topRightCorner<3, 1>();  // first order in the rotation: enough here
  xi.tail<3>() = aa.angle() * aa.axis();
  return xi;
}

TEST(UncertaintyJacobian, Se3JacobianMatchesFiniteDifferencesOfTheLogarithm) {
  std::mt19937_64 rng(8);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseVector theta = random_pose(rng);
    const PoseMatrix j = se3_jacobian(theta);
    for (int k = 0; k < 6; ++k) {
      PoseVector up = theta, down = theta;
      up[k] += 1e-6;
      down[k] -= 1e-6;
      const PoseVector fd = (right_log(theta, up) - right_log(theta, down)) / 2e-6;
      EXPECT_LT((j.col(k) - fd).norm(), 1e-6) << "column " << k;
    }
  }
}

// Points spread through a 1 m box (about 7 cm apart, far more than the 1 mm noise), so that the
// nearest neighbour is the true partner: the least-squares covariance is then known exactly.
PointCloud box_points(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    cloud.points.emplace_back(static_cast<float>(uniform(rng, 0, 1)),
                              static_cast<float>(uniform(rng, 0, 1.5)),
                              static_cast<float>(uniform(rng, 0, 0.7)));
  }
  return cloud;
}

// The source: the reference moved by T_gt^-1 with Gaussian noise on every coordinate.
PointCloud noisy_source(const PointCloud& reference, const Eigen::Matrix4d& T_gt, double noise_m,
                        std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m);
  const Eigen::Matrix4d T_inv = T_gt.inverse();
  PointCloud source;
  for (const auto& p : reference.points) {
    const Eigen::Vector3d q = T_inv.topLeftCorner<3, 3>() * p.cast<double>() +
                              T_inv.topRightCorner<3, 1>() +
                              Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    source.points.push_back(q.cast<float>());
  }
  return source;
}

// sigma^2 (sum J^T n n^T J)^-1 at the true pose, n the exact normals of the reference points
// (the source point i is reference point i moved), metres and radians.
PoseMatrix surface_covariance(const PointCloud& source, const PointCloud& reference,
                              const Eigen::Matrix4d& T_gt, double noise_m) {
  const EulerPoseJacobian pose(pose_from_transform(T_gt));
  PoseMatrix info = PoseMatrix::Zero();
  for (std::size_t i = 0; i < source.size(); ++i) {
    const PoseJacobianMatrix j = pose.jacobian(source.points[i].cast<double>());
    const Eigen::Vector3d n = reference.normals[i].cast<double>();
    info += j.transpose() * n * n.transpose() * j;
  }
  return noise_m * noise_m * info.inverse();
}

SgdSettings uncertainty_settings(UncertaintyType method, bool temper,
                                 CostType cost = CostType::point_to_point) {
  SgdSettings s;
  s.cost = cost;
  s.uncertainty.method = method;
  s.uncertainty.temper = temper;
  return s;
}

const Eigen::Matrix4d kTgt = make_transform(0.05, -0.03, 0.1, {0.05, -0.04, 0.02});

// Point-to-point pairs slide along the surface: the covariance is that of the distance to the
// surface, sigma^2 (sum J^T n n^T J)^-1 (the reference's normals are estimated from its points).
TEST(Laplace, MatchesTheAnalyticCovarianceOfKnownNoise) {
  const PointCloud reference = box_surface(20000, 1);
  const PointCloud source = noisy_source(reference, kTgt, kNoise_m, 2);
  PointCloud bare = reference;
  bare.normals.clear();
  const RegistrationResult r =
      align(source, bare, uncertainty_settings(UncertaintyType::laplace, false));
  ASSERT_TRUE(r.converged) << r.message;
  const PoseMatrix expected = surface_covariance(source, reference, kTgt, kNoise_m);
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(r.covariance(k, k) / expected(k, k), 1.0, 0.15) << "axis " << k;
  }
  // Correlations too: the whole matrix within 10 % in the norm of the expected one.
  const PoseMatrix whitened =
      expected.llt().matrixL().solve(expected.llt().matrixL().solve(r.covariance).transpose());
  EXPECT_LT((whitened - PoseMatrix::Identity()).norm(), 0.4);
  EXPECT_NEAR(r.residual_sigma_m, kNoise_m, 0.05 * kNoise_m);
  // Symmetric positive definite, and the tangent-space one too.
  EXPECT_LT((r.covariance - r.covariance.transpose()).norm(), 1e-15);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<PoseMatrix>(r.covariance).eigenvalues().minCoeff(), 0.0);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<PoseMatrix>(r.covariance_se3).eigenvalues().minCoeff(),
            0.0);
  EXPECT_TRUE(r.samples.empty());
}

TEST(Laplace, IndependentResidualsAreNotTempered) {
  const PointCloud reference = box_surface(20000, 3);
  const PointCloud source = noisy_source(reference, kTgt, kNoise_m, 4);
  const RegistrationResult r =
      align(source, reference, uncertainty_settings(UncertaintyType::laplace, true));
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_GE(r.correlation_factor, 1.0);
  EXPECT_LT(r.correlation_factor, 1.6);
}

// The secant's softening is one number: given back as UncertaintySettings::softening it gives the
// same covariance and pose without the secant's passes; a softening half as large doubles the
// standard deviations along the held directions (the covariance grows by its inverse square).
TEST(Laplace, AGivenSofteningStandsInForTheMeasuredOne) {
  const PointCloud reference = box_surface(20000, 7);
  const PointCloud source = noisy_source(reference, kTgt, 3.0 * kNoise_m, 8);
  SgdSettings s = uncertainty_settings(UncertaintyType::laplace, true, CostType::point_to_plane);
  const RegistrationResult measured = align(source, reference, s);
  ASSERT_TRUE(measured.converged) << measured.message;
  ASSERT_GT(measured.softening, kMinSoftening);
  ASSERT_LE(measured.softening, 1.0);
  s.uncertainty.softening = measured.softening;
  const RegistrationResult given = align(source, reference, s);
  EXPECT_EQ(given.softening, measured.softening);
  EXPECT_TRUE(given.covariance.isApprox(measured.covariance, 1e-9)) << given.covariance;
  EXPECT_TRUE(given.T_reference_source.isApprox(measured.T_reference_source, 1e-9));
  s.uncertainty.softening = std::max(kMinSoftening, 0.5 * measured.softening);
  const RegistrationResult softer = align(source, reference, s);
  const double ratio = s.uncertainty.softening / measured.softening;
  // A box holds every direction: each variance grows by 1 / ratio^2, within the prior's share
  // and the Newton step's different optimum.
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(softer.covariance(k, k) / measured.covariance(k, k), 1.0 / (ratio * ratio),
                0.1 / (ratio * ratio))
        << "axis " << k;
  }
  s.uncertainty.softening = 1.5;
  EXPECT_THROW(static_cast<void>(align(source, reference, s)), InvalidSettingsError);
  s.uncertainty.softening = 0.05;  // below any the secant reports: refused, not raised to 0.1
  EXPECT_THROW(static_cast<void>(align(source, reference, s)), InvalidSettingsError);
}

TEST(Laplace, NoneLeavesTheCovarianceEmpty) {
  const PointCloud reference = box_points(1000, 5);
  const RegistrationResult r = align(noisy_source(reference, kTgt, kNoise_m, 6), reference);
  EXPECT_TRUE(r.covariance.isZero());
  EXPECT_EQ(r.uncertainty_pairs, 0U);
}

// Two runs with the same seed give the same `count` samples and covariance; the next seed gives
// other samples.
void expect_reproducible_samples(const PointCloud& source, const PointCloud& reference,
                                 SgdSettings s, std::size_t count) {
  const RegistrationResult a = align(source, reference, s);
  const RegistrationResult b = align(source, reference, s);
  ASSERT_EQ(a.samples.size(), count);
  ASSERT_EQ(b.samples.size(), count);
  for (std::size_t i = 0; i < a.samples.size(); ++i) EXPECT_EQ(a.samples[i], b.samples[i]);
  EXPECT_EQ(a.covariance, b.covariance);
  s.sampling.seed += 1;
  const RegistrationResult c = align(source, reference, s);
  ASSERT_EQ(c.samples.size(), count);
  EXPECT_NE(a.samples.front(), c.samples.front());
  EXPECT_NE(a.samples.back(), c.samples.back());
}

TEST(Sgld, SameSeedSameSamplesOtherSeedOtherSamples) {
  const PointCloud reference = box_points(2000, 9);
  const PointCloud source = noisy_source(reference, kTgt, kNoise_m, 10);
  SgdSettings s = uncertainty_settings(UncertaintyType::sgld, true);
  s.uncertainty.samples = 50;
  expect_reproducible_samples(source, reference, s, 50);
}

// With the point-to-plane cost the chain samples the energy whose curvature Laplace inverts.
TEST(Sgld, SampleCovarianceMatchesLaplaceOnAWellConditionedProblem) {
  const PointCloud reference = box_surface(20000, 11);
  const PointCloud source = noisy_source(reference, kTgt, kNoise_m, 12);
  SgdSettings s = uncertainty_settings(UncertaintyType::sgld, false, CostType::point_to_plane);
  s.uncertainty.samples = 1000;
  const RegistrationResult sgld = align(source, reference, s);
  ASSERT_TRUE(sgld.converged) << sgld.message;
  ASSERT_EQ(sgld.samples.size(), 1000U);
  const RegistrationResult laplace =
      align(source, reference,
            uncertainty_settings(UncertaintyType::laplace, false, CostType::point_to_plane));
  const PoseMatrix expected = laplace.covariance;
  for (int k = 0; k < 6; ++k) {
    const double ratio = std::sqrt(sgld.covariance(k, k) / expected(k, k));
    EXPECT_GT(ratio, 0.75) << "axis " << k;
    EXPECT_LT(ratio, 1.33) << "axis " << k;
    // The samples centre on the estimate (the mean of SGD's last iterates, not the exact
    // optimum): within half a posterior standard deviation.
    const double mean_error =
        std::abs(sgld.sample_mean[k] - pose_from_transform(sgld.T_reference_source)[k]);
    EXPECT_LT(mean_error, 0.5 * std::sqrt(expected(k, k))) << "axis " << k;
  }
}

// The box 5 m along a strip of floor from the origin, with the scaling origin at the lower corner
// (the paper's): a turn about the origin moves the box sideways, so that y and yaw are
// correlated to about 0.99 in the space the chain runs in (and in the reported theta, about the
// same origin); a chain with a diagonal pre-conditioner in theta mixes along that ridge too
// slowly to fill it.
PointCloud box_at_the_end_of_a_strip(std::uint64_t seed) {
  PointCloud cloud = box_surface(20000, seed);
  for (auto& p : cloud.points) p.x() += 5.0F;
  std::mt19937_64 rng(seed + 1);
  for (int i = 0; i < 6000; ++i) {  // enough to be part of the bulk (robust_scaling)
    cloud.points.emplace_back(static_cast<float>(uniform(rng, 0.0, 5.0)),
                              static_cast<float>(uniform(rng, 0.0, 0.1)), 0.0F);
    cloud.normals.emplace_back(0.0F, 0.0F, 1.0F);
  }
  return cloud;
}

// The whole matrix, not only its diagonal: the chain's covariance whitened by Laplace's is the
// identity up to the sampling error of 2000 samples.
TEST(Sgld, SampleCovarianceMatchesLaplaceAlongCorrelatedDirections) {
  const PointCloud reference = box_at_the_end_of_a_strip(21);
  const PointCloud source = noisy_source(reference, kTgt, kNoise_m, 22);
  SgdSettings s = uncertainty_settings(UncertaintyType::sgld, false, CostType::point_to_plane);
  s.scaling.origin = ScalingOrigin::lower_corner;
  s.uncertainty.samples = 2000;
  const RegistrationResult sgld = align(source, reference, s);
  ASSERT_TRUE(sgld.converged) << sgld.message;
  s.uncertainty.method = UncertaintyType::laplace;
  const RegistrationResult laplace = align(source, reference, s);
  const PoseMatrix& expected = laplace.covariance;
  const double correlation =
      expected(1, 5) / std::sqrt(expected(1, 1) * expected(5, 5));  // y and yaw
  EXPECT_GT(std::abs(correlation), 0.9) << expected;
  const Eigen::LLT<PoseMatrix> llt(expected);
  const PoseMatrix whitened = llt.matrixL().solve(llt.matrixL().solve(sgld.covariance).transpose());
  // Each whitened variance within the chain's discretisation bias (about +5 to +15 %), and the
  // whitened correlations small (a chain that did not fill the ridge: 0.68 and 0.92 here).
  for (int k = 0; k < 6; ++k) {
    EXPECT_GT(whitened(k, k), 0.75) << "axis " << k;
    EXPECT_LT(whitened(k, k), 1.33) << "axis " << k;
  }
  PoseMatrix off_diagonal = whitened;
  off_diagonal.diagonal().setZero();
  EXPECT_LT(off_diagonal.norm(), 0.5) << whitened;
}

// The chain contracts every whitened axis by sgld_step = 0.1 per iteration, so its samples are
// worth more independent draws the more iterations lie between them. On this box the slowest
// coordinate's samples are worth 2 % of their number at thinning 1, 12 % at the default 5, 25 %
// at 10 (an AR(1) chain correlated 0.9 per iteration would give 5, 26 and 48 %: the chain mixes
// more slowly than its contraction alone says).
TEST(Sgld, ReportsTheEffectiveSampleSizeOfItsChain) {
  const PointCloud reference = box_surface(20000, 31);
  const PointCloud source = noisy_source(reference, kTgt, kNoise_m, 32);
  SgdSettings s = uncertainty_settings(UncertaintyType::sgld, false, CostType::point_to_plane);
  s.uncertainty.samples = 400;
  const auto ess_share = [&](std::size_t thinning) {
    s.uncertainty.thinning = thinning;
    const RegistrationResult r = align(source, reference, s);
    EXPECT_TRUE(r.converged) << r.message;
    return r.effective_samples / static_cast<double>(r.samples.size());
  };
  const double every = ess_share(1);
  const double fifth = ess_share(5);
  const double tenth = ess_share(10);
  EXPECT_LT(every, 0.06);
  EXPECT_GT(fifth, 0.06);
  EXPECT_LT(fifth, 0.3);
  EXPECT_GT(tenth, 1.5 * fifth);
  EXPECT_GT(tenth, 5.0 * every);
  // laplace samples nothing: nothing to report.
  s.uncertainty.method = UncertaintyType::laplace;
  EXPECT_EQ(align(source, reference, s).effective_samples, 0.0);
}

// The control variate's gradients at the optimum are paired once per point when the batch cost
// is a sum over its points (no trimming); with trimming the batch is paired at the optimum
// again. A trim ratio that keeps every pair of a batch of 160 takes the second path on the same
// energy: the chains agree but for rounding.
TEST(Sgld, PointGradientsAtTheOptimumGiveTheChainOfPairingEveryBatch) {
  const PointCloud reference = box_surface(5000, 23);
  const PointCloud source = noisy_source(reference, kTgt, kNoise_m, 24);
  SgdSettings s = uncertainty_settings(UncertaintyType::sgld, true, CostType::point_to_plane);
  s.uncertainty.samples = 100;
  s.refinement.gauss_newton = false;  // trimming would turn it off: the same run both ways
  const RegistrationResult summed = align(source, reference, s);
  s.pairing.trim_ratio = 0.9999999;  // ceil(0.9999999 * 160) = 160: nothing trimmed
  const RegistrationResult paired = align(source, reference, s);
  ASSERT_EQ(summed.samples.size(), 100U);
  ASSERT_EQ(paired.samples.size(), 100U);
  for (std::size_t i = 0; i < summed.samples.size(); ++i) {
    for (int k = 0; k < 6; ++k) {
      const double std_k = std::sqrt(paired.covariance(k, k));
      EXPECT_LT(std::abs(summed.samples[i][k] - paired.samples[i][k]), 1e-3 * std_k)
          << "sample " << i << " axis " << k;
    }
  }
}

// A plane z = 0 leaves x, y and yaw free; a corridor (two walls x = +-1 and a floor) leaves y.
// The point-to-plane cost sees it; point-to-point with its pairs held fixed does not (each pair
// pins a point; the sliding comes from re-pairing: docs/uncertainty.md).
PointCloud plane_points(std::size_t n, bool corridor, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = uniform(rng, -1, 1), b = uniform(rng, -3, 3);
    const int part = corridor ? static_cast<int>(i % 3) : 0;
    const Eigen::Vector3d p = part == 0   ? Eigen::Vector3d(a, b, 0.0)
                              : part == 1 ? Eigen::Vector3d(-1.0, b, 1.0 + a)
                                          : Eigen::Vector3d(1.0, b, 1.0 + a);
    cloud.points.push_back(p.cast<float>());
  }
  return cloud;
}

TEST(Degenerate, PlaneHasLargeVarianceAlongItsFreeDirections) {
  const PointCloud reference = plane_points(5000, false, 13);
  const Eigen::Matrix4d T = make_transform(0.01, 0.01, 0.0, {0.0, 0.0, 0.01});
  const RegistrationResult r =
      align(noisy_source(reference, T, kNoise_m, 14), reference,
            uncertainty_settings(UncertaintyType::laplace, true, CostType::point_to_plane));
  ASSERT_NE(r.stop_reason, StopReason::diverged) << r.message;
  const Eigen::Matrix3d t = r.covariance.topLeftCorner<3, 3>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(t);
  EXPECT_LT(std::abs(eig.eigenvectors().col(2).z()), 1e-3);  // the largest lies in the plane
  EXPECT_GT(eig.eigenvalues()[1] / t(2, 2), 1e4);            // x and y both free
  EXPECT_GT(r.covariance(5, 5) / r.covariance(3, 3), 1e4);   // yaw free, roll held
  EXPECT_GT(r.covariance(5, 5) / r.covariance(4, 4), 1e4);   // pitch held
}

TEST(Degenerate, CorridorHasLargeVarianceAlongItsAxis) {
  const PointCloud reference = plane_points(6000, true, 15);
  const Eigen::Matrix4d T = make_transform(0.01, -0.01, 0.02, {0.02, 0.0, 0.01});
  const RegistrationResult r =
      align(noisy_source(reference, T, kNoise_m, 16), reference,
            uncertainty_settings(UncertaintyType::laplace, true, CostType::point_to_plane));
  ASSERT_NE(r.stop_reason, StopReason::diverged) << r.message;
  const Eigen::SelfAdjointEigenSolver<PoseMatrix> eig(r.covariance);
  const PoseVector largest = eig.eigenvectors().col(5);
  EXPECT_GT(std::abs(largest[1]), 0.999);  // along y
  EXPECT_GT(eig.eigenvalues()[5] / eig.eigenvalues()[4], 100.0);
}

// ---- svgd (Stein ICP)

SgdSettings svgd_settings(std::size_t particles, CostType cost = CostType::point_to_plane) {
  SgdSettings s = uncertainty_settings(UncertaintyType::svgd, true, cost);
  s.uncertainty.particles = particles;
  return s;
}

TEST(Svgd, CovarianceIsSymmetricPositiveDefiniteAndModesAreReported) {
  const PointCloud reference = box_surface(20000, 21);
  const RegistrationResult r =
      align(noisy_source(reference, kTgt, kNoise_m, 22), reference, svgd_settings(32));
  ASSERT_TRUE(r.converged) << r.message;
  ASSERT_EQ(r.samples.size(), 32U);
  ASSERT_FALSE(r.modes.empty());
  EXPECT_EQ(r.modes.front().covariance, r.covariance);
  double weights = 0.0;
  for (const PoseMode& m : r.modes) weights += m.weight;
  EXPECT_DOUBLE_EQ(weights, 1.0);
  EXPECT_EQ(r.modes.size(), 1U);  // a box seen from a small motion: one mode
  EXPECT_LT((r.covariance - r.covariance.transpose()).norm(), 1e-15);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<PoseMatrix>(r.covariance).eigenvalues().minCoeff(), 0.0);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<PoseMatrix>(r.covariance_se3).eigenvalues().minCoeff(),
            0.0);
}

TEST(Svgd, SameSeedSameParticlesOtherSeedOtherParticles) {
  const PointCloud reference = box_points(2000, 23);
  const PointCloud source = noisy_source(reference, kTgt, kNoise_m, 24);
  expect_reproducible_samples(source, reference, svgd_settings(16, CostType::point_to_point), 16);
}

// A non-quadratic energy whose gradient changes every call (as a mini-batch's does).
struct NoisyEnergy {
  std::mt19937_64 rng{31};
  PoseVector operator()(const PoseVector& z) {
    PoseVector g;
    for (int k = 0; k < 6; ++k) g[k] = (k + 1) * z[k] + std::sin(z[k]) + uniform(rng, -0.3, 0.3);
    return g;
  }
};

// With one particle the kernel term vanishes and its weight is 1: SVGD is Adam descent on U.
TEST(Svgd, OneParticleIsAdamDescentOnTheEnergy) {
  PoseVector start;
  start << 3.0, -2.0, 1.5, 0.5, -4.0, 2.5;
  constexpr std::size_t kIterations = 60;
  NoisyEnergy svgd_energy;
  const std::vector<PoseVector> particles = stein_descent(
      {start},
      [&](const std::vector<PoseVector>& z, std::vector<PoseVector>& g) {
        g[0] = svgd_energy(z[0]);
      },
      kIterations, 0.6, 0.01);
  // Adam (Kingma and Ba 2015, Algorithm 1) with the same geometric step schedule.
  NoisyEnergy energy;
  PoseVector x = start, m = PoseVector::Zero(), v = PoseVector::Zero();
  for (std::size_t t = 1; t <= kIterations; ++t) {
    const double step = 0.6 * std::pow(0.01 / 0.6, static_cast<double>(t - 1) / (kIterations - 1));
    const PoseVector g = energy(x);
    m = 0.9 * m + 0.1 * g;
    v = 0.999 * v + 0.001 * g.cwiseProduct(g);
    const PoseVector m_hat = m / (1.0 - std::pow(0.9, static_cast<double>(t)));
    const PoseVector v_hat = v / (1.0 - std::pow(0.999, static_cast<double>(t)));
    x -= step * m_hat.cwiseQuotient((v_hat.cwiseSqrt().array() + 1e-8).matrix());
  }
  ASSERT_EQ(particles.size(), 1U);
  EXPECT_LT((particles[0] - x).norm(), 1e-12)
      << particles[0].transpose() << " vs " << x.transpose();
  EXPECT_LT(x.norm(), 0.5);  // it did descend
}

// On a standard Gaussian U = |z|^2 / 2 the kernel's repulsion keeps the particles spread about
// as the distribution (without it they would all collapse onto its mode).
TEST(Svgd, ParticlesSpreadLikeAStandardGaussian) {
  std::mt19937_64 rng(33);
  std::vector<PoseVector> z(64);
  for (PoseVector& zi : z) {
    for (int k = 0; k < 6; ++k) zi[k] = uniform(rng, -4.0, 4.0);
  }
  const std::vector<PoseVector> out = stein_descent(
      z, [](const std::vector<PoseVector>& x, std::vector<PoseVector>& g) { g = x; }, 300, 0.5,
      0.01);
  PoseVector mean = PoseVector::Zero();
  for (const PoseVector& zi : out) mean += zi / 64.0;
  double variance = 0.0;
  for (const PoseVector& zi : out) variance += (zi - mean).squaredNorm() / (6.0 * 63.0);
  EXPECT_LT(mean.norm(), 0.3);
  // 0.92 with the widened kernel; 0.62 with the median heuristic itself (SVGD's variance
  // collapse in six dimensions).
  EXPECT_GT(variance, 0.8);
  EXPECT_LT(variance, 1.5);
}

TEST(Svgd, ParticleModesAreConnectedComponentsInADeterministicOrder) {
  std::vector<PoseVector> z(5, PoseVector::Zero());
  z[0][0] = 100.0;  // alone
  z[2][0] = 3.0;    // linked to 1 and 4 through the chain 1 - 2 - 4
  z[3][0] = 104.0;  // with 0
  z[4][0] = 6.0;
  const auto modes = particle_modes(z, kModeLinkDistance);
  ASSERT_EQ(modes.size(), 2U);
  EXPECT_EQ(modes[0], (std::vector<std::size_t>{1, 2, 4}));
  EXPECT_EQ(modes[1], (std::vector<std::size_t>{0, 3}));
}

// A box has a half-turn symmetry about each of its three axes: particles spread over about a
// radian and a half reach the symmetric poses, and svgd reports a mode at the estimate and at
// half-turns; laplace describes one Gaussian around the estimate.
TEST(Svgd, SymmetricObjectHasAModeAtEachSymmetricPose) {
  // Few points and 5 mm noise: a posterior wide enough that particles spread over a half-turn
  // converge within the iterations (the step spans spread / svgd_step).
  PointCloud reference = box_surface(500, 25);
  const Eigen::Vector3f centre(0.5F, 0.75F, 0.35F);
  for (auto& p : reference.points) p -= centre;  // centred on its axes of symmetry
  const Eigen::Matrix4d T = make_transform(0.02, -0.01, 0.01, {0.0, 0.0, 0.05});
  const PointCloud source = noisy_source(reference, T, 5.0 * kNoise_m, 26);
  SgdSettings s = svgd_settings(64);
  // Pairs everywhere (no refinement of d_max): far particles feel the energy.
  s.refinement.stages = 0;
  s.pairing.max_correspondence_distance = Distance::scaled(1.0);
  s.uncertainty.svgd_iterations = 1000;
  s.uncertainty.method = UncertaintyType::laplace;
  s.uncertainty.temper = false;
  const RegistrationResult laplace = align(source, reference, s);
  ASSERT_TRUE(laplace.converged) << laplace.message;
  EXPECT_TRUE(laplace.modes.empty());
  // svgd's unit: a standard deviation of the tempered Gauss-Newton posterior that whitens it.
  const double yaw_std = std::sqrt(laplace.covariance(5, 5) * laplace.correlation_factor);
  s.uncertainty.temper = true;
  s.uncertainty.method = UncertaintyType::svgd;
  s.uncertainty.svgd_spread = 1.5 / yaw_std;
  const RegistrationResult r = align(source, reference, s);
  // The estimate, then its half-turns about x, y and z.
  std::vector<PoseVector> poses{pose_from_transform(T)};
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::Vector3d rpy = Eigen::Vector3d::Zero();
    rpy[axis] = std::numbers::pi;
    poses.push_back(pose_from_transform(
        make_transform(rpy.x(), rpy.y(), rpy.z(), Eigen::Vector3d::Zero()) * T));
  }
  double at_estimate = 0.0, at_half_turns = 0.0;
  std::ostringstream modes;
  for (const PoseMode& m : r.modes) {
    modes << m.weight << " at " << m.mean.transpose() << "\n";
    for (std::size_t k = 0; k < poses.size(); ++k) {
      PoseVector d = m.mean - poses[k];
      for (int a = 3; a < 6; ++a) d[a] = wrap_angle(d[a]);
      if (d.head<3>().norm() < 0.01 && d.tail<3>().norm() < 0.03) {
        (k == 0 ? at_estimate : at_half_turns) += m.weight;
      }
    }
  }
  EXPECT_GE(r.modes.size(), 2U);
  EXPECT_GT(at_estimate, 0.1) << modes.str();
  EXPECT_GT(at_half_turns, 0.1) << modes.str();
}

TEST(Degenerate, SvgdPlaneHasLargeVarianceAlongItsFreeDirections) {
  const PointCloud reference = plane_points(5000, false, 13);
  const Eigen::Matrix4d T = make_transform(0.01, 0.01, 0.0, {0.0, 0.0, 0.01});
  const RegistrationResult r =
      align(noisy_source(reference, T, kNoise_m, 14), reference, svgd_settings(32));
  ASSERT_NE(r.stop_reason, StopReason::diverged) << r.message;
  ASSERT_EQ(r.modes.size(), 1U);
  const Eigen::Matrix3d t = r.covariance.topLeftCorner<3, 3>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(t);
  EXPECT_GT(eig.eigenvalues()[1] / t(2, 2), 1e4);           // x and y both free
  EXPECT_GT(r.covariance(5, 5) / r.covariance(3, 3), 1e4);  // yaw free, roll held
  EXPECT_GT(r.covariance(5, 5) / r.covariance(4, 4), 1e4);  // pitch held
}

TEST(UncertaintySettings, BadValuesAreRejectedNamingTheSetting) {
  SgdSettings s;
  s.uncertainty.samples = 0;
  try {
    s.validate(SettingNames::cli);
    FAIL() << "no error";
  } catch (const InvalidSettingsError& e) {
    EXPECT_NE(std::string(e.what()).find("--uncertainty-samples 0: must be in [2, 1000000]"),
              std::string::npos)
        << e.what();
  }
  s = SgdSettings{};
  s.uncertainty.thinning = 0;
  EXPECT_THROW(s.validate(), InvalidSettingsError);
  s = SgdSettings{};
  s.uncertainty.step = std::nan("");
  EXPECT_THROW(s.validate(), InvalidSettingsError);
  s.uncertainty.step = -0.1;
  EXPECT_THROW(s.validate(), InvalidSettingsError);
  try {
    (void)parse_enum<UncertaintyType>("svgd2");
    FAIL() << "no error";
  } catch (const InvalidSettingsError& e) {
    EXPECT_STREQ(e.what(),
                 "unknown uncertainty method 'svgd2' (expected none, laplace, sgld or svgd)");
  }
  EXPECT_EQ(parse_enum<UncertaintyType>("sgld"), UncertaintyType::sgld);
  EXPECT_EQ(parse_enum<UncertaintyType>("svgd"), UncertaintyType::svgd);
  // svgd: zero particles, a step that is not a positive number, zero iterations.
  s = SgdSettings{};
  s.uncertainty.particles = 0;
  try {
    s.validate(SettingNames::cli);
    FAIL() << "no error";
  } catch (const InvalidSettingsError& e) {
    EXPECT_NE(std::string(e.what()).find("--particles 0: must be in [1, 10000]"), std::string::npos)
        << e.what();
  }
  s = SgdSettings{};
  for (const double bad : {std::nan(""), -0.1, 0.0}) {
    s.uncertainty.svgd_step = bad;
    try {
      s.validate(SettingNames::field);
      FAIL() << "no error for " << bad;
    } catch (const InvalidSettingsError& e) {
      EXPECT_NE(std::string(e.what()).find("uncertainty.svgd_step"), std::string::npos) << e.what();
    }
  }
  s = SgdSettings{};
  s.uncertainty.svgd_iterations = 0;
  EXPECT_THROW(s.validate(), InvalidSettingsError);
  s = SgdSettings{};
  s.uncertainty.svgd_spread = -1.0;
  EXPECT_THROW(s.validate(), InvalidSettingsError);
}

}  // namespace
