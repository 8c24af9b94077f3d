// Each step rule of optimizer.hpp against its closed form on inputs whose answer is known:
// the fixed step, heavy-ball momentum, RMSProp and Adam (with its bias correction), and the
// damped Gauss-Newton pre-conditioned step.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "sgdicp/core/error.hpp"
#include "sgdicp/solver/optimizer.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

const Matrix6d kNoHessian = Matrix6d::Zero();

OptimizerSettings settings_of(OptimizerType type, double learning_rate) {
  OptimizerSettings s;
  s.type = type;
  s.learning_rate = learning_rate;
  return s;
}

PoseVector example_gradient() {
  return PoseVector(0.3, -2.0, 1e-4, 5.0, -0.01, 0.7);
}

TEST(Optimizer, FixedStepIsMinusAlphaTimesTheGradient) {
  Optimizer sgd(settings_of(OptimizerType::sgd, 2.0));
  const PoseVector g = example_gradient();
  EXPECT_TRUE(sgd.step(g, kNoHessian).isApprox(-2.0 * g));
  // The stage multiplier scales the step (refinement halves it).
  EXPECT_TRUE(sgd.step(g, kNoHessian, 0.25).isApprox(-0.5 * g));
}

TEST(Optimizer, MomentumAccumulatesAVelocity) {
  Optimizer momentum(settings_of(OptimizerType::momentum, 0.2));
  const PoseVector g = example_gradient();
  EXPECT_TRUE(momentum.step(g, kNoHessian).isApprox(-0.2 * g));
  EXPECT_TRUE(momentum.step(g, kNoHessian).isApprox(-0.2 * 1.9 * g));
  EXPECT_TRUE(momentum.step(g, kNoHessian).isApprox(-0.2 * (0.9 * 1.9 + 1.0) * g));
  // A constant gradient settles at the terminal velocity g / (1 - momentum).
  PoseVector last;
  for (int i = 0; i < 400; ++i) last = momentum.step(g, kNoHessian);
  EXPECT_TRUE(last.isApprox(-0.2 * 10.0 * g, 1e-9));
}

TEST(Optimizer, RmsPropDividesByTheRunningRootMeanSquare) {
  OptimizerSettings s = settings_of(OptimizerType::rmsprop, 0.01);
  Optimizer rmsprop(s);
  const PoseVector g = example_gradient();
  // No bias correction: after one step the mean square is (1 - decay) g^2, decay 0.9.
  constexpr double kRmsDecay = 0.9, kRmsEpsilon = 1e-8;
  const PoseVector expected =
      -0.01 *
      g.cwiseQuotient(((std::sqrt(1.0 - kRmsDecay) * g.cwiseAbs()).array() + kRmsEpsilon).matrix());
  EXPECT_TRUE(rmsprop.step(g, kNoHessian).isApprox(expected, 1e-12));
}

TEST(Optimizer, AdamBiasCorrectionMakesEveryStepOfAConstantGradientAlphaLong) {
  // With a constant gradient, the bias-corrected moments are exactly g and g^2 at every step
  // t, so each step is -alpha g / (|g| + eps): alpha per coordinate. Without the correction the
  // first step would be -alpha (1 - beta1) / sqrt(1 - beta2) = 3.2 alpha.
  OptimizerSettings s = settings_of(OptimizerType::adam, 0.01);
  Optimizer adam(s);
  const PoseVector g = example_gradient();
  const PoseVector expected =
      -0.01 * g.cwiseQuotient((g.cwiseAbs().array() + kRmsEpsilon).matrix());
  for (int t = 1; t <= 50; ++t) {
    const PoseVector step = adam.step(g, kNoHessian);
    ASSERT_TRUE(step.isApprox(expected, 1e-9)) << "step " << t << ": " << step.transpose();
  }
}

TEST(Optimizer, AdamMatchesItsDefinitionOnAVaryingGradient) {
  // An independent transcription of Kingma and Ba's Algorithm 1 over random gradients, with
  // their published constants.
  constexpr double kAdamBeta1 = 0.9, kAdamBeta2 = 0.999, kRmsEpsilon = 1e-8;
  OptimizerSettings s = settings_of(OptimizerType::adam, 0.05);
  Optimizer adam(s);
  std::mt19937_64 rng(11);
  PoseVector m = PoseVector::Zero(), v = PoseVector::Zero();
  for (int t = 1; t <= 30; ++t) {
    PoseVector g;
    for (int a = 0; a < 6; ++a) g[a] = test::uniform(rng, -1.0, 1.0);
    PoseVector expected;
    for (int a = 0; a < 6; ++a) {
      m[a] = kAdamBeta1 * m[a] + (1.0 - kAdamBeta1) * g[a];
      v[a] = kAdamBeta2 * v[a] + (1.0 - kAdamBeta2) * g[a] * g[a];
      const double m_hat = m[a] / (1.0 - std::pow(kAdamBeta1, t));
      const double v_hat = v[a] / (1.0 - std::pow(kAdamBeta2, t));
      expected[a] = -s.learning_rate * m_hat / (std::sqrt(v_hat) + kRmsEpsilon);
    }
    ASSERT_TRUE(adam.step(g, kNoHessian).isApprox(expected, 1e-12)) << "step " << t;
  }
}

Matrix6d example_hessian() {
  std::mt19937_64 rng(12);
  Matrix6d a;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) a(r, c) = test::uniform(rng, -1.0, 1.0);
  }
  return a * a.transpose() + 0.1 * Matrix6d::Identity();
}

TEST(Optimizer, GaussNewtonFirstStepIsTheDampedNewtonStep) {
  // After one step the bias-corrected average of the matrices is the matrix itself.
  OptimizerSettings s = settings_of(OptimizerType::gauss_newton, 1.0);
  Optimizer gn(s);
  const Matrix6d h = example_hessian();
  const PoseVector g = example_gradient();
  const double lambda = s.damping * h.trace() / 6.0;
  const PoseVector expected = -(h + lambda * Matrix6d::Identity()).inverse() * g;
  EXPECT_TRUE(gn.step(g, h).isApprox(expected, 1e-10));
  // Bias correction again: the same matrix every step keeps the same step.
  EXPECT_TRUE(gn.step(g, h).isApprox(expected, 1e-10));
}

TEST(Optimizer, GaussNewtonDampingShortensTheStepTowardsGradientDescent) {
  const Matrix6d h = example_hessian();
  const PoseVector g = example_gradient();
  double previous = std::numeric_limits<double>::infinity();
  for (const double damping : {0.0, 1e-3, 1.0, 100.0}) {
    OptimizerSettings s = settings_of(OptimizerType::gauss_newton, 1.0);
    s.damping = damping;
    Optimizer gn(s);
    const PoseVector step = gn.step(g, h);
    EXPECT_LT(step.norm(), previous) << "damping " << damping;
    previous = step.norm();
    if (damping == 100.0) {
      // Heavily damped: -g / lambda, a small gradient-descent step.
      const double lambda = damping * h.trace() / 6.0;
      EXPECT_TRUE(step.isApprox(-g / lambda, 0.05));
    }
  }
}

TEST(Optimizer, GaussNewtonWithoutCurvatureDoesNotStep) {
  // No pairs yet, so no curvature: no step rather than a division by zero.
  Optimizer gn(settings_of(OptimizerType::gauss_newton, 1.0));
  EXPECT_TRUE(gn.step(example_gradient(), kNoHessian).isZero());
  EXPECT_TRUE(gn.needs_hessian());
  EXPECT_FALSE(Optimizer(settings_of(OptimizerType::adam, 0.01)).needs_hessian());
}

TEST(Optimizer, RejectsAbsurdSettings) {
  const auto rejects = [](auto change) {
    OptimizerSettings s;
    change(s);
    EXPECT_THROW(Optimizer{s}, InvalidSettingsError);
  };
  rejects([](OptimizerSettings& s) { s.learning_rate = 0.0; });
  rejects([](OptimizerSettings& s) { s.learning_rate = std::nan(""); });
  rejects([](OptimizerSettings& s) { s.learning_rate = 1e5; });
  rejects([](OptimizerSettings& s) { s.damping = -1.0; });
}

}  // namespace
}  // namespace sgdicp

// Levenberg's damping on systems whose answer is known (src/solver/levenberg_marquardt.hpp).
#include "solver/levenberg_marquardt.hpp"

namespace sgdicp {
namespace {

// A one-dimensional cost along the first coordinate; the step for damping lambda is
// -g / (h (1 + lambda)), and the true cost after it is given by `cost_of`.
template <typename Cost>
struct LineSystem {
  double g, h;
  Cost cost_of;
  [[nodiscard]] PoseVector step(double lambda) const {
    PoseVector s = PoseVector::Zero();
    s[0] = -g / (h * (1.0 + lambda));
    return s;
  }
  [[nodiscard]] double cost() const { return cost_of(0.0); }
  [[nodiscard]] double cost_after(const PoseVector& s) const { return cost_of(s[0]); }
};
template <typename Cost>
LineSystem(double, double, Cost) -> LineSystem<Cost>;

TEST(LevenbergMarquardt, AcceptsADescentStepAndRelaxesTheDamping) {
  // The quadratic (x - 1)^2: the Gauss-Newton step from 0 is exact.
  const LineSystem quadratic{-2.0, 2.0, [](double x) { return (x - 1.0) * (x - 1.0); }};
  detail::LevenbergMarquardt lm(1e-3);
  const auto step = lm.descend(quadratic);
  ASSERT_TRUE(step.has_value());
  EXPECT_NEAR((*step)[0], 1.0 / (1.0 + 1e-3), 1e-12);
  EXPECT_DOUBLE_EQ(lm.damping(), 1e-4);
}

TEST(LevenbergMarquardt, RaisesTheDampingUntilTheCostFalls) {
  // The model over-shoots: only steps shorter than 0.05 lower this cost.
  const LineSystem steep{-2.0, 2.0, [](double x) { return x < 0.05 ? -x : 1.0; }};
  detail::LevenbergMarquardt lm(1e-3);
  const auto step = lm.descend(steep);
  ASSERT_TRUE(step.has_value());
  EXPECT_LT((*step)[0], 0.05);
  EXPECT_GT(lm.damping(), 1.0);  // raised to 100 (step 1/101), then relaxed once
}

TEST(LevenbergMarquardt, ReportsWhenNoDampingLowersTheCost) {
  const LineSystem uphill{-2.0, 2.0, [](double x) { return x > 0.0 ? 1.0 : 0.0; }};
  detail::LevenbergMarquardt lm(1e-3);
  EXPECT_FALSE(lm.descend(uphill).has_value());
}

TEST(LevenbergMarquardt, ZeroDampingIsPlainGaussNewton) {
  const LineSystem uphill{-2.0, 2.0, [](double x) { return x > 0.0 ? 1.0 : 0.0; }};
  detail::LevenbergMarquardt lm(0.0);
  const auto step = lm.descend(uphill);
  ASSERT_TRUE(step.has_value());
  EXPECT_DOUBLE_EQ((*step)[0], 1.0);
  EXPECT_EQ(lm.damping(), 0.0);
}

}  // namespace
}  // namespace sgdicp
