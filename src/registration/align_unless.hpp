#pragma once
// align() that gives up on a run heading where another already went (private to the library):
// the race of global registration refines several hypotheses, and a run that comes within the
// same-pose distance of a pose already refined would converge onto it (docs/global.md).
#include <functional>
#include <optional>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/result.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp::detail {

/// Reads a run's pose (T_reference_source, the clouds' frames) at the end of each convergence
/// window; true abandons the run.
using AbandonTest = std::function<bool(const Eigen::Matrix4d& T_reference_source)>;

/// align(source, reference, settings, T_init), or nullopt once `abandon` accepted a pose of the
/// run (then no final statistics are computed). An empty `abandon` never abandons.
[[nodiscard]] std::optional<RegistrationResult> align_unless(const PointCloud& source,
                                                             const ReferenceIndex& reference,
                                                             const SgdSettings& settings,
                                                             const Eigen::Matrix4d& T_init,
                                                             const AbandonTest& abandon);

}  // namespace sgdicp::detail
