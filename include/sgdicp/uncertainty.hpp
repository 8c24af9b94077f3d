#pragma once
// Pose uncertainty of an SGD-ICP registration (docs/uncertainty.md).
//   laplace: the inverse Gauss-Newton matrix of the cost at the optimum over every paired source
//            point, times the residual variance sigma^2 = sum r^2 / (n - 6), plus a weak prior.
//   sgld:    Bayesian ICP (Maken, Ramos, Ott, ICRA 2020): pre-conditioned stochastic gradient
//            Langevin dynamics (RMSProp pre-conditioner, Li et al. 2016) on the mini-batch
//            gradient of the registration's own pairing, started at the point estimate, with a
//            control variate at the optimum (Baker et al. 2019) so that the mini-batch noise
//            does not widen the chain.
// Calibration (`temper`): nearest-neighbour residuals are not independent, so the likelihood of
// n residuals holds fewer than n independent ones. A block sandwich estimator (the mini-batch
// gradients summed per voxel block of side `block_size`) measures the factor kappa by which the
// naive covariance is too narrow; the likelihood is tempered by 1/kappa (n_eff = n / kappa).
//
// Conventions: theta = (x, y, z, roll, pitch, yaw) of T_reference_source, R = Rz Ry Rx, metres
// and radians (pose.hpp). The tangent-space covariance is of xi = (rho, phi), translation first,
// with the right perturbation T = T_hat * Exp(xi) (xi in the source frame).
#include <array>
#include <cstdint>
#include <functional>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/cost.hpp"
#include "sgdicp/distance.hpp"
#include "sgdicp/enum_names.hpp"
#include "sgdicp/point_cloud.hpp"
#include "sgdicp/pose.hpp"
#include "sgdicp/result.hpp"

namespace sgdicp {

enum class UncertaintyType { none, laplace, sgld };

inline constexpr std::array<EnumName<UncertaintyType>, 3> kUncertaintyNames{{
    {UncertaintyType::none, "none"},
    {UncertaintyType::laplace, "laplace"},
    {UncertaintyType::sgld, "sgld"},
}};
constexpr const auto& enum_names(UncertaintyType) {
  return kUncertaintyNames;
}
constexpr std::string_view enum_noun(UncertaintyType) {
  return "uncertainty method";
}
[[nodiscard]] inline std::string_view to_string(UncertaintyType t) {
  return enum_name(t);
}

struct UncertaintySettings {
  UncertaintyType method = UncertaintyType::none;
  /// sgld: samples kept after the burn-in, one every `thinning` iterations.
  std::size_t samples = 200;
  /// sgld: iterations discarded before the first sample (measured: docs/uncertainty.md).
  std::size_t burn_in = 50;
  /// sgld: iterations per kept sample (measured: the autocorrelation time of the stiffest axis).
  std::size_t thinning = 5;
  /// sgld: the step eps, as the contraction per iteration along the stiffest axis (unitless).
  double step = 0.1;
  /// Temper the likelihood by the measured correlation factor kappa (false: residuals treated
  /// as independent, what the peers report).
  bool temper = true;
  /// Side of the blocks of the sandwich estimator (about the correlation length of residuals).
  Distance block_size = Distance::scaled(0.1);

  bool operator==(const UncertaintySettings&) const = default;
};

/// The pose of a registration in the scaled space and what the uncertainty needs of it.
struct UncertaintyProblem {
  /// The cost of some source points at a scaled pose with the run's final pairing (d_max,
  /// cost, kernel, trimming), as the SGD loop computes it for a mini-batch.
  std::function<CostAccumulator(const std::vector<std::uint32_t>& batch, const PoseVector& theta,
                                bool with_hessian)>
      batch_cost;
  /// Scaled pose -> the reported theta (metric, between the clouds' frames).
  std::function<PoseVector(const PoseVector& theta)> to_reported;
  const PointCloud* source = nullptr;  ///< the source points the batches index, metres
  double scale_m = 1.0;                ///< metres per scaled unit
  CostType cost = CostType::point_to_point;
  std::size_t batch_size = 160;
  std::uint64_t seed = 0;
  PoseVector theta_init = PoseVector::Zero();  ///< scaled: the centre of the prior
};

/// Fills covariance, covariance_se3 (and for sgld samples, sample_mean) of `result` for the
/// scaled point estimate theta_hat.
void estimate_uncertainty(const UncertaintyProblem& problem, const UncertaintySettings& settings,
                          const PoseVector& theta_hat, RegistrationResult& result);

/// d xi / d theta at theta: the map of a theta covariance into the tangent space (right
/// perturbation, translation first).
[[nodiscard]] PoseMatrix se3_jacobian(const PoseVector& theta);

/// Central-difference Jacobian of f at x (step h in every coordinate); angles wrapped.
[[nodiscard]] PoseMatrix pose_map_jacobian(const std::function<PoseVector(const PoseVector&)>& f,
                                           const PoseVector& x, double h = 1e-6);

/// Scalar residuals per pair of a cost: the rank of its information matrix.
[[nodiscard]] inline std::size_t residuals_per_pair(CostType cost) {
  return cost == CostType::point_to_plane ? 1 : 3;
}

/// The weak prior: a Gaussian at the initial pose with this standard deviation (scaled units
/// for the translation, rad for the angles); it only bounds unconstrained directions.
inline constexpr double kPriorTranslationStd = 1.0;
inline constexpr double kPriorRotationStd = 1.0;

}  // namespace sgdicp
