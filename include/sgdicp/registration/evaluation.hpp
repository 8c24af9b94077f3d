#pragma once
// The statistics every registration reports at its end, whatever the method (one place for
// all solvers): inliers and their RMS distance on a sample of the source, and a check
// for degenerate geometry.
//
// Degeneracy: with the pairs of the final alignment, the point-to-plane information matrix
// H = sum_i J_i^T J_i, J_i = n_i^T [I | -[q_i]x] (n_i the reference normal, q_i the moved source
// point relative to the pairs' centroid, in units of their RMS spread so that translations and
// rotations weigh alike), has a near-zero eigenvalue for every motion the data does not constrain:
// two translations and a rotation on a single plane, the axis of a corridor or a cylinder. We
// report the smallest over the largest eigenvalue; the result is flagged degenerate below 0.01.
// The check always runs: switching it off changed no pose and saved at most a few percent of a
// run (docs/registration.md, *Why each setting is there*).
#include <cstddef>
#include <cstdint>
#include <functional>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/result.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"

namespace sgdicp {

/// What a user chooses of the final statistics; the degeneracy check's constants are
/// evaluation.cpp's, its threads and normals come from the registration.
struct EvaluationSettings {
  /// Source points to evaluate (spread by a golden-ratio sequence); 0 = all.
  std::size_t evaluation_points = 2000;

  bool operator==(const EvaluationSettings&) const = default;
};

/// The unit normal of reference point i (or zero where the surface defines none).
using ReferenceNormals = std::function<Eigen::Vector3f(std::uint32_t)>;

/// Fills result.evaluated_points, inliers, inlier_ratio, inlier_rmse_m, constraint_ratio and
/// degenerate for the transform in result.T_reference_source and pairs within max_distance_m.
/// The inlier queries run on one thread for num_threads 1, else in two halves on two threads (a
/// registration passes its own num_threads); the same values for any count, since the sums are
/// made in sample order on the calling thread. The degeneracy check takes the reference normals
/// from `normals` when given (a registration's own, so that they are the ones its cost used),
/// else from the cloud, else from 10 neighbours by the estimator of estimate_normals.
void evaluate_alignment(const PointCloud& source, const ReferenceIndex& reference,
                        double max_distance_m, const EvaluationSettings& settings,
                        std::size_t num_threads, RegistrationResult& result,
                        const ReferenceNormals& normals = {});

/// The fraction of (at most max_points, evenly strided) source points that T_reference_source
/// puts within radius_m of a reference point: how much of the source the reference covers
/// there. 0 for an empty source or a non-finite T. The odometry judges a frame by it against the
/// frames before it; the global registration scores its hypotheses by it.
[[nodiscard]] double overlap_fraction(const PointCloud& source, const ReferenceIndex& reference,
                                      const Eigen::Matrix4d& T_reference_source, double radius_m,
                                      std::size_t max_points);

}  // namespace sgdicp
