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
// Their settings are BatchSettings (settings.hpp).
#include <cstddef>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/result.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp {

/// Registers source to the reference held by an index. Plane costs need the reference's normals
/// or covariances (prepare_reference, surfaces/prepare_reference.hpp); GICP estimates the source's
/// covariances itself (timed) unless the source has them.
[[nodiscard]] RegistrationResult align_batch(
    const PointCloud& source, const ReferenceIndex& reference, const BatchSettings& settings = {},
    const Eigen::Matrix4d& T_init = Eigen::Matrix4d::Identity());

/// Convenience overload that builds the index (reference_index_for) itself.
[[nodiscard]] RegistrationResult align_batch(
    const PointCloud& source, const PointCloud& reference, const BatchSettings& settings = {},
    const Eigen::Matrix4d& T_init = Eigen::Matrix4d::Identity());

/// The index align_batch(source, reference cloud, settings) builds: the reference on the
/// settings' voxel grid (none by default), its KD-tree, and the normals or covariances the cost
/// needs. Reuse it over many sources for the same results as passing the cloud each time. A
/// reference used as it is (no grid, the default here) is copied, or moved in by the second
/// overload.
[[nodiscard]] ReferenceIndex reference_index_for(const PointCloud& reference,
                                                 const BatchSettings& settings);
[[nodiscard]] ReferenceIndex reference_index_for(PointCloud&& reference,
                                                 const BatchSettings& settings);

}  // namespace sgdicp
