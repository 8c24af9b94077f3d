#pragma once
// The batch baselines users compare against, on the same KD-tree, costs, kernels and result as
// SGD-ICP: every iteration pairs *all* source points with their nearest reference point within
// d_max, then
//   point-to-point ICP (Besl and McKay 1992): the closed-form weighted least-squares rigid
//     transform of the pairs (Kabsch/Umeyama, via SVD);
//   point-to-plane ICP (Chen and Medioni 1992) and GICP (Segal et al. 2009): one damped
//     Gauss-Newton (Levenberg-Marquardt) step on sum rho(e^T Omega e) (cost.hpp), with the pose
//     updated on the left, T <- exp(delta) T.
// They stop when an iteration moves the pose less than the tolerances, or at max_iterations.
#include <cstddef>

#include <Eigen/Core>

#include "sgdicp/cost.hpp"
#include "sgdicp/nearest_neighbor.hpp"
#include "sgdicp/point_cloud.hpp"
#include "sgdicp/preprocessing.hpp"
#include "sgdicp/registration.hpp"
#include "sgdicp/result.hpp"
#include "sgdicp/robust_kernel.hpp"

namespace sgdicp {

struct BatchSettings {
  /// point-to-point (icp), point-to-plane (icp-plane) or plane-to-plane (gicp).
  CostType cost = CostType::point_to_point;
  /// d_max: pairs farther apart are rejected. Scaled units are a fraction of the largest side
  /// of the joint bounding box (e.g. 0.05 = 6 m on a 120 m LiDAR scan, 10 cm on a 2 m Kinect view).
  Distance max_correspondence_distance = Distance::scaled(0.05);
  KernelType kernel = KernelType::none;
  Distance kernel_scale = Distance::scaled(0.01);
  /// Keep only this fraction of the pairs, the closest ones (trimmed ICP). In (0, 1].
  double trim_ratio = 1.0;
  std::size_t max_iterations = 100;
  /// Converged when an iteration moves the translation less than this (scaled units: 0.1 mm on
  /// a 10 m room, 1.5 mm on a 150 m LiDAR scene) ...
  double translation_tolerance = 1e-5;
  /// ... and the rotation less than this (rad).
  double rotation_tolerance = 1e-5;
  /// Initial Levenberg-Marquardt damping, relative to the mean diagonal of J^T J; 0 = plain
  /// Gauss-Newton. Unused by point-to-point (closed form).
  double initial_damping = 1e-6;
  /// Neighbourhoods for the normals / covariances of the plane costs (estimated when missing).
  NeighborhoodSettings neighborhood{};
  std::size_t evaluation_points = 2000;  ///< see SgdSettings
  bool check_degeneracy = true;          ///< see SgdSettings
  /// Record a per-iteration trace in the result: the pose after each iteration, every source
  /// point processed per iteration, step size 1, d_max, the pairs kept and, as the cost, their
  /// mean squared distance before the step (scaled units^2).
  bool record_trace = false;

  static BatchSettings icp();        ///< point-to-point
  static BatchSettings icp_plane();  ///< point-to-plane
  static BatchSettings gicp();       ///< plane-to-plane

  /// Throws InvalidSettingsError naming the first absurd setting.
  void validate() const;
};

/// Registers source to the reference held by an index. Plane costs need the reference's normals
/// or covariances (prepare_reference in features.hpp); GICP estimates the source's covariances
/// itself (timed) unless the source has them.
[[nodiscard]] RegistrationResult align_batch(
    const PointCloud& source, const ReferenceIndex& reference, const BatchSettings& settings = {},
    const Eigen::Matrix4d& T_init = Eigen::Matrix4d::Identity());

/// Convenience overload that builds the index (and the reference features) itself.
[[nodiscard]] RegistrationResult align_batch(
    const PointCloud& source, const PointCloud& reference, const BatchSettings& settings = {},
    const Eigen::Matrix4d& T_init = Eigen::Matrix4d::Identity());

}  // namespace sgdicp
