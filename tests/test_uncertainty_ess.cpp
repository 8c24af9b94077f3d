// Tests of the effective sample size sgld reports (src/uncertainty/effective_samples.hpp) on
// chains whose autocorrelation is known.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "uncertainty/effective_samples.hpp"

namespace sgdicp::detail {
namespace {

// x_i = r x_(i-1) + sqrt(1 - r^2) e_i, stationary with unit variance: tau = (1 + r) / (1 - r).
std::vector<double> ar1(double r, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> x(n);
  double v = normal(rng);
  for (double& xi : x) {
    v = r * v + std::sqrt(1.0 - r * r) * normal(rng);
    xi = v;
  }
  return x;
}

double expected_ess(double r, std::size_t n) {
  return static_cast<double>(n) * (1.0 - r) / (1.0 + r);
}

}  // namespace

TEST(EffectiveSamples, IndependentDrawsAreWorthThemselves) {
  const std::size_t n = 200000;
  const double ess = effective_sample_size(ar1(0.0, n, 1));
  EXPECT_GT(ess, 0.9 * n);
  EXPECT_LT(ess, 1.1 * n);
}

TEST(EffectiveSamples, AutoregressiveChainsAsTheirTheory) {
  const std::size_t n = 200000;
  for (const double r : {0.5, 0.9}) {
    const double ess = effective_sample_size(ar1(r, n, 2));
    EXPECT_GT(ess, 0.85 * expected_ess(r, n)) << "r = " << r;
    EXPECT_LT(ess, 1.15 * expected_ess(r, n)) << "r = " << r;
  }
}

// A chain of poses is worth what its slowest coordinate is worth.
TEST(EffectiveSamples, PoseChainTakesItsSlowestCoordinate) {
  const std::size_t n = 200000;
  std::vector<PoseVector> chain(n, PoseVector::Zero());
  for (int k = 0; k < 6; ++k) {
    const std::vector<double> x = ar1(k == 4 ? 0.9 : 0.0, n, 10 + static_cast<std::uint64_t>(k));
    for (std::size_t i = 0; i < n; ++i) chain[i][k] = x[i];
  }
  const double ess = effective_sample_size(chain);
  EXPECT_GT(ess, 0.85 * expected_ess(0.9, n));
  EXPECT_LT(ess, 1.15 * expected_ess(0.9, n));
}

// The autocovariances by FFT against the sum one lag at a time, on a short chain where every
// lag is cheap: the same tau to rounding.
TEST(EffectiveSamples, MatchesTheDirectSumOfAutocovariances) {
  const std::vector<double> x = ar1(0.7, 500, 3);
  const auto n = static_cast<double>(x.size());
  double mean = 0.0;
  for (const double v : x) mean += v / n;
  const auto gamma = [&](std::size_t k) {
    double sum = 0.0;
    for (std::size_t i = 0; i + k < x.size(); ++i) sum += (x[i] - mean) * (x[i + k] - mean);
    return sum / n;
  };
  double tau = -1.0;
  double previous = 1e300;
  for (std::size_t m = 0; 2 * m + 1 < x.size(); ++m) {
    const double pair = (gamma(2 * m) + gamma(2 * m + 1)) / gamma(0);
    if (!(pair > 0.0)) break;
    previous = std::min(previous, pair);
    tau += 2.0 * previous;
  }
  EXPECT_NEAR(effective_sample_size(x), n / tau, 1e-9 * n / tau);
}

// A chain that never decorrelates (a random walk) at the largest sample count a run may ask
// for: its pairs of autocorrelations stay positive to lag ~n/2, where the sum one lag at a time
// took O(n^2) (hours); it is worth a handful of draws.
TEST(EffectiveSamples, RandomWalkOfAMillionSamplesIsWorthFewDraws) {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> x(1000000);
  double v = 0.0;
  for (double& xi : x) xi = (v += normal(rng));
  const double ess = effective_sample_size(x);
  EXPECT_GT(ess, 0.0);
  EXPECT_LT(ess, 100.0);
}

TEST(EffectiveSamples, TooShortOrStillChainsAreWorthNothing) {
  EXPECT_EQ(effective_sample_size(std::vector<double>{1.0, 2.0, 3.0}), 0.0);
  EXPECT_EQ(effective_sample_size(std::vector<double>(100, 4.2)), 0.0);
  EXPECT_EQ(effective_sample_size(std::vector<PoseVector>{}), 0.0);
}

}  // namespace sgdicp::detail
