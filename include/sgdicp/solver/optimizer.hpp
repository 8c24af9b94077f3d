#pragma once
// First-order optimisers for the update of paper eq. 3, theta_t = theta_{t-1} - alpha A g, with
// A = identity: fixed step ("vanilla SGD", the paper's alpha = 2), heavy-ball momentum, RMSProp
// and Adam (Kingma and Ba 2015, the paper's "Adam-SGD"); and a pre-conditioned step with A the
// inverse of a damped, averaged mini-batch Gauss-Newton matrix (eq. 3 with A != I, which the
// paper leaves for future work).
#include <array>
#include <cmath>
#include <string>
#include <string_view>

#include <Eigen/Cholesky>

#include "sgdicp/core/enum_names.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/core/pose.hpp"

namespace sgdicp {

enum class OptimizerType { sgd, momentum, rmsprop, adam, gauss_newton };

inline constexpr std::array<EnumName<OptimizerType>, 5> kOptimizerNames{{
    {OptimizerType::sgd, "sgd"},
    {OptimizerType::momentum, "momentum"},
    {OptimizerType::rmsprop, "rmsprop"},
    {OptimizerType::adam, "adam"},
    {OptimizerType::gauss_newton, "gauss-newton"},
}};
constexpr const auto& enum_names(OptimizerType) {
  return kOptimizerNames;
}
constexpr std::string_view enum_noun(OptimizerType) {
  return "optimizer";
}

[[nodiscard]] inline std::string_view to_string(OptimizerType t) {
  return enum_name(t);
}

/// Parses a name of kOptimizerNames ('_' for '-' too); throws InvalidSettingsError otherwise.
[[nodiscard]] inline OptimizerType optimizer_from_string(std::string_view name) {
  return parse_enum<OptimizerType>(name);
}

// The rules' constants. Momentum, RMSProp and Adam keep their published values (Adam: Kingma and
// Ba 2015, whose "Adam-SGD" the paper runs with them); no pairs file or sequence was measured to
// gain from others, so they are not settings (docs/registration.md, *Why each setting is there*).
inline constexpr double kMomentum = 0.9;     ///< heavy ball: velocity decay
inline constexpr double kAdamBeta1 = 0.9;    ///< Adam: decay of the mean of gradients
inline constexpr double kAdamBeta2 = 0.999;  ///< Adam: decay of the mean of squared gradients
inline constexpr double kRmsDecay = 0.9;     ///< RMSProp: decay of the mean of squared gradients
inline constexpr double kRmsEpsilon = 1e-8;  ///< Adam, RMSProp: added to the root mean square
/// Gauss-Newton: decay of the running average of the mini-batch Gauss-Newton matrices. 0.9
/// averages about ten mini-batches: enough to keep A well conditioned when one batch is
/// degenerate, few enough to follow the pose.
inline constexpr double kHessianDecay = 0.9;

/// The step size each rule runs with unless told otherwise, the one table that the presets,
/// the CLI's --optimizer and Python's optimizer= read. Adaptive rules (Adam, RMSProp) take a
/// length per step in scaled units; the fixed step a gradient multiplier (the paper's 2), and
/// momentum the same once its velocity has built up (hence 2 (1 - kMomentum)); Gauss-Newton a
/// fraction of the Newton step (1 = the full step).
[[nodiscard]] constexpr double default_learning_rate(OptimizerType type) {
  switch (type) {
    case OptimizerType::sgd:
      return 2.0;
    case OptimizerType::momentum:
      return 2.0 * (1.0 - kMomentum);
    case OptimizerType::gauss_newton:
      return 1.0;
    case OptimizerType::rmsprop:
    case OptimizerType::adam:
      break;
  }
  return 0.01;
}

struct OptimizerSettings {
  OptimizerType type = OptimizerType::sgd;
  /// alpha of eq. 3, in scaled units per unit gradient. The paper uses 2 with a fixed step.
  double learning_rate = 2.0;
  /// Gauss-Newton: Levenberg damping, relative to the mean diagonal of the averaged matrix.
  double damping = 1e-3;

  /// Throws InvalidSettingsError for a value outside its range (settings.hpp's table).
  void validate() const;

  bool operator==(const OptimizerSettings&) const = default;
};

/// `settings` stepping with Gauss-Newton at its own step, its damping kept: the step of the
/// refinement stages, of a small source's coarse stage and of the odometry's tracking.
[[nodiscard]] inline OptimizerSettings with_gauss_newton_steps(OptimizerSettings settings) {
  settings.type = OptimizerType::gauss_newton;
  settings.learning_rate = default_learning_rate(OptimizerType::gauss_newton);
  return settings;
}

/// The state of one optimiser run. step() returns the increment to add to theta.
class Optimizer {
 public:
  explicit Optimizer(const OptimizerSettings& settings) : settings_(settings) {
    settings_.validate();
  }

  /// Whether step() needs the Gauss-Newton matrix of the mini-batch.
  [[nodiscard]] bool needs_hessian() const noexcept {
    return settings_.type == OptimizerType::gauss_newton;
  }

  /// The increment -alpha * A * g for gradient g (and Gauss-Newton matrix h, used only by the
  /// pre-conditioned step), with learning-rate multiplier lr_scale (for decay schedules).
  [[nodiscard]] PoseVector step(const PoseVector& g, const Eigen::Matrix<double, 6, 6>& h,
                                double lr_scale = 1.0) {
    const double alpha = settings_.learning_rate * lr_scale;
    ++t_;
    switch (settings_.type) {
      case OptimizerType::sgd:
        return -alpha * g;
      case OptimizerType::momentum:
        velocity_ = kMomentum * velocity_ + g;
        return -alpha * velocity_;
      case OptimizerType::rmsprop:
        second_ = kRmsDecay * second_ + (1.0 - kRmsDecay) * g.cwiseProduct(g);
        return -alpha * g.cwiseQuotient((second_.cwiseSqrt().array() + kRmsEpsilon).matrix());
      case OptimizerType::adam: {
        first_ = kAdamBeta1 * first_ + (1.0 - kAdamBeta1) * g;
        second_ = kAdamBeta2 * second_ + (1.0 - kAdamBeta2) * g.cwiseProduct(g);
        const double c1 = 1.0 - std::pow(kAdamBeta1, static_cast<double>(t_));
        const double c2 = 1.0 - std::pow(kAdamBeta2, static_cast<double>(t_));
        const PoseVector m_hat = first_ / c1;
        const PoseVector v_hat = second_ / c2;
        return -alpha * m_hat.cwiseQuotient((v_hat.cwiseSqrt().array() + kRmsEpsilon).matrix());
      }
      case OptimizerType::gauss_newton: {
        // Averaging the curvature over batches keeps A well conditioned when one batch is
        // degenerate; the gradient stays the fresh, unbiased mini-batch gradient.
        hessian_ = kHessianDecay * hessian_ + (1.0 - kHessianDecay) * h;
        const double c = 1.0 - std::pow(kHessianDecay, static_cast<double>(t_));
        Eigen::Matrix<double, 6, 6> a = hessian_ / c;
        const double mean_diagonal = a.trace() / 6.0;
        if (!(mean_diagonal > 0.0)) return PoseVector::Zero();  // no pairs yet: no curvature
        a.diagonal().array() += settings_.damping * mean_diagonal;
        return -alpha * a.ldlt().solve(g);
      }
    }
    return PoseVector::Zero();
  }

  [[nodiscard]] const OptimizerSettings& settings() const noexcept { return settings_; }

 private:
  OptimizerSettings settings_;
  PoseVector first_ = PoseVector::Zero();
  PoseVector second_ = PoseVector::Zero();
  PoseVector velocity_ = PoseVector::Zero();
  Eigen::Matrix<double, 6, 6> hessian_ = Eigen::Matrix<double, 6, 6>::Zero();
  long t_ = 0;
};

}  // namespace sgdicp
