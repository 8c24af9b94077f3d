#pragma once
// SGD-ICP registration (paper Algorithm 1); its settings are SgdSettings (settings.hpp).
#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/result.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp {

/// Registers source to the reference held by an index (built once, reusable, thread-safe).
/// T_init is the initial T_reference_source. The source is first thinned on the voxel grid of
/// the index (reference_index_for), or on settings.downsampling.voxel_size_m when set; an index
/// built from a cloud as given (ReferenceIndex's constructor) has none, and the source is then used
/// as given too. The result says which grid (voxel_size_m). Throws InvalidInputError /
/// InvalidSettingsError.
[[nodiscard]] RegistrationResult align(const PointCloud& source, const ReferenceIndex& reference,
                                       const SgdSettings& settings = {},
                                       const Eigen::Matrix4d& T_init = Eigen::Matrix4d::Identity());

/// Convenience overload that builds the index (reference_index_for) for a single registration.
[[nodiscard]] RegistrationResult align(const PointCloud& source, const PointCloud& reference,
                                       const SgdSettings& settings = {},
                                       const Eigen::Matrix4d& T_init = Eigen::Matrix4d::Identity());

/// The index align(source, reference cloud, settings) builds: the reference on the settings'
/// voxel grid (voxel_size_m, or the grid downsample_to chooses from the reference), its KD-tree
/// built on num_threads threads. Build it once and reuse it over many sources: the results are
/// those of passing the cloud each time. Throws InvalidInputError / InvalidSettingsError. A
/// reference thinned on a grid is only read; one used as it is (no grid) is copied, or moved in
/// by the second overload.
[[nodiscard]] ReferenceIndex reference_index_for(const PointCloud& reference,
                                                 const SgdSettings& settings);
[[nodiscard]] ReferenceIndex reference_index_for(PointCloud&& reference,
                                                 const SgdSettings& settings);

}  // namespace sgdicp
