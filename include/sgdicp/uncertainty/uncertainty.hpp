#pragma once
// Pose uncertainty of an SGD-ICP registration (docs/uncertainty.md).
//   laplace: the inverse Gauss-Newton matrix of the cost at the optimum over every paired source
//            point, times the residual variance sigma^2 = sum r^2 / (n - 6), plus a weak prior.
//   sgld:    Bayesian ICP (Maken, Ramos, Ott, ICRA 2020): pre-conditioned stochastic gradient
//            Langevin dynamics (RMSProp pre-conditioner, Li et al. 2016) on the mini-batch
//            gradient of the registration's own pairing, in the space whitened by the Laplace
//            precision, started at the point estimate, with a control variate at the optimum
//            (Baker et al. 2019) so that the mini-batch noise does not widen the chain.
//   svgd:    Stein ICP (Maken, Ramos, Ott, RA-L 2022): Stein variational gradient descent (Liu
//            and Wang 2016) of K particles on the same energy and mini-batch gradient, one shared
//            mini-batch per iteration, RBF kernel with the median-heuristic bandwidth in the
//            space whitened by the Laplace precision; the particles are clustered into modes.
// The curvature of point-to-point: re-pairing lets a source point slide along the reference
// surface at no cost, so the curvature of the nearest-neighbour objective is that of the
// distance to the surface, J^T n n^T J (Pottmann and Hofer 2003), not the J^T J of pairs held
// fixed, which pins every point and is over-confident along the surface by an order of
// magnitude (measured: docs/uncertainty.md). The point-to-point covariance therefore uses the
// point-to-plane information of its pairs, with normals of the reference (estimated from its
// `kSurfaceNeighbors` nearest points where it has none).
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

#include "sgdicp/core/distance.hpp"
#include "sgdicp/core/enum_names.hpp"
#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/pose.hpp"
#include "sgdicp/core/result.hpp"
#include "sgdicp/costs/cost.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/points/scaling.hpp"

namespace sgdicp {

enum class UncertaintyType { none, laplace, sgld, svgd };

inline constexpr std::array<EnumName<UncertaintyType>, 4> kUncertaintyNames{{
    {UncertaintyType::none, "none"},
    {UncertaintyType::laplace, "laplace"},
    {UncertaintyType::sgld, "sgld"},
    {UncertaintyType::svgd, "svgd"},
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
  /// sgld: iterations per kept sample (about the autocorrelation time of the whitened axes).
  std::size_t thinning = 5;
  /// sgld: the step eps, as the contraction per iteration along every axis of the space whitened
  /// by the Laplace precision (unitless).
  double step = 0.1;
  /// svgd: particles K (measured: docs/uncertainty.md).
  std::size_t particles = 32;
  /// svgd: Adam iterations on the Stein direction, each on one mini-batch shared by all particles.
  std::size_t svgd_iterations = 50;
  /// svgd: Adam's last step, in posterior standard deviations (whitened units); the step decays
  /// geometrically from kSvgdFirstStep * svgd_spread (the scale of the initial cloud) to this.
  double svgd_step = 0.05;
  /// svgd: the initial particles' spread around the estimate, in Laplace standard deviations
  /// (the Laplace covariance inflated by its square); wide values reach other modes.
  double svgd_spread = 3.0;
  /// Temper the likelihood by the measured correlation factor kappa (false: residuals treated
  /// as independent, what the peers report).
  bool temper = true;
  /// Side of the blocks of the sandwich estimator (about the correlation length of residuals).
  Distance block_size = Distance::scaled(0.1);
  /// laplace: the softening of the fixed pairs' curvature by re-pairing (RegistrationResult::
  /// softening). 0: measured by the secant (6 passes over the source); in [kMinSoftening, 1]:
  /// this one, the secant skipped (the odometry passes the mean of its recent frames').
  double softening = 0.0;

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
  /// Point-to-point: the reference, the scaling and the final d_max (scaled) for the pairs of
  /// the surface information (below).
  const ReferenceIndex* reference = nullptr;
  const UnitCubeScaling* scaling = nullptr;
  double max_distance = 0.0;
  double scale_m = 1.0;  ///< metres per scaled unit
  CostType cost = CostType::point_to_point;
  std::size_t batch_size = 160;
  std::uint64_t seed = 0;
  PoseVector theta_init = PoseVector::Zero();  ///< scaled: the centre of the prior
  /// The batch cost is a sum over its points (no trimming): the control variate's gradients at
  /// the optimum are then paired once per point, not once per mini-batch.
  bool additive_batches = true;
  /// The grid bootstrap (laplace): the gradient of the run's cost over every point of another
  /// thinning of the source, at a scaled pose; the source as given (before thinning), the voxel
  /// side it was thinned with (0 = not thinned: no bootstrap) and the origin of the pair's frame.
  std::function<PoseVector(const PointCloud& cloud, const PoseVector& theta)> cloud_gradient;
  const PointCloud* unthinned_source = nullptr;
  double voxel_m = 0.0;
  Eigen::Vector3d frame_origin_m = Eigen::Vector3d::Zero();
};

/// Fills covariance, covariance_se3 (sgld, svgd: samples, sample_mean; svgd: modes) of `result` for
/// the scaled point estimate theta_hat, after kPolishSteps Gauss-Newton steps over every pair that
/// bring it to the full-data optimum; returns that optimum (scaled), the pose to report.
[[nodiscard]] PoseVector estimate_uncertainty(const UncertaintyProblem& problem,
                                              const UncertaintySettings& settings,
                                              PoseVector theta_hat, RegistrationResult& result);

/// The energy gradients of every particle (whitened) for one iteration: fills grads[i] for z[i].
using ParticleGradients =
    std::function<void(const std::vector<PoseVector>& z, std::vector<PoseVector>& grads)>;

/// Stein variational gradient descent (Liu and Wang 2016, Algorithm 1) with Adam: `iterations`
/// steps along phi(z_i) = 1/K sum_j [k(z_j, z_i) (-grad U(z_j)) + grad_{z_j} k(z_j, z_i)], RBF
/// kernel k = exp(-|z_j - z_i|^2 / h), h = kSvgdBandwidthScale med^2 / log(K + 1) (med^2 the
/// median of the pairwise squared distances). Adam's step decays geometrically from step_first to
/// step_last. With one particle the kernel term vanishes: plain Adam descent on U.
[[nodiscard]] std::vector<PoseVector> stein_descent(std::vector<PoseVector> z,
                                                    const ParticleGradients& energy_gradients,
                                                    std::size_t iterations, double step_first,
                                                    double step_last);

/// The particles grouped by single linkage (connected components of the pairs closer than
/// `link`, whitened units), largest group first, ties by their first particle: deterministic.
[[nodiscard]] std::vector<std::vector<std::size_t>> particle_modes(const std::vector<PoseVector>& z,
                                                                   double link);

/// svgd: particles closer than this (whitened units, posterior standard deviations) belong to
/// one mode (a 6-D Gaussian's particles lie within 4.1 of its centre with 99 % probability) ...
inline constexpr double kModeLinkDistance = 5.0;
/// ... and so do particles closer than this fraction of the kernel's length sqrt(h): the kernel
/// hardly tells them apart (k > 0.94), so they share their gradients and move as one group.
inline constexpr double kModeLinkBandwidth = 0.25;
/// svgd: the RBF bandwidth as a multiple of the median heuristic's med^2 / log(K + 1). With the
/// heuristic itself, SVGD's particles under-state the variance in six dimensions (0.46 of a
/// standard Gaussian's with 32 particles after the default 50 iterations: the known variance
/// collapse of few particles); a wider kernel repels over longer distances: 0.89 at 4x
/// (docs/uncertainty.md, measured with 16-64 particles and on the calibration scenes).
inline constexpr double kSvgdBandwidthScale = 4.0;
/// svgd: Adam's first step as a fraction of the initial spread.
inline constexpr double kSvgdFirstStep = 0.2;

/// laplace: the secant's steps, in standard deviations of the tempered Laplace covariance; the
/// least softening of the fixed pairs' curvature
/// the secant may report (in that curvature's metric); the largest secant step, a fraction of the
/// final d_max (docs/uncertainty.md).
inline constexpr double kSecantFirstStep = 3.0;
inline constexpr double kMinSoftening = 0.1;
inline constexpr double kMaxSecantStep = 0.5;
/// laplace: the source thinned on this many grids shifted at random (the grid bootstrap).
inline constexpr int kGridOffsets = 6;
/// laplace: the bootstrap stops after this many grids when their covariance is below
/// kGridShareNegligible of the sandwich's variance in both blocks. Three draws know a block's
/// trace to within ~3x (a 5 % tail), so a share that shows below 0.15 is below half the sandwich,
/// what leaving it out could cost at most (docs/design.md, *A negligible grid share stops the
/// bootstrap* and *... below its sampling error*).
inline constexpr int kGridProbeOffsets = 2;
inline constexpr double kGridShareNegligible = 0.15;

/// sgld: fewer effective draws than this and the result's message says so. A 6-D covariance
/// from nu independent draws gives a NEES whose mean is 6 nu / (nu - 7) times the truth's
/// (infinite for nu <= 7): 9 at nu = 21, the top of issue 50's target. Measured (docs/uncertainty-
/// calibration.md): 4-25 effective draws of the 200 samples, and the cases below 7 have mean
/// NEES of 14-1,460.
inline constexpr double kFewEffectiveSamples = 21.0;

/// Gauss-Newton steps over every pair before the covariance (measured: 2 reach the optimum).
inline constexpr int kPolishSteps = 2;

/// d xi / d theta at theta: the map of a theta covariance into the tangent space (right
/// perturbation, translation first).
[[nodiscard]] PoseMatrix se3_jacobian(const PoseVector& theta);

/// Central-difference Jacobian of f at x (step h in every coordinate); angles wrapped.
[[nodiscard]] PoseMatrix pose_map_jacobian(const std::function<PoseVector(const PoseVector&)>& f,
                                           const PoseVector& x, double h = 1e-6);

/// Scalar residuals per pair of the information the covariance uses: 1 for point-to-point
/// (its surface information n n^T) and point-to-plane, 3 for plane-to-plane.
[[nodiscard]] inline std::size_t residuals_per_pair(CostType cost) {
  return cost == CostType::plane_to_plane ? 3 : 1;
}

/// The weak prior: a Gaussian at the initial pose with this standard deviation (scaled units
/// for the translation, rad for the angles); it only bounds unconstrained directions.
inline constexpr double kPriorTranslationStd = 1.0;
inline constexpr std::size_t kSurfaceNeighbors = 10;
inline constexpr double kPriorRotationStd = 1.0;

}  // namespace sgdicp
