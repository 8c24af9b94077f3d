#pragma once
// The local surface (normal and covariance) of a cloud's points, for the costs that need it
// (cost.hpp): taken from the cloud when it carries them, else estimated on first use with the
// estimator of estimate_covariances (normals.hpp), over the cloud's own KD-tree. An SGD
// run touches only the neighbourhoods its mini-batches reach (a few tens of thousands of points
// of a 100k-300k-point scan), so estimating those alone costs a fraction of estimating every
// point (sgd-plane 1.9x less CPU on KITTI pairs, 3.3x on Kinect frames), and gives
// bit-identical values. Private to the library.
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/surfaces/normals.hpp"

namespace sgdicp::detail {

struct PointSurface {
  Eigen::Vector3f normal;      // unit and facing the viewpoint, or zero when degenerate
  Eigen::Matrix3f covariance;  // raw (m^2) or regularized (unitless)
};

/// `settings` with the viewpoint (given in the cloud's frame) in the cloud's stored
/// coordinates, measured from its origin_m.
[[nodiscard]] NeighborhoodSettings in_stored_frame(const NeighborhoodSettings& settings,
                                                   const PointCloud& cloud);

/// The surface at index.cloud().points[i] from its flat_k nearest neighbours where they lie flat,
/// else from its min(k, size) nearest (NeighborhoodSettings::flat_k); `stored` from
/// in_stored_frame, `neighbors` scratch space. A pure function of its inputs.
[[nodiscard]] PointSurface estimate_surface(const ReferenceIndex& index, std::size_t i,
                                            const NeighborhoodSettings& stored,
                                            std::vector<Neighbor>& neighbors);

/// Throws InvalidSettingsError for settings out of range (NeighborhoodSettings::validate).
void check_neighborhood(const NeighborhoodSettings& settings);

/// The surface of a neighbourhood of `count` points around `point` with this mean and (raw)
/// covariance: its normal from the smallest eigenvector, facing the viewpoint, and its raw or
/// regularized covariance; degenerate neighbourhoods as estimate_covariances describes them.
/// `variation`, when given, receives the surface variation lambda_0 / (lambda_0 + lambda_1 +
/// lambda_2), or infinity for a degenerate neighbourhood; `linearity`, when given, the
/// linearity (lambda_2 - lambda_1) / lambda_2 (1: a line), or NaN for fewer than 3 points or
/// lambda_2 <= 0.
[[nodiscard]] PointSurface describe_covariance(const Eigen::Vector3f& point,
                                               const Eigen::Vector3d& mean,
                                               const Eigen::Matrix3d& covariance, std::size_t count,
                                               const NeighborhoodSettings& settings,
                                               double* variation = nullptr,
                                               double* linearity = nullptr);

/// Normals and covariances of a cloud, read from it or estimated once per point on first use
/// over `index`, a KD-tree over exactly that cloud (may be null when the cloud carries what its
/// cost reads). One per run: not thread-safe.
class PointSurfaces {
 public:
  PointSurfaces(const PointCloud& cloud, const ReferenceIndex* index,
                const NeighborhoodSettings& settings)
      : cloud_(cloud), index_(index), stored_(in_stored_frame(settings, cloud)) {}
  PointSurfaces(const ReferenceIndex& index, const NeighborhoodSettings& settings)
      : PointSurfaces(index.cloud(), &index, settings) {}
  PointSurfaces(const PointSurfaces&) = delete;
  PointSurfaces& operator=(const PointSurfaces&) = delete;

  [[nodiscard]] const Eigen::Vector3f& normal(std::uint32_t i) {
    return cloud_.has_normals() ? cloud_.normals[i] : estimated(i).normal;
  }
  [[nodiscard]] const Eigen::Matrix3f& covariance(std::uint32_t i) {
    return cloud_.has_covariances() ? cloud_.covariances[i] : estimated(i).covariance;
  }
  /// Points whose surface was estimated here so far.
  [[nodiscard]] std::size_t estimated_count() const noexcept { return estimated_count_; }

 private:
  const PointSurface& estimated(std::uint32_t i) {
    if (done_.empty()) {
      // Uninitialised storage: only the pages of the points estimated are ever touched.
      surfaces_.reset(new PointSurface[cloud_.size()]);
      done_.assign(cloud_.size(), 0);
    }
    if (done_[i] == 0) {
      surfaces_[i] = estimate_surface(*index_, i, stored_, scratch_);
      done_[i] = 1;
      ++estimated_count_;
    }
    return surfaces_[i];
  }

  const PointCloud& cloud_;
  const ReferenceIndex* index_;
  NeighborhoodSettings stored_;
  std::unique_ptr<PointSurface[]> surfaces_;
  std::vector<std::uint8_t> done_;
  std::vector<Neighbor> scratch_;
  std::size_t estimated_count_ = 0;
};

}  // namespace sgdicp::detail
