#pragma once
// SGD-ICP registration (paper Algorithm 1) with its settings and result.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/convergence.hpp"
#include "sgdicp/cost.hpp"
#include "sgdicp/distance.hpp"
#include "sgdicp/nearest_neighbor.hpp"
#include "sgdicp/optimizer.hpp"
#include "sgdicp/point_cloud.hpp"
#include "sgdicp/preprocessing.hpp"
#include "sgdicp/refinement.hpp"
#include "sgdicp/result.hpp"
#include "sgdicp/robust_kernel.hpp"
#include "sgdicp/scaling.hpp"

namespace sgdicp {

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
  /// Cost of a pair (cost.hpp): the paper's point-to-point, point-to-plane, or plane-to-plane
  /// (GICP). The plane costs need normals / covariances (estimated with `neighborhood` when the
  /// clouds lack them).
  CostType cost = CostType::point_to_point;
  /// Robust kernel on each pair's residual (robust_kernel.hpp) ...
  KernelType kernel = KernelType::none;
  /// ... and its scale: the residual size where it starts to down-weight.
  Distance kernel_scale = Distance::scaled(0.01);
  /// Keep only this fraction of each mini-batch's pairs, the closest ones (trimmed ICP,
  /// Chetverikov et al. 2002), for partial overlap; 1 keeps all. In (0, 1].
  double trim_ratio = 1.0;
  /// Neighbourhoods for normals and covariances when a plane cost needs them.
  NeighborhoodSettings neighborhood{};
  /// Origin of the scaled space = pivot of roll, pitch, yaw. The paper's lower corner couples
  /// rotation and translation strongly (a small rotation about a far corner is a large
  /// translation of the points); the box centre decouples them (docs/design.md).
  ScalingOrigin scaling_origin = ScalingOrigin::center;
  /// Hard limit on iterations (mini-batches); reaching it means "not converged".
  std::size_t max_iterations = 4000;
  /// Seed of the mini-batch sampler; same inputs and seed give the same result.
  std::uint64_t seed = 2019;
  /// Return the mean of the iterates of the final stage's stationary window (the last
  /// `window` iterations) instead of the last iterate.
  bool average_iterates = true;
  /// Source points used for the final inlier statistics (0 = all).
  std::size_t evaluation_points = 2000;
  /// Record a per-iteration trace in the result.
  bool record_trace = false;
  /// Check the final alignment for degenerate geometry (a plane, a line, a corridor) and report
  /// it in the result (degeneracy.hpp); costs about `evaluation_points` k-nearest queries.
  bool check_degeneracy = true;

  /// The paper's settings: m = 160, d_max = 0.5 scaled, fixed step alpha = 2 (or Adam), no
  /// refinement, the last iterate returned, the paper's scaling origin (lower corner).
  static SgdSettings paper(OptimizerType optimizer = OptimizerType::sgd);

  /// Throws InvalidSettingsError naming the first absurd or contradictory setting.
  void validate() const;
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
