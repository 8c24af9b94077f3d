#pragma once
// SGD-ICP registration (paper Algorithm 1) with its settings and result.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/convergence.hpp"
#include "sgdicp/nearest_neighbor.hpp"
#include "sgdicp/optimizer.hpp"
#include "sgdicp/point_cloud.hpp"
#include "sgdicp/scaling.hpp"

namespace sgdicp {

/// A length with an explicit unit: metres, or units of the paper's [0, 1] scaled space
/// (1 scaled unit = the largest side of the joint bounding box of both clouds).
struct Distance {
  enum class Unit { metres, scaled };
  double value = 0.0;
  Unit unit = Unit::scaled;

  static constexpr Distance metres(double v) { return {v, Unit::metres}; }
  static constexpr Distance scaled(double v) { return {v, Unit::scaled}; }
  /// The value in scaled units, given the metres per scaled unit.
  [[nodiscard]] double to_scaled(double metres_per_unit) const {
    return unit == Unit::scaled ? value : value / metres_per_unit;
  }
};

/// Refinement after the paper's coarse phase (our answer to DESIGN's "central problem"). Each
/// time a stage is stationary (ConvergenceMonitor), d_max shrinks to `distance_factor` times the
/// median correspondence distance of the stage's last `window` iterations (never growing, never
/// below `min_distance`) and the step size is multiplied by `step_decay`. After `stages` such
/// stages the run has converged; it then returns the mean of the last stage's iterates after
/// its first `window` (Polyak averaging), which removes most of the remaining jitter.
struct RefinementSettings {
  std::size_t stages = 3;
  double step_decay = 0.5;
  double distance_factor = 3.0;
  Distance min_distance = Distance::scaled(1e-4);
};

struct SgdSettings {
  /// m of the paper: source points per mini-batch.
  std::size_t batch_size = 160;
  /// d_max: pairs farther apart are rejected (paper: 0.5 in scaled units).
  Distance max_correspondence_distance = Distance::scaled(0.5);
  /// Default: Adam with a step of 0.01 scaled units, measured best over the real pairs
  /// (docs/design.md): it keeps the paper's wide basin (KITTI copies moved by 30 m), which the
  /// greedier Gauss-Newton step loses, and reaches cm accuracy with the refinement stages.
  OptimizerSettings optimizer{OptimizerType::adam, 0.01};
  ConvergenceSettings convergence{};
  RefinementSettings refinement{};
  /// Origin of the scaled space = pivot of roll, pitch, yaw. The paper's lower corner couples
  /// rotation and translation strongly (a small rotation about a far corner is a large
  /// translation of the points); the box centre decouples them (docs/design.md).
  ScalingOrigin scaling_origin = ScalingOrigin::center;
  /// Hard limit on iterations (mini-batches); reaching it means "not converged".
  std::size_t max_iterations = 4000;
  /// Seed of the mini-batch sampler; same inputs and seed give the same result.
  std::uint64_t seed = 2019;
  /// Return the mean of the final stage's iterates (after its first `window`) instead of the
  /// last iterate.
  bool average_iterates = true;
  /// Source points used for the final inlier statistics (0 = all).
  std::size_t evaluation_points = 10000;
  /// Record a per-iteration trace in the result.
  bool record_trace = false;

  /// The paper's settings: m = 160, d_max = 0.5 scaled, fixed step alpha = 2 (or Adam), no
  /// refinement, the last iterate returned, the paper's scaling origin (lower corner).
  static SgdSettings paper(OptimizerType optimizer = OptimizerType::sgd);

  /// Throws InvalidSettingsError naming the first absurd or contradictory setting.
  void validate() const;
};

enum class StopReason {
  converged,           ///< the convergence test passed (after all refinement stages)
  max_iterations,      ///< the iteration limit was reached first
  no_correspondences,  ///< a whole window of mini-batches found no pair within d_max
  diverged,            ///< the pose became non-finite or left the scaled space far behind
};
[[nodiscard]] std::string_view to_string(StopReason reason);

struct TraceEntry {
  std::size_t iteration = 0;
  std::size_t points_processed = 0;    ///< source points drawn so far
  Eigen::Matrix4d T_reference_source;  ///< metric pose after this iteration
  double step_size = 0.0;              ///< effective learning rate of this iteration
  double max_distance_m = 0.0;         ///< d_max used, metres
  std::size_t inliers = 0;             ///< pairs kept in this mini-batch
  double cost = 0.0;                   ///< mini-batch cost F, scaled units^2
};

struct RegistrationResult {
  Eigen::Matrix4d T_reference_source = Eigen::Matrix4d::Identity();
  bool converged = false;
  StopReason stop_reason = StopReason::max_iterations;
  std::string message;  ///< one line on why it stopped
  std::size_t iterations = 0;
  std::size_t points_processed = 0;   ///< source points drawn (iterations * batch size)
  std::size_t stages = 0;             ///< convergence stages completed
  std::size_t evaluated_points = 0;   ///< source points in the final inlier statistics
  std::size_t inliers = 0;            ///< of those, with a reference point within d_max
  double inlier_ratio = 0.0;          ///< inliers / evaluated_points
  double inlier_rmse_m = 0.0;         ///< RMS distance of the inliers, metres
  double final_max_distance_m = 0.0;  ///< d_max at the end (after refinement), metres
  double scale_m = 0.0;               ///< metres per scaled unit
  double time_ms = 0.0;               ///< wall time of the registration (not of the index build)
  std::vector<TraceEntry> trace;      ///< per iteration, when record_trace is set
};

/// Registers source to the reference held by an index (built once, reusable, thread-safe).
/// T_init is the initial T_reference_source. Throws InvalidInputError / InvalidSettingsError.
[[nodiscard]] RegistrationResult align(const PointCloud& source, const ReferenceIndex& reference,
                                       const SgdSettings& settings = {},
                                       const Eigen::Matrix4d& T_init = Eigen::Matrix4d::Identity());

/// Convenience overload that builds the index for a single registration.
[[nodiscard]] RegistrationResult align(const PointCloud& source, const PointCloud& reference,
                                       const SgdSettings& settings = {},
                                       const Eigen::Matrix4d& T_init = Eigen::Matrix4d::Identity());

}  // namespace sgdicp
