#pragma once
// Refinement after the paper's coarse phase (our answer to DESIGN's "central problem",
// docs/design.md). The paper's single d_max = 0.5 scaled rejects nothing on a large outdoor
// scene, so its optimum is biased by every non-overlapping point; each time a stage tests
// stationary (ConvergenceMonitor) the schedule shrinks d_max to a multiple of the median
// correspondence distance of the stage's last window and multiplies the step size by a decay.
// When the last stage is stationary, or a refinement stage leaves d_max where it was, the run
// has converged.
#include <algorithm>
#include <cstddef>
#include <vector>

#include "sgdicp/core/distance.hpp"

namespace sgdicp {

/// Each time a stage is stationary, d_max shrinks to `distance_factor` times the median
/// correspondence distance of the stage's last window of iterations (never below
/// `min_distance`; a mini-batch without any pair doubles it again, up to the initial d_max) and
/// the step size is multiplied by `step_decay`. When the last of these `stages` is stationary
/// the run has converged; it returns the mean of the iterates of that stationary window
/// (Polyak averaging), which removes most of the remaining jitter.
struct RefinementSettings {
  std::size_t stages = 3;
  double step_decay = 0.5;
  double distance_factor = 3.0;
  Distance min_distance = Distance::scaled(1e-4);
  /// The refinement stages take pre-conditioned Gauss-Newton steps (optimizer.hpp, at its own
  /// step size times the stage's multiplier) whatever the coarse stage's rule: near the optimum
  /// they reach the stationary test in fewer mini-batches (15-30 % faster at the same errors:
  /// KITTI 50 -> 38 ms, 7-Scenes 60 -> 52 ms), while the coarse stage keeps the rule whose
  /// basin is wide (Adam). Not with a robust kernel or trimming (partial overlap), where the full
  /// Newton steps follow the outliers' pull: the refinement then keeps the coarse stage's rule.
  bool gauss_newton = true;
  /// A refinement stage also ends the run when the d_max it would hand on is within this
  /// fraction of its own: the pairs have settled, and one more stage would only repeat them at
  /// half the step. On nearly aligned dense frames that is the last stage's window of 20
  /// mini-batches saved (PCL Kinect frames and 7-Scenes 80 -> 60, rotation as precise: 0.191 ->
  /// 0.186 deg and 0.171 -> 0.170 deg). 0 = always run every stage. In [0, 0.99].
  double settle_tolerance = 0.05;
  bool operator==(const RefinementSettings&) const = default;
};

/// The state of the schedule during one run: d_max, the step multiplier, the stage, and the
/// pair distances of the current and the last completed window. Distances are in scaled units.
class RefinementSchedule {
 public:
  RefinementSchedule(const RefinementSettings& settings, double initial_max_distance,
                     double min_max_distance, std::size_t pairs_per_window)
      : settings_(settings),
        initial_max_distance_(initial_max_distance),
        min_max_distance_(std::min(initial_max_distance, min_max_distance)),
        max_distance_(initial_max_distance) {
    current_window_.reserve(std::min<std::size_t>(pairs_per_window, 1U << 16));
  }

  /// d_max of the next mini-batch.
  [[nodiscard]] double max_distance() const noexcept { return max_distance_; }
  /// Multiplier of the optimiser's step size in this stage.
  [[nodiscard]] double step_scale() const noexcept { return step_scale_; }
  /// Refinements done so far (0 = the paper's coarse phase).
  [[nodiscard]] std::size_t stage() const noexcept { return stage_; }
  /// Whether a stationary test of this stage ends the run.
  [[nodiscard]] bool final_stage() const noexcept { return stage_ == settings_.stages; }

  /// Where the mini-batch's pair distances go (the median of a window sets the next d_max).
  [[nodiscard]] std::vector<float>& pair_distances() noexcept { return current_window_; }

  /// After each mini-batch. A refined d_max can fall below the jitter of the steps (an exact
  /// copy gives a median pair distance of 0 while Adam still steps ~alpha): a mini-batch
  /// without pairs widens it again, up to the initial d_max, instead of losing the data.
  void end_batch(std::size_t pairs) {
    if (pairs == 0 && max_distance_ < initial_max_distance_) {
      max_distance_ = std::min(2.0 * max_distance_, initial_max_distance_);
      widened_ = true;
    }
  }

  /// At the end of every tested window: its distances are the ones a refinement would use.
  void end_window() {
    last_window_.swap(current_window_);
    current_window_.clear();
  }

  /// Whether the stage just found stationary, a refinement stage whose d_max never had to widen
  /// (a stage that lost its pairs has not settled), would hand on a d_max within
  /// settle_tolerance of its own (RefinementSettings::settle_tolerance).
  [[nodiscard]] bool settled() {
    if (stage_ == 0 || widened_ || settings_.settle_tolerance <= 0.0) return false;
    return next_max_distance() >= (1.0 - settings_.settle_tolerance) * max_distance_;
  }

  /// The stage was stationary: tighter correspondences, smaller steps.
  void refine() {
    ++stage_;
    step_scale_ *= settings_.step_decay;
    max_distance_ = next_max_distance();
    widened_ = false;
  }

 private:
  // distance_factor x the median pair distance of the last window, within [min, current].
  double next_max_distance() {
    const double robust = settings_.distance_factor * median(last_window_);
    return std::clamp(robust, min_max_distance_, max_distance_);
  }

  static double median(std::vector<float>& values) {
    if (values.empty()) return 0.0;
    const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    return static_cast<double>(*mid);
  }

  RefinementSettings settings_;
  double initial_max_distance_;
  double min_max_distance_;
  double max_distance_;
  double step_scale_ = 1.0;
  std::size_t stage_ = 0;
  bool widened_ = false;  // end_batch widened d_max in this stage
  std::vector<float> current_window_;
  std::vector<float> last_window_;
};

}  // namespace sgdicp
