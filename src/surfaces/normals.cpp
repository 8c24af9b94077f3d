#include "sgdicp/surfaces/normals.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/format_number.hpp"
#include "sgdicp/core/threads.hpp"
#include "surfaces/point_surfaces.hpp"
#include "surfaces/symmetric_eigen.hpp"
#include "util/parallel_chunks.hpp"

namespace sgdicp {
namespace detail {
namespace {

constexpr std::size_t kMinNeighbors = 3;
constexpr std::size_t kMaxNeighbors = 1000;
// A neighbourhood whose second-largest eigenvalue is below this fraction of the largest is a
// line (width < 1/1000 of its length): its normal is not defined.
constexpr double kCollinearRatio = 1e-6;
// describe_covariance: eigenvalue ratios below this are solved iteratively (see there).
constexpr double kDirectSolveRatio = 1e-3;
// Spreads below this many float ulps of the coordinates are rounding noise, not geometry.
constexpr double kResolutionUlps = 16.0;

// The neighbourhood summary of one point. Pure function of its inputs, hence identical
// results for any thread count.
PointSurface describe(const Eigen::Vector3f& point, const std::vector<Eigen::Vector3f>& points,
                      const std::vector<Neighbor>& neighbors, const NeighborhoodSettings& settings,
                      double* variation = nullptr) {
  const auto n = static_cast<double>(neighbors.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& nb : neighbors) mean += points[nb.index].cast<double>();
  mean /= n;
  // Two passes: centring first keeps the precision when the neighbourhood is far from the
  // origin (KITTI points lie up to 80 m away with cm spacing).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& nb : neighbors) {
    const Eigen::Vector3d d = points[nb.index].cast<double>() - mean;
    covariance.noalias() += d * d.transpose();
  }
  covariance /= n;
  return describe_covariance(point, mean, covariance, neighbors.size(), settings, variation);
}

}  // namespace

void check_neighborhood(const NeighborhoodSettings& settings) {
  if (settings.k < kMinNeighbors || settings.k > kMaxNeighbors) {
    throw InvalidSettingsError(
        "neighbourhood size k must be in [3, 1000] (it includes the "
        "point itself), got " +
        std::to_string(settings.k));
  }
  if (settings.flat_k != 0 &&
      (settings.flat_k < kMinNeighbors || settings.flat_k > kMaxNeighbors)) {
    throw InvalidSettingsError(
        "flat neighbourhood size flat_k must be 0 (off) or in [3, 1000], got " +
        std::to_string(settings.flat_k));
  }
  if (!(settings.flatness >= 0.0 && settings.flatness <= 1.0 / 3.0)) {
    throw InvalidSettingsError(
        "flatness (the largest surface variation of a flat neighbourhood) must be in [0, 1/3], "
        "got " +
        format_number(settings.flatness));
  }
  if (!std::isfinite(settings.epsilon) || settings.epsilon <= 0.0 || settings.epsilon > 1.0) {
    throw InvalidSettingsError("covariance regularization epsilon must be in (0, 1], got " +
                               format_number(settings.epsilon));
  }
  if (settings.num_threads > kMaxThreads) {
    throw InvalidSettingsError("number of threads must be at most " + std::to_string(kMaxThreads) +
                               " (0 = all cores), got " + std::to_string(settings.num_threads));
  }
  if (!settings.viewpoint.allFinite()) {
    throw InvalidSettingsError("normal viewpoint must be finite");
  }
}

PointSurface describe_covariance(const Eigen::Vector3f& point, const Eigen::Vector3d& mean,
                                 const Eigen::Matrix3d& covariance, std::size_t count,
                                 const NeighborhoodSettings& settings, double* variation,
                                 double* linearity) {
  // The closed form costs a fraction of the iterative solver, but its smallest eigenvector
  // loses precision when the two smallest eigenvalues are close (a line, a point, a blob):
  // those neighbourhoods are solved again iteratively.
  detail::SmallestEigenpair direct = detail::smallest_eigenpair(covariance);
  bool solved = true;
  if (!(direct.values[1] - direct.values[0] > kDirectSolveRatio * direct.values[2])) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    solved = solver.info() == Eigen::Success;
    direct = {solver.eigenvalues(), solver.eigenvectors().col(0)};
  }
  const Eigen::Vector3d& eigenvalues = direct.values;  // ascending
  const double resolution = kResolutionUlps * FLT_EPSILON * mean.cwiseAbs().maxCoeff();
  const double floor = resolution * resolution;
  // Negated comparisons so that a NaN (which cannot arise from finite input) is degenerate too.
  const bool degenerate = count < kMinNeighbors || !solved ||
                          !(direct.vector.squaredNorm() > 0.5) || !(eigenvalues[2] > floor) ||
                          !(eigenvalues[1] > std::max(floor, kCollinearRatio * eigenvalues[2]));

  if (variation != nullptr) {
    *variation =
        degenerate ? std::numeric_limits<double>::infinity() : eigenvalues[0] / eigenvalues.sum();
  }
  if (linearity != nullptr) {
    const bool spread = count >= kMinNeighbors && solved && eigenvalues[2] > 0.0;
    *linearity = spread ? (eigenvalues[2] - std::max(eigenvalues[1], 0.0)) / eigenvalues[2]
                        : std::numeric_limits<double>::quiet_NaN();
  }
  PointSurface out;
  if (degenerate) {
    out.normal.setZero();
    out.covariance = settings.regularize ? Eigen::Matrix3f::Identity()
                                         : Eigen::Matrix3f(covariance.cast<float>());
    return out;
  }
  Eigen::Vector3d normal = direct.vector.normalized();
  if (normal.dot(settings.viewpoint.cast<double>() - point.cast<double>()) < 0.0) normal = -normal;
  out.normal = normal.cast<float>();
  if (settings.regularize) {
    // V diag(eps, 1, 1) V^T = I - (1 - eps) n n^T for orthonormal V: exactly symmetric, and
    // the eigenvalues are (eps, 1, 1) to rounding.
    const Eigen::Matrix3d plane =
        Eigen::Matrix3d::Identity() - (1.0 - settings.epsilon) * normal * normal.transpose();
    out.covariance = plane.cast<float>();
  } else {
    out.covariance = covariance.cast<float>();
  }
  return out;
}

NeighborhoodSettings in_stored_frame(const NeighborhoodSettings& settings,
                                     const PointCloud& cloud) {
  NeighborhoodSettings stored = settings;
  stored.viewpoint = (settings.viewpoint.cast<double>() - cloud.origin_m).cast<float>();
  return stored;
}

PointSurface estimate_surface(const ReferenceIndex& index, std::size_t i,
                              const NeighborhoodSettings& stored,
                              std::vector<Neighbor>& neighbors) {
  const std::vector<Eigen::Vector3f>& points = index.cloud().points;
  const std::size_t k = std::min(stored.k, points.size());
  if (stored.flat_k != 0 && stored.flat_k < k) {
    index.k_nearest(points[i], stored.flat_k, neighbors);
    double variation = 0.0;
    const PointSurface flat = describe(points[i], points, neighbors, stored, &variation);
    if (variation <= stored.flatness) return flat;
  }
  index.k_nearest(points[i], k, neighbors);
  return describe(points[i], points, neighbors, stored);
}

}  // namespace detail

using detail::check_neighborhood;
using detail::parallel_chunks;
using detail::PointSurface;
using detail::resolve_threads;

namespace {

void validate(const PointCloud& cloud) {
  if (cloud.empty()) throw InvalidInputError("cannot estimate normals of an empty cloud");
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.points[i].allFinite()) {
      throw InvalidInputError("cloud has a non-finite point at index " + std::to_string(i));
    }
  }
}

void validate_index(const PointCloud& cloud, const ReferenceIndex& index) {
  const auto& indexed = index.cloud().points;
  if (indexed.size() != cloud.size()) {
    throw InvalidInputError("kd-tree was built over " + std::to_string(indexed.size()) +
                            " points but the cloud has " + std::to_string(cloud.size()));
  }
  // Cheap next to the k-nearest queries, and a different cloud of the same size would
  // otherwise give silently wrong neighbourhoods.
  for (std::size_t i = 0; i < indexed.size(); ++i) {
    if (indexed[i] != cloud.points[i]) {
      throw InvalidInputError(
          "kd-tree was built over different points than the cloud (first "
          "difference at index " +
          std::to_string(i) + ")");
    }
  }
}

// The surfaces of the points `which` (all when null) of the indexed cloud, in that order.
void estimate_at(const ReferenceIndex& index, const std::vector<std::uint32_t>* which,
                 const NeighborhoodSettings& stored, std::size_t num_threads,
                 std::vector<Eigen::Vector3f>& normals, std::vector<Eigen::Matrix3f>* covariances) {
  const std::size_t n = which ? which->size() : index.size();
  normals.resize(n);
  if (covariances) covariances->resize(n);
  parallel_chunks(n, resolve_threads(num_threads, n), [&](std::size_t begin, std::size_t end) {
    std::vector<Neighbor> neighbors;  // one per thread, reused
    for (std::size_t j = begin; j < end; ++j) {
      const std::size_t i = which ? (*which)[j] : j;
      const PointSurface s = detail::estimate_surface(index, i, stored, neighbors);
      normals[j] = s.normal;
      if (covariances) (*covariances)[j] = s.covariance;
    }
  });
}

void estimate(PointCloud& cloud, const ReferenceIndex& index, const NeighborhoodSettings& settings,
              bool with_covariances) {
  std::vector<Eigen::Vector3f> normals;
  std::vector<Eigen::Matrix3f> covariances;
  estimate_at(index, nullptr, detail::in_stored_frame(settings, cloud), settings.num_threads,
              normals, with_covariances ? &covariances : nullptr);
  // Only now touch the cloud, so that it is unchanged if anything above threw.
  cloud.normals = std::move(normals);
  if (with_covariances) cloud.covariances = std::move(covariances);
}

ReferenceIndex build_index(const PointCloud& cloud) {
  PointCloud points_only;
  points_only.points = cloud.points;
  points_only.origin_m = cloud.origin_m;
  return ReferenceIndex(std::move(points_only));
}

}  // namespace

void NeighborhoodSettings::validate() const {
  check_neighborhood(*this);
}

void estimate_covariances(PointCloud& cloud, const NeighborhoodSettings& settings) {
  check_neighborhood(settings);
  validate(cloud);
  estimate(cloud, build_index(cloud), settings, true);
}

void estimate_covariances(PointCloud& cloud, const ReferenceIndex& index,
                          const NeighborhoodSettings& settings) {
  check_neighborhood(settings);
  validate(cloud);
  validate_index(cloud, index);
  estimate(cloud, index, settings, true);
}

void estimate_normals(PointCloud& cloud, const NeighborhoodSettings& settings) {
  check_neighborhood(settings);
  validate(cloud);
  estimate(cloud, build_index(cloud), settings, false);
}

void estimate_normals(PointCloud& cloud, const ReferenceIndex& index,
                      const NeighborhoodSettings& settings) {
  check_neighborhood(settings);
  validate(cloud);
  validate_index(cloud, index);
  estimate(cloud, index, settings, false);
}

PointCloud subset_with_surfaces(const PointCloud& cloud, const std::vector<std::uint32_t>& which,
                                const NeighborhoodSettings& settings, bool with_covariances) {
  check_neighborhood(settings);
  PointCloud out;
  out.origin_m = cloud.origin_m;
  if (which.empty()) return out;
  validate(cloud);
  out.points.reserve(which.size());
  for (const std::uint32_t i : which) {
    if (i >= cloud.size()) {
      throw InvalidInputError("subset_with_surfaces: index " + std::to_string(i) +
                              " beyond the cloud's " + std::to_string(cloud.size()) + " points");
    }
    out.points.push_back(cloud.points[i]);
  }
  estimate_at(build_index(cloud), &which, detail::in_stored_frame(settings, cloud),
              settings.num_threads, out.normals, with_covariances ? &out.covariances : nullptr);
  return out;
}

}  // namespace sgdicp
