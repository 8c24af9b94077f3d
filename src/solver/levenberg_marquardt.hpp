#pragma once
// Levenberg's damping for the batch Gauss-Newton solvers (private to the library): a step is
// accepted only if it lowers the cost; otherwise the damping grows tenfold and the step is tried
// again, at most 10 times. After an accepted step the damping shrinks tenfold, towards plain
// Gauss-Newton. A damping of 0 is plain Gauss-Newton: every step is accepted.
#include <algorithm>
#include <optional>

#include "sgdicp/core/pose.hpp"

namespace sgdicp::detail {

class LevenbergMarquardt {
 public:
  /// `initial_damping` is relative to the mean diagonal of the Gauss-Newton matrix.
  explicit LevenbergMarquardt(double initial_damping)
      : initial_(initial_damping), damping_(initial_damping) {}

  /// The first damped step of `system` that lowers its cost, or nothing when none of the 10
  /// tried does. System: PoseVector step(double damping) const; double cost() const;
  /// double cost_after(const PoseVector& step) const.
  template <typename System>
  [[nodiscard]] std::optional<PoseVector> descend(const System& system) {
    for (int attempt = 0; attempt < kAttempts; ++attempt) {
      const PoseVector step = system.step(damping_);
      if (damping_ == 0.0 || system.cost_after(step) <= system.cost()) {
        damping_ = std::max(damping_ * 0.1, initial_ > 0 ? 1e-12 : 0.0);
        return step;
      }
      damping_ = std::max(damping_ * 10.0, 1e-9);
    }
    return std::nullopt;
  }

  /// The damping the next step starts from.
  [[nodiscard]] double damping() const noexcept { return damping_; }

  static constexpr int kAttempts = 10;

 private:
  double initial_;
  double damping_;
};

}  // namespace sgdicp::detail
