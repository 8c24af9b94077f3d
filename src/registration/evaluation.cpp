#include "sgdicp/registration/evaluation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include <Eigen/Eigenvalues>

#include "index/nearest_memory.hpp"
#include "registration/solver_support.hpp"
#include "sgdicp/core/threads.hpp"
#include "surfaces/point_surfaces.hpp"
#include "util/helper_thread.hpp"

namespace sgdicp {
namespace {

// The degeneracy check's constants; it always runs, so they are not settings.
// Ratio below which the geometry is reported degenerate (unitless). Measured: 0.08-0.23 on the
// real pairs of shared/data, 1e-6 to 3e-3 on a synthetic plane, line, pipe and corridor.
constexpr double kDegenerateBelow = 1e-2;
// Pairs (spread like the samples) the check uses: a thousand pin the eigenvalues down well; more
// only cost k-nearest queries.
constexpr std::size_t kDegeneracyPairs = 1000;
// Neighbours for a reference normal that neither the registration nor the cloud gives (the
// estimator of estimate_normals).
constexpr std::size_t kNormalNeighbors = 10;

// The k-th of `count` sample indices in [0, n): the golden-ratio (Kronecker) sequence spreads
// them evenly without the aliasing a fixed stride has on data in a periodic order (scan rings,
// interleaved surfaces).
std::size_t sample_index(std::size_t k, std::size_t count, std::size_t n) {
  if (count >= n) return k;
  const double phase = std::fmod(static_cast<double>(k) * 0.6180339887498949, 1.0);
  return std::min(n - 1, static_cast<std::size_t>(phase * static_cast<double>(n)));
}

// Unit normal of the reference at point `index`: from the cloud when it has normals, else from
// its k nearest neighbours by the library's one estimator (zero when they span no plane).
Eigen::Vector3d reference_normal(const ReferenceIndex& reference, std::uint32_t index,
                                 const NeighborhoodSettings& stored,
                                 std::vector<Neighbor>& scratch) {
  const PointCloud& cloud = reference.cloud();
  if (cloud.has_normals()) return cloud.normals[index].cast<double>();
  return detail::estimate_surface(reference, index, stored, scratch).normal.cast<double>();
}

// Fewer inlier queries than this are not worth waking a helper thread for; the queries are made
// in blocks of kSampleBlock (their results held until summed in order).
constexpr std::size_t kMinSamplesToSplit = 256;
constexpr std::size_t kSampleBlock = 4096;

// A source point moved into the reference frame and its nearest reference point.
struct Pair {
  Eigen::Vector3d moved;
  std::uint32_t reference_index;
};

// The source under the transform being evaluated, in floats as the index stores the reference.
struct MovedSource {
  const PointCloud& cloud;
  Eigen::Matrix3f R_reference_source;
  Eigen::Vector3f t_reference_source_m;
  float max_sq;                         // squared pair distance limit, m^2
  const detail::NearestMemory* memory;  // the run's, or null

  [[nodiscard]] std::size_t size() const { return cloud.size(); }
  [[nodiscard]] Eigen::Vector3f point(std::size_t i) const {
    return R_reference_source * cloud.points[i] + t_reference_source_m;
  }
};

// Counts the inliers among `samples` spread source points and fills evaluated_points, inliers,
// inlier_ratio and inlier_rmse_m; returns the pairs (for the degeneracy check).
std::vector<Pair> count_inliers(const MovedSource& source, const ReferenceIndex& reference,
                                std::size_t samples, std::size_t threads,
                                RegistrationResult& result) {
  const std::size_t n = source.size();
  const bool split = resolve_thread_count(threads) >= 2;
  // The queries (most of the evaluation) into one slot per sample of a block, in two halves on
  // two threads; the sums follow in sample order here, so the values do not depend on the
  // thread count.
  std::vector<Eigen::Vector3f> moved(std::min(samples, kSampleBlock));
  std::vector<std::optional<Neighbor>> found(moved.size());
  std::vector<Pair> pairs;
  double sum_sq = 0.0;
  result.evaluated_points = samples;
  for (std::size_t first = 0; first < samples; first += kSampleBlock) {
    const std::size_t count = std::min(kSampleBlock, samples - first);
    const auto query = [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        const std::size_t i = sample_index(first + k, samples, n);
        moved[k] = source.point(i);
        // The run's memory answers a point it certifies without the tree (a small source, drawn
        // many times, ends near where it was last queried): the tree's answer, bit for bit.
        detail::NearestMemory::Entry unused;
        found[k] = source.memory != nullptr
                       ? source.memory->nearest(static_cast<std::uint32_t>(i), moved[k],
                                                source.max_sq, unused)
                       : reference.nearest(moved[k], source.max_sq);
      }
    };
    if (split && count >= kMinSamplesToSplit) {
      const std::array<std::size_t, 3> halves{0, count / 2, count};
      detail::run_ranges(halves, query);
    } else {
      query(0, count);
    }
    for (std::size_t k = 0; k < count; ++k) {
      if (const auto& nn = found[k]) {
        sum_sq += nn->squared_distance;
        pairs.push_back({moved[k].cast<double>(), nn->index});
        ++result.inliers;
      }
    }
  }
  result.inlier_ratio =
      result.evaluated_points > 0
          ? static_cast<double>(result.inliers) / static_cast<double>(result.evaluated_points)
          : 0.0;
  result.inlier_rmse_m =
      result.inliers > 0 ? std::sqrt(sum_sq / static_cast<double>(result.inliers)) : 0.0;
  return pairs;
}

// The pairs of `wanted` spread source points within the distance limit.
std::vector<Pair> sample_pairs(const MovedSource& source, const ReferenceIndex& reference,
                               std::size_t wanted) {
  std::vector<Pair> pairs;
  for (std::size_t k = 0; k < wanted; ++k) {
    const Eigen::Vector3f moved = source.point(sample_index(k, wanted, source.size()));
    if (const auto nn = reference.nearest(moved, source.max_sq)) {
      pairs.push_back({moved.cast<double>(), nn->index});
    }
  }
  return pairs;
}

void mark_degenerate(RegistrationResult& result, const char* why) {
  result.degenerate = true;
  result.constraint_ratio = 0.0;
  result.message += why;
}

// The 6x6 information matrix of point-to-plane constraints at (a spread sample of) the pairs,
// rotations about `centroid` with lever arms in units of `spread`.
Eigen::Matrix<double, 6, 6> constraint_matrix(const std::vector<Pair>& pairs,
                                              const Eigen::Vector3d& centroid, double spread,
                                              const ReferenceIndex& reference,
                                              const ReferenceNormals& normals) {
  Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
  std::vector<Neighbor> scratch;
  const NeighborhoodSettings stored =
      detail::in_stored_frame({.k = kNormalNeighbors}, reference.cloud());
  const std::size_t used = std::min(pairs.size(), kDegeneracyPairs);
  for (std::size_t k = 0; k < used; ++k) {
    const auto& p = pairs[sample_index(k, used, pairs.size())];
    const Eigen::Vector3d normal =
        normals ? normals(p.reference_index).cast<double>()
                : reference_normal(reference, p.reference_index, stored, scratch);
    const Eigen::Vector3d q = (p.moved - centroid) / spread;
    Eigen::Matrix<double, 6, 1> j;
    j << normal, q.cross(normal);
    h.noalias() += j * j.transpose();
  }
  return h;
}

// Fills constraint_ratio and degenerate from the pairs of the final alignment.
void measure_degeneracy(const std::vector<Pair>& pairs, const ReferenceIndex& reference,
                        const ReferenceNormals& normals, RegistrationResult& result) {
  if (pairs.size() < 6) {
    mark_degenerate(result, "; degenerate: fewer than 6 pairs in the final alignment");
    return;
  }
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : pairs) centroid += p.moved;
  centroid /= static_cast<double>(pairs.size());
  // Lever arms in units of the pairs' RMS spread, so that a rotation moves the points about as
  // much as a unit translation and the eigenvalues of both kinds compare.
  double spread_sq = 0.0;
  for (const auto& p : pairs) spread_sq += (p.moved - centroid).squaredNorm();
  const double spread = std::sqrt(spread_sq / static_cast<double>(pairs.size()));
  if (!(spread > 0.0)) {
    mark_degenerate(result, "; degenerate: all pairs at one point");
    return;
  }
  const Eigen::Matrix<double, 6, 6> h =
      constraint_matrix(pairs, centroid, spread, reference, normals);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(h, Eigen::EigenvaluesOnly);
  const double largest = eig.eigenvalues()[5];
  result.constraint_ratio = largest > 0.0 ? std::max(0.0, eig.eigenvalues()[0]) / largest : 0.0;
  result.degenerate = result.constraint_ratio < kDegenerateBelow;
  if (result.degenerate) {
    char note[160];
    std::snprintf(note, sizeof(note),
                  "; degenerate geometry (constraint ratio %.2g < %.2g): some motion is not "
                  "constrained by the data",
                  result.constraint_ratio, kDegenerateBelow);
    result.message += note;
  }
}

}  // namespace

void evaluate_alignment(const PointCloud& source, const ReferenceIndex& reference,
                        double max_distance_m, const EvaluationSettings& settings,
                        std::size_t num_threads, RegistrationResult& result,
                        const ReferenceNormals& normals) {
  detail::evaluate_alignment(source, reference, max_distance_m, settings, num_threads, result,
                             normals, nullptr);
}

void detail::evaluate_alignment(const PointCloud& source, const ReferenceIndex& reference,
                                double max_distance_m, const EvaluationSettings& settings,
                                std::size_t num_threads, RegistrationResult& result,
                                const ReferenceNormals& normals, const NearestMemory* memory) {
  const std::size_t n = source.size();
  const std::size_t samples =
      settings.evaluation_points == 0 ? n : std::min(n, settings.evaluation_points);
  const MovedSource moved_source{source,
                                 result.T_reference_source.topLeftCorner<3, 3>().cast<float>(),
                                 result.T_reference_source.topRightCorner<3, 1>().cast<float>(),
                                 static_cast<float>(max_distance_m * max_distance_m), memory};
  std::vector<Pair> pairs = count_inliers(moved_source, reference, samples, num_threads, result);
  // A small evaluation sample (evaluation_points 1, say) does not decide the geometry: the check
  // draws its own sample then.
  const std::size_t wanted = std::min(n, kDegeneracyPairs);
  if (samples < wanted) pairs = sample_pairs(moved_source, reference, wanted);
  measure_degeneracy(pairs, reference, normals, result);
}

double overlap_fraction(const PointCloud& source, const ReferenceIndex& reference,
                        const Eigen::Matrix4d& T_reference_source, double radius_m,
                        std::size_t max_points) {
  if (source.empty() || !T_reference_source.allFinite()) return 0.0;
  const std::size_t stride =
      std::max<std::size_t>(1, source.size() / std::max<std::size_t>(1, max_points));
  const Eigen::Matrix3d R = T_reference_source.topLeftCorner<3, 3>();
  const Eigen::Vector3d t = T_reference_source.topRightCorner<3, 1>();
  const auto radius2 = static_cast<float>(radius_m * radius_m);
  std::size_t near = 0;
  std::size_t looked = 0;
  for (std::size_t i = 0; i < source.size(); i += stride, ++looked) {
    const Eigen::Vector3f p = (R * source.points[i].cast<double>() + t).cast<float>();
    near += reference.nearest(p, radius2) ? 1 : 0;
  }
  return static_cast<double>(near) / static_cast<double>(looked);
}

}  // namespace sgdicp
