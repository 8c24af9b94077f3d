#pragma once
// When has a stochastic run stopped improving? (docs/design.md, "Convergence".) Raw SGD steps never
// reach zero, so a threshold on single steps either stops too early or never, and tests on the
// iterates are fooled by their autocorrelation at small step sizes. We test the mini-batch
// gradients instead, which are nearly independent from batch to batch whatever the optimiser.
// Over a window of W iterations, a stage is stationary when the mean gradient is not
// significantly different from zero by Hotelling's T^2 test, T^2 = W gbar^T S^-1 gbar <= c, with
// S the sample covariance of the W gradients and c = chi2 * (W - 1) / (W - 6). T^2 is invariant
// to any linear change of parameters, so it also sees slow progress along a narrow valley of the
// cost, where the gradient is small but so is its noise (a per-coordinate test does not).
// Exact data, where gradients and steps vanish, is caught by an absolute tolerance on the steps.
// The gradient test alone can be fooled far from the optimum, on a plateau of the cost where
// the gradient is small against its noise while an adaptive step (Adam) still travels. So the
// path of the window must also look like jitter, not travel: its net displacement divided by
// its length (1 for a straight path, about 1/sqrt(W) for a random walk, less for oscillation)
// must stay below `max_path_efficiency`.
// A window whose mini-batches found fewer than 3 pairs each on average (too few to fix 6
// parameters) is never stationary: a zero gradient there means "no data", not "optimum".
#include <cmath>
#include <cstddef>

#include <Eigen/Cholesky>

#include "sgdicp/point_to_point.hpp"
#include "sgdicp/pose.hpp"

namespace sgdicp {

struct ConvergenceSettings {
  /// Iterations per test window, at least 8 (also the length of the final iterate average).
  std::size_t window = 20;
  /// Critical value of the test: the chi-square quantile with 6 degrees of freedom
  /// (12.59 = 95 %, larger = stops earlier).
  double chi2 = 12.59;
  /// Largest ratio |sum of steps| / sum of |steps| of a stationary window (unitless, (0, 1]).
  double max_path_efficiency = 0.5;
  /// Absolute test: a window whose steps all moved the translation less than this (scaled
  /// units) ...
  double translation_tolerance = 1e-6;
  /// ... and the angles less than this (sum of |d roll|, |d pitch|, |d yaw|, rad) is stationary.
  double rotation_tolerance = 1e-6;
  bool operator==(const ConvergenceSettings&) const = default;
};

class ConvergenceMonitor {
 public:
  explicit ConvergenceMonitor(const ConvergenceSettings& settings) : settings_(settings) {}

  /// Forgets the statistics (after a change of step size or d_max).
  void start_stage() {
    count_ = 0;
    sum_ = PoseVector::Zero();
    sum_outer_ = PoseMatrix::Zero();
    all_steps_small_ = true;
    pairs_ = 0;
    displacement_ = PoseVector::Zero();
    path_length_ = 0.0;
    iterate_sum_ = PoseVector::Zero();
  }

  /// Records one iteration's mini-batch gradient, step, number of pairs and the iterate after
  /// the step; returns true at the end of a window that tested stationary.
  bool update(const PoseVector& gradient, const PoseVector& step, std::size_t pairs,
              const PoseVector& iterate) {
    ++count_;
    iterate_sum_ += iterate;
    pairs_ += pairs;
    displacement_ += step;
    path_length_ += step.norm();
    sum_ += gradient;
    sum_outer_.noalias() += gradient * gradient.transpose();
    double rotation = 0.0;
    for (int a = 3; a < 6; ++a) rotation += std::abs(step[a]);
    all_steps_small_ = all_steps_small_ &&
                       step.head<3>().norm() < settings_.translation_tolerance &&
                       rotation < settings_.rotation_tolerance;
    if (count_ < settings_.window) return false;
    const double n = static_cast<double>(count_);
    window_mean_ = iterate_sum_ / n;
    const PoseVector mean = sum_ / n;
    PoseMatrix covariance = (sum_outer_ - n * mean * mean.transpose()) / (n - 1.0);
    // A tiny ridge keeps S invertible when a direction has no noise at all (exact data).
    covariance.diagonal().array() += 1e-12 * covariance.trace() / 6.0 + 1e-300;
    const double t2 = n * mean.dot(covariance.ldlt().solve(mean));
    const bool insignificant = t2 <= settings_.chi2 * (n - 1.0) / (n - 6.0);
    const bool jittering = displacement_.norm() <= settings_.max_path_efficiency * path_length_;
    const bool enough_pairs = pairs_ >= 3 * count_;
    const bool stationary = enough_pairs && ((insignificant && jittering) || all_steps_small_);
    start_stage();
    return stationary;
  }

  /// Mean of the iterates of the last tested window (Polyak averaging: once a window tests
  /// stationary its iterates jitter about the optimum, and their mean removes most of that).
  [[nodiscard]] const PoseVector& window_mean() const { return window_mean_; }

 private:
  ConvergenceSettings settings_;
  std::size_t count_ = 0;
  PoseVector sum_ = PoseVector::Zero();
  PoseMatrix sum_outer_ = PoseMatrix::Zero();
  bool all_steps_small_ = true;
  std::size_t pairs_ = 0;
  PoseVector displacement_ = PoseVector::Zero();
  double path_length_ = 0.0;
  PoseVector iterate_sum_ = PoseVector::Zero();
  PoseVector window_mean_ = PoseVector::Zero();
};

}  // namespace sgdicp
