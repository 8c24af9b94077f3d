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
// Exact data, where gradients and steps vanish (and T^2 compares noise with rounding), is caught
// by absolute tolerances: every step of the window and the window's mean gradient below them.
// Deterministic batches (m a multiple of N: every mini-batch is the whole source) need one more
// rule: their iterates can settle into a cycle between pairings (measured on the 361-point bunny
// with full-batch Gauss-Newton: steps of 2e-4 back and forth, mean gradient 3e-9, 4,000 iterations
// without a stop), where S has rank one and T^2 is huge. There, a window whose mean gradient is
// below the tolerances and whose path is jitter, not travel, is stationary too. Not with
// stochastic batches: their window mean can dip below the tolerances while the pose is still
// off (the paper preset on the KITTI copies stopped 0.013-0.036 deg off instead of < 0.01).
// The gradient part is what makes it a statement about the data: steps that are tiny because
// the step size is (alpha = 1e-308, a huge Adam epsilon) leave the data's pull on the pose
// large, and must not end a stage (measured: on every run of the shared pairs that stopped
// this way, the mean gradient was below 1.4e-7 translation / 2.7e-7 rotation, under the 1e-6
// defaults).
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

#include "sgdicp/core/pose.hpp"
#include "sgdicp/costs/point_to_point.hpp"

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
  /// units), and whose mean gradient's translation part is below it too, ...
  double translation_tolerance = 1e-6;
  /// ... and the angles less than this (sum of |d roll|, |d pitch|, |d yaw|, rad; the same sum
  /// of the mean gradient's angle part) is stationary.
  double rotation_tolerance = 1e-6;
  bool operator==(const ConvergenceSettings&) const = default;
};

/// The verdict of ConvergenceMonitor::update on the iteration it has just recorded.
enum class WindowTest {
  incomplete,  ///< the window is not full yet
  moving,      ///< the window is full and the run is still making progress
  stationary,  ///< the window is full and tested stationary
};

class ConvergenceMonitor {
 public:
  /// `deterministic_batches`: every mini-batch is the whole source, as a set (m a multiple of N).
  explicit ConvergenceMonitor(const ConvergenceSettings& settings,
                              bool deterministic_batches = false)
      : settings_(settings), deterministic_batches_(deterministic_batches) {}

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
  /// the step; tests the window when it is full, then starts the next one.
  WindowTest update(const PoseVector& gradient, const PoseVector& step, std::size_t pairs,
                    const PoseVector& iterate) {
    ++count_;
    iterate_sum_ += iterate;
    pairs_ += pairs;
    displacement_ += step;
    path_length_ += step.norm();
    sum_ += gradient;
    sum_outer_.noalias() += gradient * gradient.transpose();
    all_steps_small_ = all_steps_small_ && below_tolerances(step);
    if (count_ < settings_.window) return WindowTest::incomplete;
    const double n = static_cast<double>(count_);
    window_mean_ = iterate_sum_ / n;
    const PoseVector mean = sum_ / n;
    PoseMatrix covariance = (sum_outer_ - n * mean * mean.transpose()) / (n - 1.0);
    // A tiny ridge keeps S invertible when a direction has no noise at all (exact data). It is
    // relative to the gradients' second moment, not to S: a noise-free gradient leaves in S only
    // the rounding of the subtraction above, which can be indefinite and make T^2 negative.
    covariance.diagonal().array() += 1e-12 * sum_outer_.trace() / (6.0 * n) + 1e-300;
    const double t2 = n * mean.dot(covariance.ldlt().solve(mean));
    const bool insignificant = t2 <= settings_.chi2 * (n - 1.0) / (n - 6.0);
    const bool jittering = displacement_.norm() <= settings_.max_path_efficiency * path_length_;
    const bool enough_pairs = pairs_ >= 3 * count_;
    const bool exact =
        below_tolerances(mean) && (all_steps_small_ || (deterministic_batches_ && jittering));
    const bool stationary = enough_pairs && ((insignificant && jittering) || exact);
    start_stage();
    return stationary ? WindowTest::stationary : WindowTest::moving;
  }

  /// Mean of the iterates of the last tested window (Polyak averaging: once a window tests
  /// stationary its iterates jitter about the optimum, and their mean removes most of that).
  [[nodiscard]] const PoseVector& window_mean() const { return window_mean_; }

 private:
  // Translation part (norm) and angle part (sum of magnitudes) below the tolerances.
  [[nodiscard]] bool below_tolerances(const PoseVector& v) const {
    return v.head<3>().norm() < settings_.translation_tolerance &&
           v.tail<3>().cwiseAbs().sum() < settings_.rotation_tolerance;
  }

  ConvergenceSettings settings_;
  bool deterministic_batches_;
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
