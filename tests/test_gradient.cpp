// Tests of the point-to-point cost and its analytic gradient (paper eq. 5-7): the gradient must be
// the gradient of exactly the cost, which must be 1/(4m) sum ||R s + t - r||^2 with
// R = Rz(yaw) Ry(pitch) Rx(roll), evaluated here independently with Eigen's AngleAxis.
#include <cmath>
#include <cstddef>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "sgdicp/core/pose.hpp"
#include "sgdicp/costs/point_to_point.hpp"
#include "test_support.hpp"

namespace {

using sgdicp::test::uniform;

using sgdicp::PointToPointGradient;
using sgdicp::PoseVector;
constexpr double kPi = std::numbers::pi;

Eigen::Vector3d random_point(std::mt19937_64& rng, double half_width) {
  return {uniform(rng, -half_width, half_width), uniform(rng, -half_width, half_width),
          uniform(rng, -half_width, half_width)};
}

struct Pairs {
  std::vector<Eigen::Vector3d> s;
  std::vector<Eigen::Vector3d> r;
};

Pairs random_pairs(std::mt19937_64& rng, std::size_t n) {
  Pairs p;
  for (std::size_t i = 0; i < n; ++i) {
    p.s.push_back(random_point(rng, 1.0));
    p.r.push_back(random_point(rng, 1.0));
  }
  return p;
}

// The cost of the paper at theta, computed without the library.
double independent_cost(const PoseVector& theta, const Pairs& p) {
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(theta[5], Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(theta[4], Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(theta[3], Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  double sum = 0.0;
  for (std::size_t i = 0; i < p.s.size(); ++i) {
    sum += (r * p.s[i] + theta.head<3>() - p.r[i]).squaredNorm();
  }
  return sum / (4.0 * static_cast<double>(p.s.size()));
}

PointToPointGradient accumulate(const PoseVector& theta, const Pairs& p) {
  PointToPointGradient g(theta);
  for (std::size_t i = 0; i < p.s.size(); ++i) g.add(p.s[i], g.transform(p.s[i]), p.r[i]);
  return g;
}

double library_cost(const PoseVector& theta, const Pairs& p) {
  return accumulate(theta, p).cost(p.s.size());
}

template <class Cost>
PoseVector finite_difference_gradient(const PoseVector& theta, const Cost& cost, double h) {
  PoseVector g;
  for (int k = 0; k < 6; ++k) {
    PoseVector plus = theta;
    PoseVector minus = theta;
    plus[k] += h;
    minus[k] -= h;
    g[k] = (cost(plus) - cost(minus)) / (2.0 * h);
  }
  return g;
}

PoseVector random_pose(std::mt19937_64& rng, double max_angle) {
  PoseVector theta;
  theta << uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -2, 2),
      uniform(rng, -max_angle, max_angle), uniform(rng, -max_angle, max_angle),
      uniform(rng, -max_angle, max_angle);
  return theta;
}

TEST(PointToPointGradient, TransformIsRsPlusT) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 100; ++i) {
    const PoseVector theta = random_pose(rng, kPi);
    const Eigen::Vector3d s = random_point(rng, 5.0);
    const PointToPointGradient g(theta);
    const Eigen::Vector3d expected = (Eigen::AngleAxisd(theta[5], Eigen::Vector3d::UnitZ()) *
                                      Eigen::AngleAxisd(theta[4], Eigen::Vector3d::UnitY()) *
                                      Eigen::AngleAxisd(theta[3], Eigen::Vector3d::UnitX())) *
                                         s +
                                     theta.head<3>();
    ASSERT_LT((g.transform(s) - expected).cwiseAbs().maxCoeff(), 1e-13);
  }
}

TEST(PointToPointGradient, CostIsQuarterMeanSquaredResidual) {
  std::mt19937_64 rng(12);
  for (int i = 0; i < 100; ++i) {
    const PoseVector theta = random_pose(rng, kPi);
    const Pairs p = random_pairs(rng, 50);
    const PointToPointGradient g = accumulate(theta, p);
    const double expected = independent_cost(theta, p);
    ASSERT_NEAR(g.cost(p.s.size()), expected, 1e-12 * expected);
  }
}

TEST(PointToPointGradient, MatchesFiniteDifferencesOfTheCost) {
  std::mt19937_64 rng(13);
  const double h = 1e-6;
  // Small, moderate and large angles (the Euler map is smooth everywhere, gimbal lock included).
  for (const double max_angle : {0.1, 1.0, kPi, 2.0 * kPi}) {
    for (int i = 0; i < 100; ++i) {
      const PoseVector theta = random_pose(rng, max_angle);
      const Pairs p = random_pairs(rng, 50);
      const PoseVector analytic = accumulate(theta, p).gradient(p.s.size());
      // Against the independent cost...
      const PoseVector fd_independent = finite_difference_gradient(
          theta, [&](const PoseVector& t) { return independent_cost(t, p); }, h);
      // ... and against the library's own cost at perturbed poses, with the same pairs.
      const PoseVector fd_library = finite_difference_gradient(
          theta, [&](const PoseVector& t) { return library_cost(t, p); }, h);
      const double scale = std::max(1.0, fd_independent.cwiseAbs().maxCoeff());
      ASSERT_LT((analytic - fd_independent).cwiseAbs().maxCoeff(), 1e-6 * scale)
          << "theta " << theta.transpose() << "\nanalytic " << analytic.transpose()
          << "\nfinite differences " << fd_independent.transpose();
      ASSERT_LT((analytic - fd_library).cwiseAbs().maxCoeff(), 1e-6 * scale);
    }
  }
}

TEST(PointToPointGradient, MatchesFiniteDifferencesAtGimbalLock) {
  std::mt19937_64 rng(14);
  for (const double pitch : {kPi / 2, -kPi / 2}) {
    PoseVector theta = random_pose(rng, kPi);
    theta[4] = pitch;
    const Pairs p = random_pairs(rng, 50);
    const PoseVector analytic = accumulate(theta, p).gradient(p.s.size());
    const PoseVector fd = finite_difference_gradient(
        theta, [&](const PoseVector& t) { return independent_cost(t, p); }, 1e-6);
    EXPECT_LT((analytic - fd).cwiseAbs().maxCoeff(),
              1e-6 * std::max(1.0, fd.cwiseAbs().maxCoeff()));
  }
}

TEST(PointToPointGradient, ZeroAtTheExactOptimum) {
  std::mt19937_64 rng(15);
  for (int i = 0; i < 100; ++i) {
    const PoseVector theta = random_pose(rng, kPi);
    const Eigen::Matrix4d t = sgdicp::transform_from_pose(theta);
    Pairs p;
    for (int k = 0; k < 50; ++k) {
      const Eigen::Vector3d s = random_point(rng, 1.0);
      p.s.push_back(s);
      p.r.push_back(t.topLeftCorner<3, 3>() * s + t.topRightCorner<3, 1>());
    }
    const PointToPointGradient g = accumulate(theta, p);
    ASSERT_LT(g.gradient(p.s.size()).cwiseAbs().maxCoeff(), 1e-13);
    ASSERT_LT(g.cost(p.s.size()), 1e-28);
    // A nearby pose is not optimal: the gradient points uphill (positive directional slope).
    PoseVector off = theta;
    off[0] += 1e-3;
    off[5] += 1e-3;
    const PoseVector g_off = accumulate(off, p).gradient(p.s.size());
    ASSERT_GT(g_off.dot(off - theta), 0.0);
  }
}

TEST(PointToPointGradient, MeanNormalisationDoesNotDependOnBatchSize) {
  // The same pairs added twice, divided by twice the count: the same gradient and cost.
  std::mt19937_64 rng(16);
  const PoseVector theta = random_pose(rng, 1.0);
  const Pairs p = random_pairs(rng, 40);
  Pairs doubled = p;
  doubled.s.insert(doubled.s.end(), p.s.begin(), p.s.end());
  doubled.r.insert(doubled.r.end(), p.r.begin(), p.r.end());
  const PoseVector g1 = accumulate(theta, p).gradient(p.s.size());
  const PoseVector g2 = accumulate(theta, doubled).gradient(doubled.s.size());
  EXPECT_LT((g1 - g2).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_NEAR(library_cost(theta, p), library_cost(theta, doubled), 1e-14);
}

TEST(PointToPointGradient, PaperStepTwoMovesTranslationExactlyByTheOffset) {
  // R = I, r = s + t0 + d: the translation part of the gradient is -d/2 (paper normalisation
  // 1/(2m)), so a fixed step theta <- theta - alpha g with alpha = 2 lands the translation on
  // t0 + d in one step, whatever m is.
  std::mt19937_64 rng(17);
  const double alpha = 2.0;
  for (const std::size_t m : {1U, 15U, 160U, 1000U}) {
    const Eigen::Vector3d t0 = random_point(rng, 1.0);
    const Eigen::Vector3d d = random_point(rng, 0.3);
    PoseVector theta = PoseVector::Zero();
    theta.head<3>() = t0;
    Pairs p;
    for (std::size_t i = 0; i < m; ++i) {
      const Eigen::Vector3d s = random_point(rng, 1.0);
      p.s.push_back(s);
      p.r.push_back(s + t0 + d);
    }
    const PoseVector g = accumulate(theta, p).gradient(m);
    EXPECT_LT((g.head<3>() + 0.5 * d).cwiseAbs().maxCoeff(), 1e-14) << "m = " << m;
    const PoseVector next = theta - alpha * g;
    EXPECT_LT((next.head<3>() - (t0 + d)).cwiseAbs().maxCoeff(), 1e-14) << "m = " << m;
  }
}

}  // namespace
