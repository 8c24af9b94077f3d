#pragma once
// The setup and wrap-up every solver shares (private to the library): the checked source with
// what its cost needs, the scaling of the pair, the stop of a run and its final statistics.
#include <chrono>
#include <optional>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "core/checks.hpp"
#include "index/nearest_memory.hpp"
#include "points/voxel_table.hpp"
#include "registration/reference_index.hpp"
#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/result.hpp"
#include "sgdicp/costs/cost.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/points/scaling.hpp"
#include "sgdicp/points/voxel_grid.hpp"
#include "sgdicp/registration/evaluation.hpp"
#include "sgdicp/registration/settings.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"
#include "surfaces/point_surfaces.hpp"
#include "util/stopwatch.hpp"

namespace sgdicp::detail {

/// When the costs' normals and covariances that the clouds lack are estimated: for every point
/// before the run, or for the points the run touches, on first use (point_surfaces.hpp).
enum class SurfaceEstimation { eager, lazy };

/// The source of a registration, checked, with the covariances plane-to-plane needs estimated
/// here (and so timed with the registration) when it lacks them: every point's (eager), or a
/// KD-tree over the source for PointSurfaces to estimate them on first use (lazy).
class PreparedSource {
 public:
  /// `origin_m`: the origin of the pair's frame (PairFrame); a source stored relative to
  /// another origin is re-based onto it (a copy, only then).
  /// voxel_size_m > 0: the source is first thinned with that voxel grid (source_voxel_size), on
  /// up to `threads` threads (the registration's num_threads).
  PreparedSource(const PointCloud& source, double voxel_size_m, std::size_t threads,
                 const Eigen::Vector3d& origin_m, CostType cost,
                 const NeighborhoodSettings& neighborhood, std::size_t min_points,
                 const std::string& why_min, SurfaceEstimation when = SurfaceEstimation::eager)
      : cloud_(&source) {
    check_source(source, min_points, why_min, voxel_size_m > 0.0);
    if (voxel_size_m > 0.0) {
      copy_ = thinned(source, voxel_size_m, threads, "source cloud");
      cloud_ = &*copy_;
      if (copy_->size() < min_points) {
        throw InvalidInputError("source cloud has " + std::to_string(copy_->size()) +
                                " points on a voxel grid of " + std::to_string(voxel_size_m) +
                                " m, fewer than " + why_min + " " + std::to_string(min_points) +
                                ": use a smaller voxel size");
      }
    }
    if (cloud_->origin_m != origin_m) {
      copy_ = rebased(*cloud_, origin_m);
      cloud_ = &*copy_;
    }
    if (!needs_covariances(cost) || cloud_->has_covariances()) return;
    if (!copy_) copy_ = *cloud_;
    if (when == SurfaceEstimation::eager) {
      estimate_covariances(*copy_, neighborhood);
      cloud_ = &*copy_;
    } else {
      index_.emplace(std::move(*copy_));
      copy_.reset();
      cloud_ = &index_->cloud();
    }
  }
  PreparedSource(const PreparedSource&) = delete;
  PreparedSource& operator=(const PreparedSource&) = delete;

  [[nodiscard]] const PointCloud& cloud() const noexcept { return *cloud_; }
  /// The KD-tree over cloud() for lazily estimated covariances, or null when none are needed.
  [[nodiscard]] const ReferenceIndex* index() const noexcept { return index_ ? &*index_ : nullptr; }

 private:
  std::optional<PointCloud> copy_;       // re-based, or with the covariances estimated here
  std::optional<ReferenceIndex> index_;  // lazy: over the source, owning its points
  const PointCloud* cloud_;
};

/// The voxel grid a registration thins its source with (0 = none): the settings' size when set,
/// else the grid the reference index was thinned with (reference_index_for), so that both clouds
/// are on one grid. An index built from a cloud as given has none, and the source is then used
/// as given too: centroids paired with raw points would bias the point-to-point cost (4.9 mm on
/// a moved copy of the ETH map that both clouds at full resolution register to 1e-7 m).
inline double source_voxel_size(const ReferenceIndex& reference,
                                const DownsamplingSettings& downsampling) {
  return downsampling.voxel_size_m > 0.0 ? downsampling.voxel_size_m : reference.voxel_size_m();
}

/// The frame a registration runs in: the reference's stored coordinates, measured from its
/// origin_m (zero unless georeferenced); the source is re-based onto it (PreparedSource). The
/// transforms in and out are between the clouds' own frames.
class PairFrame {
 public:
  explicit PairFrame(const ReferenceIndex& reference) : origin_m_(reference.cloud().origin_m) {}
  [[nodiscard]] const Eigen::Vector3d& origin_m() const noexcept { return origin_m_; }
  /// T_reference_source between the clouds' frames -> between the stored coordinates.
  [[nodiscard]] Eigen::Matrix4d to_stored(const Eigen::Matrix4d& T) const {
    return origin_m_.isZero() ? T : between_stored(T, origin_m_, origin_m_);
  }
  /// A transform between the stored coordinates -> between the clouds' frames.
  [[nodiscard]] Eigen::Matrix4d to_clouds(const Eigen::Matrix4d& T) const {
    return origin_m_.isZero() ? T : between_frames(T, origin_m_, origin_m_);
  }
  /// The transforms of a finished run (result and trace) back into the clouds' frames.
  void to_clouds(RegistrationResult& result) const {
    if (origin_m_.isZero()) return;
    result.T_reference_source = between_frames(result.T_reference_source, origin_m_, origin_m_);
    for (auto& entry : result.trace) {
      entry.T_reference_source = between_frames(entry.T_reference_source, origin_m_, origin_m_);
    }
  }

 private:
  Eigen::Vector3d origin_m_;
};

/// Checks what every solver needs besides the source: a rigid initial transform and, unless
/// estimated on first use, the reference's normals or covariances for the cost.
inline void check_pair(const ReferenceIndex& reference, CostType cost,
                       const Eigen::Matrix4d& T_init, SurfaceEstimation when) {
  check_initial_transform(T_init);
  if (when == SurfaceEstimation::eager) check_reference_prepared(reference, cost);
}

/// The bulk of a cloud must lie within 1e9 m of its origin (no place on Earth is farther from a
/// georeferencing origin): beyond, squared distances in the single-precision KD-tree overflow
/// and every pair would be lost without a word. A few far points are fine (robust scaling).
inline void check_within_float_range(const BoundingBox& box, const char* which) {
  if (box.valid() && box.min.cwiseAbs().maxCoeff() <= kLargestCoordinate_m &&
      box.max.cwiseAbs().maxCoeff() <= kLargestCoordinate_m) {
    return;
  }
  throw InvalidInputError(std::string("the ") + which +
                          " cloud lies beyond 1e9 m from its origin (single-precision distances "
                          "would overflow): give the points in metres, near their frame's origin "
                          "or with an origin (PointCloud::origin_m)");
}

/// The paper's map of both clouds into the unit cube (scaling.hpp), from the bounding boxes of
/// every point or of the bulk of each cloud; the far points left out go into result.far_points.
[[nodiscard]] inline UnitCubeScaling scaling_of(const PointCloud& source,
                                                const ReferenceIndex& reference,
                                                const ScalingSettings& settings,
                                                RegistrationResult& result) {
  const ScalingOrigin origin = settings.origin;
  if (!settings.robust) {
    const BoundingBox source_box = BoundingBox::of(source);
    check_within_float_range(source_box, "source");
    check_within_float_range(reference.bounding_box(), "reference");
    return UnitCubeScaling::from_boxes(source_box, reference.bounding_box(), origin);
  }
  const ScalingBox source_box = bulk_bounding_box(source);
  const ScalingBox& reference_box = reference.bulk_bounding_box();
  result.far_points = source_box.far_points + reference_box.far_points;
  check_within_float_range(source_box.box, "source");
  check_within_float_range(reference_box.box, "reference");
  return UnitCubeScaling::from_boxes(source_box.box, reference_box.box, origin);
}

/// Ends a run: why it stopped, in the result.
inline void set_stop(RegistrationResult& result, StopReason reason, std::string message) {
  result.stop_reason = reason;
  result.converged = reason == StopReason::converged;
  result.message = std::move(message);
}

/// The message of a run that used up its iterations.
[[nodiscard]] inline std::string iteration_limit_message(std::size_t max_iterations) {
  return "reached the iteration limit of " + std::to_string(max_iterations) + " before converging";
}

/// evaluate_alignment, its inlier queries answered by `memory` (over `reference` and `source`)
/// where it certifies them: the same values, fewer searches.
void evaluate_alignment(const PointCloud& source, const ReferenceIndex& reference,
                        double max_distance_m, const EvaluationSettings& settings,
                        std::size_t num_threads, RegistrationResult& result,
                        const ReferenceNormals& normals, const NearestMemory* memory);

/// Fills the final statistics of result.T_reference_source (the run's evaluation group, on its
/// threads) and the time of the whole run; `memory` as for evaluate_alignment.
template <typename Settings>
void conclude(RegistrationResult& result, const PointCloud& source, const ReferenceIndex& reference,
              double max_distance_m, const Settings& settings, const Stopwatch& clock,
              const ReferenceNormals& normals = {}, const NearestMemory* memory = nullptr) {
  result.final_max_distance_m = max_distance_m;
  evaluate_alignment(source, reference, max_distance_m, settings.evaluation, settings.num_threads,
                     result, normals, memory);
  result.time_ms = clock.elapsed_ms();
}

/// The index over a registration's reference (registration_index): as given, or on its grid
/// with the surfaces of its voxel blocks when the cost reads them.
template <typename Settings, typename Cloud>
[[nodiscard]] ReferenceIndex grid_index(Cloud&& reference, const Settings& settings) {
  const KdTreeSettings tree{.num_threads = settings.num_threads};
  NeighborhoodSettings neighborhood = settings.neighborhood;
  neighborhood.num_threads = settings.num_threads;
  const bool surfaces = needs_reference_normals(settings.cost) || needs_covariances(settings.cost);
  return registration_index(std::forward<Cloud>(reference), settings.downsampling, neighborhood,
                            surfaces, tree);
}

/// The index of a reference given as a cloud (reference_index_for, the convenience overloads of
/// align() and align_batch()): on the settings' voxel grid, with what the cost needs unless the
/// solver estimates it on first use.
template <typename Settings, typename Cloud>
[[nodiscard]] ReferenceIndex index_for(Cloud&& reference, const Settings& settings,
                                       SurfaceEstimation when) {
  settings.validate();
  ReferenceIndex index = grid_index(std::forward<Cloud>(reference), settings);
  if (when == SurfaceEstimation::eager) {
    prepare_reference(index, settings.cost, settings.neighborhood);
  } else if (settings.num_threads != 1) {
    // The refinement stages pair nearly every point of the grid, which a lone thread estimates
    // one by one as pairs need them: with threads to spare, estimate them all at once. The same
    // estimator gives the same values, so the same result as one thread.
    NeighborhoodSettings threaded = settings.neighborhood;
    threaded.num_threads = settings.num_threads;
    prepare_reference(index, settings.cost, threaded);
  }
  return index;
}

/// What a run reports of the clouds it registered.
inline void record_clouds(RegistrationResult& result, const PointCloud& source,
                          double source_voxel_m, const ReferenceIndex& reference) {
  result.voxel_size_m = source_voxel_m;
  result.source_points = source.size();
  result.reference_points = reference.size();
}

}  // namespace sgdicp::detail
