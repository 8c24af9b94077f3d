#include "sgdicp/preprocessing.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <exception>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include <Eigen/Eigenvalues>

#include "point_surfaces.hpp"
#include "sgdicp/error.hpp"
#include "sgdicp/threads.hpp"

namespace sgdicp {
namespace {

constexpr std::size_t kMinNeighbors = 3;
constexpr std::size_t kMaxNeighbors = 1000;
// Fewer points per thread than this are not worth a thread start (~tens of microseconds).
constexpr std::size_t kMinPointsPerThread = 512;
// A neighbourhood whose second-largest eigenvalue is below this fraction of the largest is a
// line (width < 1/1000 of its length): its normal is not defined.
constexpr double kCollinearRatio = 1e-6;
// Spreads below this many float ulps of the coordinates are rounding noise, not geometry.
constexpr double kResolutionUlps = 16.0;

std::string format_number(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

void check_neighborhood(const NeighborhoodSettings& settings) {
  if (settings.k < kMinNeighbors || settings.k > kMaxNeighbors) {
    throw InvalidSettingsError(
        "neighbourhood size k must be in [3, 1000] (it includes the "
        "point itself), got " +
        std::to_string(settings.k));
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

std::size_t resolve_threads(std::size_t requested, std::size_t num_points) {
  const std::size_t threads = resolve_thread_count(requested);
  const std::size_t useful = (num_points + kMinPointsPerThread - 1) / kMinPointsPerThread;
  return std::clamp<std::size_t>(useful, 1, threads);
}

// Runs body(begin, end) over contiguous chunks of [0, n) on `threads` threads (the calling
// thread takes the first chunk) and rethrows the first exception after all have joined.
template <class Body>
void parallel_chunks(std::size_t n, std::size_t threads, const Body& body) {
  std::vector<std::exception_ptr> errors(threads);
  auto run = [&](std::size_t t) {
    try {
      body(n * t / threads, n * (t + 1) / threads);
    } catch (...) {
      errors[t] = std::current_exception();
    }
  };
  {
    std::vector<std::jthread> workers;
    workers.reserve(threads - 1);
    for (std::size_t t = 1; t < threads; ++t) workers.emplace_back(run, t);
    run(0);
  }  // jthreads join here
  for (const auto& error : errors) {
    if (error) std::rethrow_exception(error);
  }
}

using detail::PointSurface;

// The neighbourhood summary of one point. Pure function of its inputs, hence identical
// results for any thread count.
PointSurface describe(const Eigen::Vector3f& point, const std::vector<Eigen::Vector3f>& points,
                      const std::vector<Neighbor>& neighbors,
                      const NeighborhoodSettings& settings) {
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

  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3d& eigenvalues = solver.eigenvalues();  // ascending
  const double resolution = kResolutionUlps * FLT_EPSILON * mean.cwiseAbs().maxCoeff();
  const double floor = resolution * resolution;
  // Negated comparisons so that a NaN (which cannot arise from finite input) is degenerate too.
  const bool degenerate = neighbors.size() < kMinNeighbors || solver.info() != Eigen::Success ||
                          !(eigenvalues[2] > floor) ||
                          !(eigenvalues[1] > std::max(floor, kCollinearRatio * eigenvalues[2]));

  PointSurface out;
  if (degenerate) {
    out.normal.setZero();
    out.covariance = settings.regularize ? Eigen::Matrix3f::Identity()
                                         : Eigen::Matrix3f(covariance.cast<float>());
    return out;
  }
  Eigen::Vector3d normal = solver.eigenvectors().col(0).normalized();
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

void estimate(PointCloud& cloud, const ReferenceIndex& index, const NeighborhoodSettings& settings,
              bool with_covariances) {
  const NeighborhoodSettings stored = detail::in_stored_frame(settings, cloud);
  const std::size_t n = cloud.size();
  std::vector<Eigen::Vector3f> normals(n);
  std::vector<Eigen::Matrix3f> covariances(with_covariances ? n : 0);
  parallel_chunks(n, resolve_threads(settings.num_threads, n),
                  [&](std::size_t begin, std::size_t end) {
                    std::vector<Neighbor> neighbors;  // one per thread, reused
                    for (std::size_t i = begin; i < end; ++i) {
                      const PointSurface s = detail::estimate_surface(index, i, stored, neighbors);
                      normals[i] = s.normal;
                      if (with_covariances) covariances[i] = s.covariance;
                    }
                  });
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

// ---- voxel grid ----

struct VoxelKey {
  std::int64_t x = 0;
  std::int64_t y = 0;
  std::int64_t z = 0;
  bool operator==(const VoxelKey&) const = default;
};

std::uint64_t mix(std::uint64_t h) {  // splitmix64 finaliser
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  h ^= h >> 31;
  return h;
}

struct VoxelKeyHash {
  std::size_t operator()(const VoxelKey& key) const noexcept {
    std::uint64_t h = mix(static_cast<std::uint64_t>(key.x));
    h = mix(h ^ static_cast<std::uint64_t>(key.y));
    h = mix(h ^ static_cast<std::uint64_t>(key.z));
    return static_cast<std::size_t>(h);
  }
};

// Voxel indices stay well inside int64 so that neighbouring-voxel arithmetic by callers and
// the conversion below can never overflow.
constexpr double kMaxVoxelIndex = 0x1p62;

std::int64_t voxel_index(float coordinate, double voxel_size_m) {
  const double index = std::floor(static_cast<double>(coordinate) / voxel_size_m);
  if (!(std::abs(index) < kMaxVoxelIndex)) {
    throw InvalidSettingsError("voxel size " + format_number(voxel_size_m) +
                               " m is too small for coordinate " + format_number(coordinate) +
                               " m: voxel indices would exceed 2^62");
  }
  return static_cast<std::int64_t>(index);
}

// ---- random subsets ----

// Uniform integer in [0, bound): reject the top partial block so that the modulo is unbiased
// (same scheme as EpochSampler, independent of the standard library's distributions).
std::uint64_t bounded(std::mt19937_64& rng, std::uint64_t bound) {
  const std::uint64_t limit = std::mt19937_64::max() - std::mt19937_64::max() % bound;
  std::uint64_t x = rng();
  while (x >= limit) x = rng();
  return x % bound;
}

void validate_attributes(const PointCloud& cloud) {
  if (!cloud.normals.empty() && cloud.normals.size() != cloud.size()) {
    throw InvalidInputError("cloud has " + std::to_string(cloud.normals.size()) + " normals for " +
                            std::to_string(cloud.size()) + " points");
  }
  if (!cloud.covariances.empty() && cloud.covariances.size() != cloud.size()) {
    throw InvalidInputError("cloud has " + std::to_string(cloud.covariances.size()) +
                            " covariances for " + std::to_string(cloud.size()) + " points");
  }
}

}  // namespace

namespace detail {

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
  index.k_nearest(points[i], std::min(stored.k, points.size()), neighbors);
  return describe(points[i], points, neighbors, stored);
}

}  // namespace detail

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

PointCloud voxel_downsample(const PointCloud& cloud, double voxel_size_m) {
  if (!std::isfinite(voxel_size_m) || voxel_size_m <= 0.0) {
    throw InvalidSettingsError("voxel size must be positive and finite, got " +
                               format_number(voxel_size_m) + " m");
  }
  std::unordered_map<VoxelKey, std::size_t, VoxelKeyHash> slot_of;  // voxel -> output slot
  std::vector<Eigen::Vector3d> sums;
  std::vector<std::size_t> counts;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!p.allFinite()) {
      throw InvalidInputError("cloud has a non-finite point at index " + std::to_string(i));
    }
    const VoxelKey key{voxel_index(p.x(), voxel_size_m), voxel_index(p.y(), voxel_size_m),
                       voxel_index(p.z(), voxel_size_m)};
    const auto [it, inserted] = slot_of.try_emplace(key, sums.size());
    if (inserted) {
      sums.emplace_back(Eigen::Vector3d::Zero());
      counts.push_back(0);
    }
    sums[it->second] += p.cast<double>();
    ++counts[it->second];
  }
  PointCloud out;
  out.origin_m = cloud.origin_m;
  out.points.reserve(sums.size());
  // Rounding is monotone, so the float centroid stays within its points' range: in their voxel.
  for (std::size_t v = 0; v < sums.size(); ++v) {
    out.points.emplace_back((sums[v] / static_cast<double>(counts[v])).cast<float>());
  }
  return out;
}

PointCloud random_downsample(const PointCloud& cloud, std::size_t count, std::uint64_t seed) {
  validate_attributes(cloud);
  const std::size_t n = cloud.size();
  if (count >= n) return cloud;
  PointCloud out;
  out.origin_m = cloud.origin_m;
  out.points.reserve(count);
  if (cloud.has_normals()) out.normals.reserve(count);
  if (cloud.has_covariances()) out.covariances.reserve(count);
  // Selection sampling (Knuth's Algorithm S): point i is kept with probability
  // needed / remaining, which makes every subset of size `count` equally likely and keeps
  // input order without sorting.
  std::mt19937_64 rng(seed);
  std::size_t needed = count;
  for (std::size_t i = 0; i < n && needed > 0; ++i) {
    if (bounded(rng, n - i) < needed) {
      out.points.push_back(cloud.points[i]);
      if (cloud.has_normals()) out.normals.push_back(cloud.normals[i]);
      if (cloud.has_covariances()) out.covariances.push_back(cloud.covariances[i]);
      --needed;
    }
  }
  return out;
}

PointCloud random_downsample_ratio(const PointCloud& cloud, double ratio, std::uint64_t seed) {
  if (!std::isfinite(ratio) || ratio <= 0.0 || ratio > 1.0) {
    throw InvalidSettingsError("downsampling ratio must be in (0, 1], got " + format_number(ratio));
  }
  const double wanted = std::round(ratio * static_cast<double>(cloud.size()));
  const auto count = std::max<std::size_t>(static_cast<std::size_t>(wanted), 1);
  return random_downsample(cloud, count, seed);
}

void prepare_reference(ReferenceIndex& reference, CostType cost,
                       const NeighborhoodSettings& neighborhood) {
  const PointCloud& cloud = reference.cloud();
  const bool missing = (needs_reference_normals(cost) && !cloud.has_normals()) ||
                       (needs_covariances(cost) && !cloud.has_covariances());
  if (!missing) return;
  // The tree points at the index's own points, so estimate into a copy and hand the results over.
  PointCloud copy;
  copy.points = cloud.points;
  estimate_covariances(copy, reference, neighborhood);
  reference.set_normals_and_covariances(std::move(copy.normals), std::move(copy.covariances));
}

void check_reference_prepared(const ReferenceIndex& reference, CostType cost) {
  const PointCloud& cloud = reference.cloud();
  if ((needs_reference_normals(cost) && !cloud.has_normals()) ||
      (needs_covariances(cost) && !cloud.has_covariances())) {
    throw InvalidInputError("the " + std::string(to_string(cost)) + " cost needs reference " +
                            (needs_covariances(cost) ? "covariances" : "normals") +
                            ": call prepare_reference(index, cost) first (or pass the reference "
                            "cloud to align(), which does it)");
  }
}

}  // namespace sgdicp
