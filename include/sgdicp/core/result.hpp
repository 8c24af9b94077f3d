#pragma once
// What a registration reports, whatever the method: the transform, why it stopped, how much
// work it took, and how good and how well-constrained the final alignment is.
#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/core/enum_names.hpp"

namespace sgdicp {

enum class StopReason {
  converged,  ///< the convergence test passed (in the last refinement stage, or in one whose pairs
              ///< had settled)
  max_iterations,      ///< the iteration limit was reached first
  no_correspondences,  ///< a whole window of mini-batches found no pair within d_max
  diverged,            ///< the pose became non-finite or left the scaled space far behind
  no_descent,  ///< batch Levenberg-Marquardt: no damping lowered the cost before convergence
};

inline constexpr std::array<EnumName<StopReason>, 5> kStopReasonNames{{
    {StopReason::converged, "converged"},
    {StopReason::max_iterations, "max_iterations"},
    {StopReason::no_correspondences, "no_correspondences"},
    {StopReason::diverged, "diverged"},
    {StopReason::no_descent, "no_descent"},
}};
constexpr const auto& enum_names(StopReason) {
  return kStopReasonNames;
}
constexpr std::string_view enum_noun(StopReason) {
  return "stop reason";
}
[[nodiscard]] inline std::string_view to_string(StopReason reason) {
  return enum_name(reason);
}

struct TraceEntry {
  std::size_t iteration = 0;
  std::size_t points_processed = 0;    ///< source points drawn so far
  Eigen::Matrix4d T_reference_source;  ///< metric pose after this iteration
  double step_size = 0.0;              ///< effective learning rate of this iteration (batch: 1)
  double max_distance_m = 0.0;         ///< d_max used, metres
  std::size_t inliers = 0;             ///< pairs kept in this mini-batch
  double cost = 0.0;  ///< mini-batch cost F (batch: mean squared pair distance), scaled units^2
};

/// One mode of a multi-modal pose posterior (svgd: a cluster of its particles).
struct PoseMode {
  double weight = 0.0;  ///< fraction of the particles
  /// Mean and covariance of theta = (x, y, z, roll, pitch, yaw), metres and radians.
  Eigen::Matrix<double, 6, 1> mean = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
};

struct RegistrationResult {
  Eigen::Matrix4d T_reference_source = Eigen::Matrix4d::Identity();
  bool converged = false;
  StopReason stop_reason = StopReason::max_iterations;
  std::string message;  ///< one line on why it stopped
  std::size_t iterations = 0;
  std::size_t points_processed = 0;   ///< source points paired (SGD: iterations * batch size)
  std::size_t stages = 0;             ///< convergence stages completed
  std::size_t evaluated_points = 0;   ///< source points in the final inlier statistics
  std::size_t inliers = 0;            ///< of those, with a reference point within d_max
  double inlier_ratio = 0.0;          ///< inliers / evaluated_points
  double inlier_rmse_m = 0.0;         ///< RMS distance of the inliers, metres
  double final_max_distance_m = 0.0;  ///< d_max at the end (after refinement), metres
  double scale_m = 0.0;               ///< metres per scaled unit
  /// Points of both clouds left out of the scale for lying far from the bulk of their cloud
  /// (robust_scaling); they are still paired, and d_max rejects them.
  std::size_t far_points = 0;
  double time_ms = 0.0;  ///< wall time of the registration (not of the index build)
  /// The voxel grid the source was thinned with before registering, metres (0 = none), and the
  /// points registered: of the source after thinning, of the reference as indexed.
  double voxel_size_m = 0.0;
  std::size_t source_points = 0;
  std::size_t reference_points = 0;
  /// Geometry check of the final alignment (always made): the smallest over the largest
  /// eigenvalue of the point-to-plane information matrix of the inlier pairs, in the scaled
  /// space. Near 0, some motion (sliding along a plane or a corridor, turning about an axis of
  /// symmetry) is not constrained by the data, and the transform is not trustworthy along it.
  double constraint_ratio = 0.0;
  bool degenerate = false;        ///< constraint_ratio below 0.01: see `message`
  std::vector<TraceEntry> trace;  ///< per iteration, when record_trace is set

  // Pose uncertainty (SgdSettings::uncertainty; docs/uncertainty.md), zero without it.
  /// Covariance of theta = (x, y, z, roll, pitch, yaw) of T_reference_source (R = Rz Ry Rx),
  /// metres and radians.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  /// The same in the tangent space of SE(3): xi = (rho, phi), translation first, right
  /// perturbation T = T_reference_source * Exp(xi) (source frame), metres and radians.
  Eigen::Matrix<double, 6, 6> covariance_se3 = Eigen::Matrix<double, 6, 6>::Zero();
  /// sgld: the samples of theta (as `covariance`), svgd: the particles; and their mean.
  std::vector<Eigen::Matrix<double, 6, 1>> samples;
  Eigen::Matrix<double, 6, 1> sample_mean = Eigen::Matrix<double, 6, 1>::Zero();
  /// svgd: the modes of the particles, heaviest first (`covariance` is the first's).
  std::vector<PoseMode> modes;
  double residual_sigma_m = 0.0;    ///< RMS of the scalar residuals at the optimum, metres
  double correlation_factor = 0.0;  ///< kappa: naive covariance too narrow by this factor
  double softening = 0.0;  ///< laplace: the fixed pairs' curvature softened by re-pairing, (0, 1]
  /// sgld: what its samples are worth in independent draws, the smallest over the six
  /// coordinates (Geyer's initial monotone sequence); 0 for the other methods.
  double effective_samples = 0.0;
  std::size_t uncertainty_pairs = 0;  ///< pairs of the full-data pass at the optimum
  double uncertainty_ms = 0.0;        ///< wall time of the uncertainty (inside time_ms)

  // Registration without an initial guess (align_global, docs/global.md); zero without it.
  bool global_init = false;       ///< the start came from the global estimate
  bool global_reliable = false;   ///< false: no reliable global solution (see `message`)
  bool global_ambiguous = false;  ///< the runner-up scored within ambiguity_ratio of the winner
  std::size_t global_winner_rank = 0;   ///< the winner's rank by feature consensus (0 = most)
  std::size_t global_hypotheses = 0;    ///< distinct hypotheses verified
  double global_score = 0.0;            ///< the winner's overlap (fraction of the source)
  double global_runner_up_score = 0.0;  ///< the best other hypothesis's overlap
  double global_ms = 0.0;               ///< wall time of the global estimate (inside time_ms)
};

/// Calls f(name, member pointer, description) for every field of RegistrationResult but the
/// transform and the trace: the one list that the CLI's JSON and the Python result read.
template <typename F>
void for_each_result_field(F&& f) {
  using R = RegistrationResult;
  f("converged", &R::converged,
    "True if the convergence test passed in the last refinement stage (or in one whose pairs had "
    "settled, RefinementSettings.settle_tolerance).");
  f("stop_reason", &R::stop_reason,
    "'converged', 'max_iterations', 'no_correspondences', 'diverged' or 'no_descent'.");
  f("message", &R::message, "One line on why it stopped.");
  f("iterations", &R::iterations,
    "Mini-batches (batch methods: passes over the source) processed.");
  f("points_processed", &R::points_processed,
    "Source points paired (SGD: iterations x batch size).");
  f("stages", &R::stages, "Stationary stages completed.");
  f("evaluated_points", &R::evaluated_points,
    "Source points (spread evenly) in the final inlier statistics.");
  f("inliers", &R::inliers, "Of those, with a reference point within the final d_max.");
  f("inlier_ratio", &R::inlier_ratio, "inliers / evaluated_points.");
  f("inlier_rmse_m", &R::inlier_rmse_m,
    "RMS distance of the inliers to their nearest reference point, metres.");
  f("final_max_distance_m", &R::final_max_distance_m,
    "d_max at the end (after refinement), metres.");
  f("scale_m", &R::scale_m, "Metres per scaled unit.");
  f("far_points", &R::far_points,
    "Points of both clouds left out of the scale for lying far from the bulk of their cloud "
    "(robust_scaling); still paired, d_max rejects them.");
  f("time_ms", &R::time_ms,
    "Wall time of the registration, milliseconds (KD-tree build excluded).");
  f("voxel_size_m", &R::voxel_size_m,
    "Side of the voxel grid the source was thinned with before registering, metres (0 = every "
    "point used).");
  f("source_points", &R::source_points, "Source points registered (after thinning).");
  f("reference_points", &R::reference_points, "Reference points indexed (after thinning).");
  f("constraint_ratio", &R::constraint_ratio,
    "Smallest over largest eigenvalue of the point-to-plane information matrix of the final "
    "inlier pairs (scaled space); near 0, some motion is not constrained by the data.");
  f("degenerate", &R::degenerate,
    "constraint_ratio below 0.01: the transform is not trustworthy along some motion (see "
    "message).");
  f("residual_sigma_m", &R::residual_sigma_m,
    "With uncertainty: RMS of the scalar residuals of the pairs at the optimum, metres (sigma of "
    "the likelihood).");
  f("correlation_factor", &R::correlation_factor,
    "With uncertainty: kappa, the factor by which the covariance of independent residuals is too "
    "narrow (block sandwich estimator); the likelihood is tempered by 1/kappa with temper.");
  f("softening", &R::softening,
    "With laplace: the factor by which re-pairing softens the fixed pairs' curvature along the "
    "directions the data hold (1 = not at all; measured by a secant of the re-paired gradient, "
    "or given by the odometry from its recent frames); the covariance grows by its inverse "
    "square.");
  f("effective_samples", &R::effective_samples,
    "With sgld: the effective sample size of its chain, the smallest over the six coordinates "
    "(Geyer's initial monotone sequence of autocorrelations): how many independent draws its "
    "samples are worth, and so how precisely their covariance is known (0 for the other "
    "methods).");
  f("uncertainty_pairs", &R::uncertainty_pairs,
    "With uncertainty: pairs of the full-data pass at the optimum.");
  f("uncertainty_ms", &R::uncertainty_ms,
    "With uncertainty: its wall time, milliseconds (included in time_ms).");
  f("global_init", &R::global_init,
    "True if the start came from the global estimate (init='global', --init global).");
  f("global_reliable", &R::global_reliable,
    "Global: False means no reliable global solution (too few points, no structure, an "
    "ambiguous scene or degenerate geometry; see message): do not use the transform.");
  f("global_ambiguous", &R::global_ambiguous,
    "Global: the runner-up hypothesis overlaps nearly as much as the winner (a symmetric object, "
    "a repetitive scene).");
  f("global_winner_rank", &R::global_winner_rank,
    "Global: the winning hypothesis's rank by feature consensus (0 = the most supported).");
  f("global_hypotheses", &R::global_hypotheses, "Global: distinct hypotheses verified.");
  f("global_score", &R::global_score,
    "Global: the winner's overlap, the fraction of source points within 1.5 feature voxels of the "
    "reference.");
  f("global_runner_up_score", &R::global_runner_up_score,
    "Global: the best other hypothesis's overlap (0 = none); near global_score, the scene is "
    "ambiguous.");
  f("global_ms", &R::global_ms,
    "Global: wall time of the global estimate, milliseconds (included in time_ms).");
}

}  // namespace sgdicp
