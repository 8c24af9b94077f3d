// ConvergenceMonitor on its own: the Hotelling T^2 test on the window's mini-batch gradients,
// the path-efficiency guard, the minimum number of pairs and the absolute tolerances, fed with
// synthetic gradients and steps whose answer is known.
#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "sgdicp/solver/convergence.hpp"
#include "sgdicp/solver/refinement.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

using test::uniform;

// Standard normal numbers from raw generator bits (Box-Muller), identical on every library.
PoseVector gaussian(std::mt19937_64& rng) {
  PoseVector v;
  for (int a = 0; a < 6; ++a) {
    const double u1 = uniform(rng, 0x1.0p-53, 1.0);
    const double u2 = uniform(rng, 0.0, 1.0);
    v[a] = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }
  return v;
}

constexpr std::size_t kPairs = 160;

// Records one iteration; true when it completed a window that tested stationary.
bool stationary(ConvergenceMonitor& monitor, const PoseVector& gradient, const PoseVector& step,
                std::size_t pairs, const PoseVector& iterate) {
  return monitor.update(gradient, step, pairs, iterate) == WindowTest::stationary;
}

// Feeds one window whose gradients are `gradient_of(noise)` and whose steps jitter (each step
// -0.01 * noise, a random walk); returns whether the window tested stationary.
template <typename GradientOf>
bool run_window(ConvergenceMonitor& monitor, std::mt19937_64& rng, std::size_t window,
                GradientOf gradient_of) {
  PoseVector theta = PoseVector::Zero();
  for (std::size_t i = 1; i <= window; ++i) {
    const PoseVector noise = gaussian(rng);
    const PoseVector step = -0.01 * noise;
    theta += step;
    const WindowTest test = monitor.update(gradient_of(noise), step, kPairs, theta);
    if (i == window) {
      EXPECT_NE(test, WindowTest::incomplete);
      return test == WindowTest::stationary;
    }
    EXPECT_EQ(test, WindowTest::incomplete) << "a window is only tested when complete";
  }
  return false;
}

double stationary_rate(const ConvergenceSettings& settings, std::uint64_t seed, int windows,
                       const PoseVector& mean_gradient) {
  ConvergenceMonitor monitor(settings);
  std::mt19937_64 rng(seed);
  int stationary = 0;
  for (int w = 0; w < windows; ++w) {
    stationary += run_window(monitor, rng, settings.window, [&](const PoseVector& noise) {
      return PoseVector(mean_gradient + noise);
    });
  }
  return static_cast<double>(stationary) / windows;
}

TEST(ConvergenceMonitor, ZeroMeanGradientsUsuallyTestStationary) {
  // T^2 <= chi2 (W-1)/(W-6) with chi2 = 12.59 accepts about 90 % of zero-mean windows of 20
  // (the exact law is (6 (W-1) / (W-6)) F(6, W-6)); the random walk's path efficiency is
  // ~1/sqrt(W), far below 0.5.
  const double rate = stationary_rate(ConvergenceSettings{}, 1, 400, PoseVector::Zero());
  EXPECT_GT(rate, 0.8);
  EXPECT_LT(rate, 0.98);
}

TEST(ConvergenceMonitor, ASignificantMeanGradientIsNotStationary) {
  // A mean of 1.5 noise standard deviations in one coordinate gives T^2 ~ W * 2.25 = 45 >> 20.
  PoseVector mean = PoseVector::Zero();
  mean[4] = 1.5;
  EXPECT_LT(stationary_rate(ConvergenceSettings{}, 2, 400, mean), 0.02);
}

TEST(ConvergenceMonitor, ALargerCriticalValueStopsMoreOften) {
  PoseVector mean = PoseVector::Zero();
  mean[0] = 0.5;
  ConvergenceSettings strict;
  ConvergenceSettings lax;
  lax.chi2 = 40.0;
  EXPECT_LT(stationary_rate(strict, 3, 300, mean), stationary_rate(lax, 3, 300, mean));
}

TEST(ConvergenceMonitor, DecisionsAreInvariantToALinearChangeOfParameters) {
  // T^2 is invariant under g -> A g: a narrow valley (gradients of very different sizes, strongly
  // correlated) is judged like an isotropic bowl. Both monitors see the same noise.
  std::mt19937_64 a_rng(4);
  Eigen::Matrix<double, 6, 6> a;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) a(r, c) = uniform(a_rng, -1.0, 1.0);
  }
  a.diagonal() += PoseVector(1e3, 1.0, 1e-3, 5.0, 0.1, 20.0);
  PoseVector mean = PoseVector::Zero();
  mean[2] = 0.6;  // borderline, so that both outcomes occur
  ConvergenceMonitor plain(ConvergenceSettings{});
  ConvergenceMonitor transformed(ConvergenceSettings{});
  std::mt19937_64 rng_plain(5), rng_transformed(5);
  int agree = 0, stationary = 0;
  const int windows = 200;
  for (int w = 0; w < windows; ++w) {
    const bool p =
        run_window(plain, rng_plain, 20, [&](const PoseVector& n) { return PoseVector(mean + n); });
    const bool t = run_window(transformed, rng_transformed, 20,
                              [&](const PoseVector& n) { return PoseVector(a * (mean + n)); });
    agree += p == t;
    stationary += p;
  }
  EXPECT_EQ(agree, windows);
  EXPECT_GT(stationary, windows / 10);
  EXPECT_LT(stationary, windows * 9 / 10);
}

TEST(ConvergenceMonitor, StraightTravelIsNotStationaryEvenWithInsignificantGradients) {
  // On a plateau the gradient can be noise while an adaptive step still travels: every step
  // the same direction, path efficiency 1 > 0.5.
  ConvergenceMonitor monitor(ConvergenceSettings{});
  std::mt19937_64 rng(6);
  PoseVector step = PoseVector::Zero();
  step[0] = 1e-3;
  int windows_stationary = 0;
  for (int w = 0; w < 50; ++w) {
    PoseVector theta = PoseVector::Zero();
    bool tested = false;
    for (int i = 0; i < 20; ++i) {
      theta += step;
      tested = stationary(monitor, gaussian(rng), step, kPairs, theta);
    }
    windows_stationary += tested;
  }
  EXPECT_EQ(windows_stationary, 0);
}

TEST(ConvergenceMonitor, PathEfficiencyBoundIsASetting) {
  // Steps that go back and forth around a drift: net / length = 0.6.
  const auto run = [](double max_path_efficiency) {
    ConvergenceSettings s;
    s.max_path_efficiency = max_path_efficiency;
    ConvergenceMonitor monitor(s);
    std::mt19937_64 rng(7);
    PoseVector theta = PoseVector::Zero();
    bool tested = false;
    for (int i = 0; i < 20; ++i) {
      PoseVector step = PoseVector::Zero();
      step[1] = i % 5 == 0 ? -1e-3 : 1e-3;  // 16 forward, 4 back: net 12, length 20
      theta += step;
      tested = stationary(monitor, 0.01 * gaussian(rng), step, kPairs, theta);
    }
    return tested;
  };
  EXPECT_FALSE(run(0.5));
  EXPECT_TRUE(run(0.7));
}

// A window of constant gradients and alternating steps of the given size. A constant gradient
// has no noise, so T^2 rejects it whatever its size: only the absolute tolerances can accept.
bool tiny_window(ConvergenceMonitor& monitor, double step_size, std::size_t pairs,
                 std::size_t window = 20, double gradient = 1e-9) {
  bool tested = false;
  PoseVector step = PoseVector::Zero();
  for (std::size_t i = 0; i < window; ++i) {
    step[0] = i % 2 == 0 ? step_size : -step_size;
    tested = stationary(monitor, PoseVector::Constant(gradient), step, pairs, PoseVector::Zero());
  }
  return tested;
}

TEST(ConvergenceMonitor, StepsAndGradientBelowTheTolerancesAreStationary) {
  // Exact data at the optimum: steps and gradients both vanish.
  ConvergenceMonitor monitor(ConvergenceSettings{});
  EXPECT_TRUE(tiny_window(monitor, 1e-9, kPairs));
}

TEST(ConvergenceMonitor, TinyStepsAgainstALargeGradientAreNotStationary) {
  // A step size of 1e-308 moves nothing, but the data still pulls: not converged.
  ConvergenceMonitor monitor(ConvergenceSettings{});
  EXPECT_FALSE(tiny_window(monitor, 1e-300, kPairs, 20, 1e-3));
  EXPECT_FALSE(tiny_window(monitor, 0.0, kPairs, 20, 2e-6));
}

// A deterministic batch (m >= N) whose iterates alternate between two pairings: gradients +-g
// about a mean of 1e-9, steps of 2e-4 back and forth (measured on the full-batch bunny). S has
// rank one, so T^2 never passes and the steps are above the tolerances: the mean gradient below
// the tolerances on a path of jitter is what ends it.
bool two_cycle_window(ConvergenceMonitor& monitor, bool travel) {
  PoseVector g;
  g << 3e-3, -1e-3, 2e-3, 5e-4, -4e-4, 1e-3;
  PoseVector step = PoseVector::Zero();
  bool tested = false;
  for (int i = 0; i < 20; ++i) {
    const double sign = i % 2 == 0 ? 1.0 : -1.0;
    step[2] = travel ? 2e-4 : sign * 2e-4;
    tested = stationary(monitor, PoseVector(sign * g + PoseVector::Constant(1e-9)), step, kPairs,
                        PoseVector::Zero());
  }
  return tested;
}

TEST(ConvergenceMonitor, ACycleOfDeterministicBatchesAboutAZeroGradientIsStationary) {
  ConvergenceMonitor monitor(ConvergenceSettings{}, true);
  EXPECT_TRUE(two_cycle_window(monitor, false));
}

TEST(ConvergenceMonitor, ATinyMeanGradientWhileTravellingIsNotStationary) {
  ConvergenceMonitor monitor(ConvergenceSettings{}, true);
  EXPECT_FALSE(two_cycle_window(monitor, true));
}

TEST(ConvergenceMonitor, StochasticBatchesNeedSmallStepsForTheAbsoluteTest) {
  // The same window from mini-batches of part of the source: its mean can be small by chance.
  ConvergenceMonitor monitor(ConvergenceSettings{}, false);
  EXPECT_FALSE(two_cycle_window(monitor, false));
}

TEST(ConvergenceMonitor, OneStepAboveTheTranslationToleranceIsNotEnough) {
  ConvergenceMonitor monitor(ConvergenceSettings{});
  PoseVector step = PoseVector::Zero();
  bool tested = false;
  for (int i = 0; i < 20; ++i) {
    step[0] = i == 7 ? 2e-6 : 1e-9;
    // A constant gradient: the T^2 test alone would never pass.
    tested = stationary(monitor, PoseVector::Constant(1.0), step, kPairs, PoseVector::Zero());
  }
  EXPECT_FALSE(tested);
}

TEST(ConvergenceMonitor, RotationToleranceIsOnTheSumOfAngleSteps) {
  ConvergenceMonitor monitor(ConvergenceSettings{});
  PoseVector step = PoseVector::Zero();
  bool tested = false;
  for (int i = 0; i < 20; ++i) {
    step.tail<3>().setConstant(4e-7);  // each below 1e-6, their sum 1.2e-6 above
    tested = stationary(monitor, PoseVector::Constant(1.0), step, kPairs, PoseVector::Zero());
  }
  EXPECT_FALSE(tested);
}

TEST(ConvergenceMonitor, TooFewPairsAreNeverStationary) {
  // Fewer than 3 pairs per mini-batch on average cannot fix 6 parameters: a zero gradient then
  // means no data, not an optimum.
  ConvergenceMonitor monitor(ConvergenceSettings{});
  EXPECT_FALSE(tiny_window(monitor, 1e-9, 2));
  EXPECT_TRUE(tiny_window(monitor, 1e-9, 3));
  EXPECT_FALSE(tiny_window(monitor, 1e-9, 0));
}

TEST(ConvergenceMonitor, WindowMeanIsTheMeanOfTheWindowsIterates) {
  ConvergenceMonitor monitor(ConvergenceSettings{});
  PoseVector sum = PoseVector::Zero();
  std::mt19937_64 rng(8);
  for (int i = 0; i < 20; ++i) {
    const PoseVector theta = gaussian(rng);
    sum += theta;
    (void)stationary(monitor, gaussian(rng), 1e-3 * gaussian(rng), kPairs, theta);
  }
  EXPECT_TRUE(monitor.window_mean().isApprox(sum / 20.0, 1e-12));
}

TEST(ConvergenceMonitor, StartStageForgetsAPartialWindow) {
  ConvergenceMonitor monitor(ConvergenceSettings{});
  for (int i = 0; i < 10; ++i) {
    (void)stationary(monitor, PoseVector::Constant(5.0), PoseVector::Constant(1.0), 0,
                     PoseVector::Zero());
  }
  monitor.start_stage();
  // A clean window afterwards is judged on its own 20 iterations.
  EXPECT_TRUE(tiny_window(monitor, 1e-9, kPairs));
}

TEST(ConvergenceMonitor, WindowLengthIsASetting) {
  ConvergenceSettings s;
  s.window = 8;
  ConvergenceMonitor monitor(s);
  EXPECT_TRUE(tiny_window(monitor, 1e-9, kPairs, 8));
  EXPECT_FALSE(tiny_window(monitor, 1e-9, kPairs, 7));  // 7 of 8: not yet tested
}

// ---- RefinementSchedule

// One window of pair distances, all `d`, then the window's end.
void window_of(RefinementSchedule& schedule, float d) {
  schedule.pair_distances().assign(100, d);
  schedule.end_window();
}

TEST(RefinementSchedule, ShrinksDMaxToThreeMediansAndHalvesTheStep) {
  RefinementSchedule schedule(RefinementSettings{}, 0.5, 1e-4, 160);
  window_of(schedule, 0.01F);
  schedule.refine();
  EXPECT_EQ(schedule.stage(), 1U);
  EXPECT_NEAR(schedule.max_distance(), 0.03, 1e-8);
  EXPECT_DOUBLE_EQ(schedule.step_scale(), 0.5);
  window_of(schedule, 0.02F);  // never widened by a refinement
  schedule.refine();
  EXPECT_NEAR(schedule.max_distance(), 0.03, 1e-8);
}

TEST(RefinementSchedule, ARefinementStageThatLeavesDMaxWhereItWasHasSettled) {
  RefinementSchedule schedule(RefinementSettings{}, 0.5, 1e-4, 160);
  window_of(schedule, 0.001F);       // d_max would fall from 0.5 to 0.003
  EXPECT_FALSE(schedule.settled());  // the coarse stage never settles the run
  schedule.refine();
  window_of(schedule, 0.00097F);  // 0.00291: 3 % below 0.003
  EXPECT_TRUE(schedule.settled());
  window_of(schedule, 0.00094F);  // 0.00282: 6 % below
  EXPECT_FALSE(schedule.settled());
  // A stage whose d_max had to widen (a mini-batch without pairs) lost its pairs: not settled.
  schedule.end_batch(0);
  window_of(schedule, 0.002F);  // 0.006 = the widened d_max
  EXPECT_FALSE(schedule.settled());
  schedule.refine();
  window_of(schedule, 0.002F);
  EXPECT_TRUE(schedule.settled());
  RefinementSettings every_stage;
  every_stage.settle_tolerance = 0.0;
  RefinementSchedule off(every_stage, 0.5, 1e-4, 160);
  window_of(off, 0.001F);
  off.refine();
  window_of(off, 0.001F);
  EXPECT_FALSE(off.settled());
}

}  // namespace
}  // namespace sgdicp
