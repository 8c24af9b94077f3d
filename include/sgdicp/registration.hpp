#pragma once
// SGD-ICP registration (paper Algorithm 1); its settings are SgdSettings (settings.hpp).
#include <Eigen/Core>

#include "sgdicp/nearest_neighbor.hpp"
#include "sgdicp/point_cloud.hpp"
#include "sgdicp/result.hpp"
#include "sgdicp/settings.hpp"

namespace sgdicp {

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
