#include "sgdicp/preprocessing.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <compare>
#include <exception>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "checks.hpp"
#include "helper_thread.hpp"
#include "point_surfaces.hpp"
#include "recycling_allocator.hpp"
#include "sgdicp/error.hpp"
#include "sgdicp/scaling.hpp"
#include "sgdicp/threads.hpp"
#include "symmetric_eigen.hpp"

namespace sgdicp {
namespace {

constexpr std::size_t kMinNeighbors = 3;
constexpr std::size_t kMaxNeighbors = 1000;
// Fewer points per thread than this are not worth a thread start (~tens of microseconds).
constexpr std::size_t kMinPointsPerThread = 512;
// A neighbourhood whose second-largest eigenvalue is below this fraction of the largest is a
// line (width < 1/1000 of its length): its normal is not defined.
constexpr double kCollinearRatio = 1e-6;
// describe_covariance: eigenvalue ratios below this are solved iteratively (see there).
constexpr double kDirectSolveRatio = 1e-3;
// Spreads below this many float ulps of the coordinates are rounding noise, not geometry.
constexpr double kResolutionUlps = 16.0;
// voxel_size_for_count: counting passes at most, and the relative error in the count that
// ends the search early (the count is a budget, not a contract).
constexpr int kVoxelSearchPasses = 6;
constexpr double kVoxelCountTolerance = 0.15;

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
// thread takes the first chunk, its helpers the others: helper_thread.hpp) and rethrows the
// first exception after all have ended.
template <class Body>
void parallel_chunks(std::size_t n, std::size_t threads, const Body& body) {
  std::vector<std::size_t> bounds(threads + 1);
  for (std::size_t t = 0; t <= threads; ++t) bounds[t] = n * t / threads;
  detail::run_ranges(bounds, body);
}

using detail::largest_coordinate;
using detail::PointSurface;

// `variation`, when given, receives the surface variation lambda_0 / (lambda_0 + lambda_1 +
// lambda_2) of the covariance, or infinity for a degenerate neighbourhood.
PointSurface describe_covariance(const Eigen::Vector3f& point, const Eigen::Vector3d& mean,
                                 const Eigen::Matrix3d& covariance, std::size_t count,
                                 const NeighborhoodSettings& settings, double* variation = nullptr);

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

PointSurface describe_covariance(const Eigen::Vector3f& point, const Eigen::Vector3d& mean,
                                 const Eigen::Matrix3d& covariance, std::size_t count,
                                 const NeighborhoodSettings& settings, double* variation) {
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
  auto operator<=>(const VoxelKey&) const = default;  // x, then y, then z
};

std::uint64_t mix(std::uint64_t h) {  // splitmix64 finaliser
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  h ^= h >> 31;
  return h;
}

// One finaliser over the three indices spread by odd constants: a third of the dependent
// multiplications of mixing each in turn, and as well spread for a table.
std::size_t hash_of(const VoxelKey& key) {
  return static_cast<std::size_t>(mix((static_cast<std::uint64_t>(key.x) * 0x9e3779b97f4a7c15ULL) ^
                                      (static_cast<std::uint64_t>(key.y) * 0xc2b2ae3d27d4eb4fULL) ^
                                      (static_cast<std::uint64_t>(key.z) * 0x165667b19e3779f9ULL)));
}

// Occupied voxel -> its slot in first-seen order: open addressing with linear probing in one
// flat array. Written here because std::unordered_map allocates a node per voxel: the 2 cm grid
// of a 274k-point Kinect frame took 11.7 ms with it, 3-4x what one array of keys takes (5.5 ms
// for the whole thinning). Filled up to 3/4 before it doubles: the table's size in cache, not
// its probe count, sets the time (half the table of a 1/2 limit: a counting pass 2.4x faster,
// 1.1-1.2x end to end on 7-Scenes, KITTI and the ETH map, even elsewhere).
class VoxelSlots {
 public:
  // An empty entry's slot.
  static constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

  explicit VoxelSlots(std::size_t expected) {
    rehash(std::bit_ceil(std::max<std::size_t>(64, expected + expected / 4)));
  }

  // The slot of `key`, a new one (the count of keys before the call) if it was not there.
  // Scans and depth images visit a voxel in runs: the table is probed only when the key changes.
  std::size_t slot(const VoxelKey& key) {
    if (size_ > 0 && key == last_key_) return last_slot_;
    last_key_ = key;
    last_slot_ = find_or_add(key);
    return last_slot_;
  }

  // The slot of `key`, or kNone: read-only, so that threads can look up at once.
  [[nodiscard]] std::size_t find(const VoxelKey& key) const {
    const std::size_t mask = entries_.size() - 1;
    for (std::size_t i = hash_of(key) & mask;; i = (i + 1) & mask) {
      const Entry& e = entries_[i];
      if (e.slot == kNone || e.key == key) return e.slot;
    }
  }

 private:
  struct Entry {
    VoxelKey key;
    std::size_t slot = kNone;
  };

  std::size_t find_or_add(const VoxelKey& key) {
    if (4 * (size_ + 1) > 3 * entries_.size()) rehash(2 * entries_.size());  // 3/4 full
    const std::size_t mask = entries_.size() - 1;
    for (std::size_t i = hash_of(key) & mask;; i = (i + 1) & mask) {
      Entry& e = entries_[i];
      if (e.slot == kNone) {
        e = {key, size_};
        return size_++;
      }
      if (e.key == key) return e.slot;
    }
  }

  void rehash(std::size_t capacity) {
    detail::RecycledVector<Entry> old(capacity);
    old.swap(entries_);
    const std::size_t mask = capacity - 1;
    for (const Entry& e : old) {
      if (e.slot == kNone) continue;
      std::size_t i = hash_of(e.key) & mask;
      while (entries_[i].slot != kNone) i = (i + 1) & mask;
      entries_[i] = e;
    }
  }

  detail::RecycledVector<Entry> entries_;
  std::size_t size_ = 0;
  VoxelKey last_key_;
  std::size_t last_slot_ = 0;
};

// Voxel indices stay well inside int64 so that neighbouring-voxel arithmetic by callers and
// the conversion below can never overflow.
constexpr double kMaxVoxelIndex = 0x1p62;

void check_voxel_size(double voxel_size_m) {
  if (!std::isfinite(voxel_size_m) || voxel_size_m <= 0.0) {
    throw InvalidSettingsError("voxel size must be positive and finite, got " +
                               format_number(voxel_size_m) + " m");
  }
}

// The voxel of a point. The range of the indices is checked once, on the cloud's extreme
// coordinates, so that the per-point key is a few inlined floors (it was 30 % of a downsampling
// as a checked call per coordinate).
class VoxelGrid {
 public:
  // `largest`: the cloud's largest_coordinate.
  VoxelGrid(double voxel_size_m, float largest) : inverse_size_(1.0 / voxel_size_m) {
    check_voxel_size(voxel_size_m);
    if (!(std::floor(static_cast<double>(largest) / voxel_size_m) + 1.0 < kMaxVoxelIndex)) {
      throw InvalidSettingsError("voxel size " + format_number(voxel_size_m) +
                                 " m is too small for coordinate " + format_number(largest) +
                                 " m: voxel indices would exceed 2^62");
    }
  }

  [[nodiscard]] VoxelKey key(const Eigen::Vector3f& p) const noexcept {
    return {index(p.x()), index(p.y()), index(p.z())};
  }

 private:
  // floor() without the libm call a portable build makes of std::floor (8 % of a downsampling),
  // of a product with the inverse size: the three divisions were a third of a counting pass
  // (3-4 % of a dense frame's registration: PCL Kinect frames 26.4 -> 25.3 ms). A key can
  // differ from the quotient's only for a coordinate within an ulp of a voxel boundary.
  [[nodiscard]] std::int64_t index(float coordinate) const noexcept {
    const double q = static_cast<double>(coordinate) * inverse_size_;
    const auto i = static_cast<std::int64_t>(q);
    return static_cast<double>(i) > q ? i - 1 : i;
  }

  double inverse_size_;
};

// What a counting pass keeps of a voxel: nothing but its key (VoxelTable).
struct Counted {
  void add(const Eigen::Vector3f& /*p*/) {}
  Counted& operator+=(const Counted& /*other*/) { return *this; }
};

// What voxel_downsample keeps of a voxel: the sum of its points, for their centroid.
struct Centroid {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double count = 0.0;

  void add(const Eigen::Vector3f& p) {
    sum += p.cast<double>();
    count += 1.0;
  }
  Centroid& operator+=(const Centroid& other) {
    sum += other.sum;
    count += other.count;
    return *this;
  }
  // Rounding is monotone, so the float centroid stays within its points' range: in their voxel.
  [[nodiscard]] Eigen::Vector3f centroid() const { return (sum / count).cast<float>(); }
};

// What voxel_downsample_with_surfaces keeps: also the sum of the outer products (xx xy xz yy yz
// zz). Sums of raw (uncentred) products add across voxels; centring them at the end costs
// ~1e-16 |mean|^2, far below the float-resolution floor under which describe_covariance calls a
// spread noise.
struct Moments : Centroid {
  std::array<double, 6> outer{};

  void add(const Eigen::Vector3f& p) {
    Centroid::add(p);
    const double x = p.x();
    const double y = p.y();
    const double z = p.z();
    outer[0] += x * x;
    outer[1] += x * y;
    outer[2] += x * z;
    outer[3] += y * y;
    outer[4] += y * z;
    outer[5] += z * z;
  }
  Moments& operator+=(const Moments& other) {
    Centroid::operator+=(other);
    for (std::size_t k = 0; k < 6; ++k) outer[k] += other.outer[k];
    return *this;
  }
};

// Every occupied voxel of a grid, in the order of its first point, with what Voxel keeps; the
// points' slots when recorded (the voxel size search's settling pass, reused by the thinning
// instead of hashing every point again: 6 % of a default registration on a Kinect frame).
template <class Voxel>
struct VoxelTable {
  VoxelSlots slots;  // once parts are merged, the first part's only (merge_later)
  detail::RecycledVector<VoxelKey> keys;  // by slot
  detail::RecycledVector<Voxel> voxels;   // by slot
  detail::RecycledVector<std::uint32_t> point_slots;
  bool over_limit = false;  // a counting pass stopped above its limit: keys and voxels partial
};

// The passes over raw points (the size search's counting, the thinning) hash and sum two fixed
// halves of a cloud and merge them in order: with two threads the halves run at once, one
// thread runs the same halves in turn, so first-seen order and every sum are the same for any
// thread count. Smaller clouds are one part.
constexpr std::size_t kMinPointsToSplit = std::size_t{1} << 15;

struct PointRange {
  std::size_t begin;
  std::size_t end;
};

std::vector<PointRange> point_parts(std::size_t n) {
  if (n < kMinPointsToSplit) return {{0, n}};
  return {{0, n / 2}, {n / 2, n}};
}

// A pass that only counts and numbers voxels (Counted: the size search's, the thinning's first)
// gives the same table for any split point: merge_later keeps first-seen order, and there are
// no sums. So its split follows the measured cost. The first half of a scan can cost 2x the
// second (near and far, dense and sparse parts of the scene: counting a KITTI scan's halves
// took 0.94 and 0.48 ms), which left one thread waiting a third of each pass. Each calling thread keeps the
// share of the points that its last counting pass would have split evenly (counting_share).
std::vector<PointRange> counting_parts(std::size_t n) {
  if (n < kMinPointsToSplit) return {{0, n}};
  const double share = std::clamp(detail::counting_share(), 0.0, 1.0);
  const auto split = static_cast<std::size_t>(share * static_cast<double>(n));
  return {{0, split}, {split, n}};
}

// The share of `n` points at which the two parts' measured times `ms` would have been equal,
// taking each part's cost per point as constant; kept within [1/8, 7/8] so that one odd pass
// cannot leave a part nearly empty.
void rebalance(const std::vector<PointRange>& parts, const std::vector<double>& ms, std::size_t n) {
  if (parts.size() != 2 || !(ms[0] > 0.0 && ms[1] > 0.0)) return;
  const double total = ms[0] + ms[1];
  const double share = static_cast<double>(parts[0].end) / static_cast<double>(n);
  const double even = ms[0] >= total / 2 ? share * (total / 2) / ms[0]
                                         : share + (1.0 - share) * (total / 2 - ms[0]) / ms[1];
  detail::counting_share() = std::clamp(even, 0.125, 0.875);
}

// body(part) for every part, on up to `threads` threads (0 = every core).
template <class Body>
void for_parts(std::size_t parts, std::size_t threads, const Body& body) {
  parallel_chunks(parts, std::min(resolve_thread_count(threads), parts),
                  [&](std::size_t begin, std::size_t end) {
                    for (std::size_t part = begin; part < end; ++part) body(part);
                  });
}

// The table of the points in `range`; stops once it holds more than `limit` voxels. `expected`
// sizes the hash table.
template <class Voxel>
VoxelTable<Voxel> table_of(const PointCloud& cloud, const VoxelGrid& grid, PointRange range,
                           std::size_t expected, std::size_t limit, bool record) {
  VoxelTable<Voxel> t{VoxelSlots(expected), {}, {}, {}};
  if (record) t.point_slots.reserve(range.end - range.begin);
  for (std::size_t i = range.begin; i < range.end; ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    const VoxelKey key = grid.key(p);
    const std::size_t slot = t.slots.slot(key);
    if (slot == t.voxels.size()) {
      if (slot == limit) {
        t.over_limit = true;
        break;
      }
      t.keys.push_back(key);
      t.voxels.emplace_back();
    }
    t.voxels[slot].add(p);
    if (record) t.point_slots.push_back(static_cast<std::uint32_t>(slot));
  }
  if (t.over_limit) t.point_slots.clear();
  return t;
}

// Where each of `keys` is in `slots` (kNone: not there), split over the threads as any pass
// (resolve_threads): the look-ups only read the table (no re-hash: a Kinect frame's merge
// 0.41 -> 0.27 ms on two threads).
detail::RecycledVector<std::size_t> look_up(const VoxelSlots& slots,
                                            const detail::RecycledVector<VoxelKey>& keys,
                                            std::size_t threads) {
  detail::RecycledVector<std::size_t> found(keys.size());
  parallel_chunks(keys.size(), resolve_threads(threads, keys.size()),
                  [&](std::size_t begin, std::size_t end) {
                    for (std::size_t s = begin; s < end; ++s) found[s] = slots.find(keys[s]);
                  });
  return found;
}

// Appends `later` (the table of the points after those of `t`) to `t`: its voxels in its own
// first-seen order, sums added after t's, point slots renumbered. The new voxels are not
// hashed into t.slots: nothing looks a voxel up once its table is complete.
template <class Voxel>
void merge_later(VoxelTable<Voxel>& t, VoxelTable<Voxel>&& later, std::size_t limit,
                 std::size_t threads) {
  t.over_limit = t.over_limit || later.over_limit;
  if (t.over_limit) {
    t.point_slots.clear();
    return;
  }
  const detail::RecycledVector<std::size_t> found = look_up(t.slots, later.keys, threads);
  detail::RecycledVector<std::uint32_t> renumbered(later.voxels.size());
  for (std::size_t s = 0; s < later.voxels.size() && !t.over_limit; ++s) {
    std::size_t slot = found[s];
    if (slot == VoxelSlots::kNone) {
      slot = t.voxels.size();
      t.over_limit = slot == limit;
      t.keys.push_back(later.keys[s]);
      t.voxels.push_back(later.voxels[s]);
    } else {
      t.voxels[slot] += later.voxels[s];
    }
    renumbered[s] = static_cast<std::uint32_t>(slot);
  }
  if (t.over_limit) {
    t.point_slots.clear();
    return;
  }
  const std::size_t first = t.point_slots.size();
  t.point_slots.resize(first + later.point_slots.size());
  parallel_chunks(later.point_slots.size(), resolve_threads(threads, later.point_slots.size()),
                  [&](std::size_t begin, std::size_t end) {
                    for (std::size_t i = begin; i < end; ++i) {
                      t.point_slots[first + i] = renumbered[later.point_slots[i]];
                    }
                  });
}

// The table of every point of the cloud, made in its parts on up to `threads` threads: fixed
// halves (point_parts) where voxels sum their points, a measured split (counting_parts) where
// they only count them on two threads or more.
template <class Voxel>
VoxelTable<Voxel> voxel_table(const PointCloud& cloud, const VoxelGrid& grid, std::size_t expected,
                              std::size_t limit, bool record, std::size_t threads) {
  // One thread makes the parts in turn: their split only moves the merge, so it stays fixed.
  const bool counting = std::is_same_v<Voxel, Counted> && resolve_thread_count(threads) >= 2;
  const std::vector<PointRange> parts =
      counting ? counting_parts(cloud.size()) : point_parts(cloud.size());
  std::vector<std::optional<VoxelTable<Voxel>>> tables(parts.size());
  std::vector<double> ms(parts.size());
  for_parts(parts.size(), threads, [&](std::size_t part) {
    const auto start = std::chrono::steady_clock::now();
    tables[part] = table_of<Voxel>(cloud, grid, parts[part], expected, limit, record);
    ms[part] =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  });
  if (counting) rebalance(parts, ms, cloud.size());
  VoxelTable<Voxel> table = std::move(*tables.front());
  if (record) table.point_slots.reserve(cloud.size());
  for (std::size_t part = 1; part < parts.size(); ++part) {
    merge_later(table, std::move(*tables[part]), limit, threads);
  }
  return table;
}

// accumulate_voxels over the voxels of a complete counting pass, reusing its hashing: each part
// sums into its own array by slot, and the arrays are added in part order.
template <class Voxel>
VoxelTable<Voxel> accumulate_counted(const PointCloud& cloud, VoxelTable<Counted>&& counted,
                                     std::size_t threads) {
  const std::vector<PointRange> parts = point_parts(cloud.size());
  std::vector<detail::RecycledVector<Voxel>> sums(parts.size());
  for_parts(parts.size(), threads, [&](std::size_t part) {
    detail::RecycledVector<Voxel>& voxels = sums[part];
    voxels.resize(counted.keys.size());
    for (std::size_t i = parts[part].begin; i < parts[part].end; ++i) {
      voxels[counted.point_slots[i]].add(cloud.points[i]);
    }
  });
  for (std::size_t part = 1; part < parts.size(); ++part) {
    for (std::size_t s = 0; s < sums.front().size(); ++s) sums.front()[s] += sums[part][s];
  }
  return {std::move(counted.slots), std::move(counted.keys), std::move(sums.front()), {}};
}

// The voxels of a cloud with their sums. On two threads or more, a counting pass (its split
// measured: counting_parts) numbers every point's voxel and the sums follow by slot in fixed
// halves (accumulate_counted); on one, one pass hashes and sums. The sums are added in the same
// order either way (each half's in point order, then the halves'), so the same table for any
// thread count.
template <class Voxel>
VoxelTable<Voxel> accumulate_voxels(const PointCloud& cloud, double voxel_size_m,
                                    std::size_t threads) {
  const VoxelGrid grid(voxel_size_m, largest_coordinate(cloud));
  const std::size_t n = cloud.size();
  constexpr std::size_t kNoLimit = std::numeric_limits<std::size_t>::max();
  if (resolve_thread_count(threads) >= 2 && n >= kMinPointsToSplit &&
      n <= std::numeric_limits<std::uint32_t>::max()) {
    return accumulate_counted<Voxel>(
        cloud, voxel_table<Counted>(cloud, grid, n / 8, kNoLimit, true, threads), threads);
  }
  return voxel_table<Voxel>(cloud, grid, n / 8, kNoLimit, false, threads);
}

// The centroids of a table's voxels, as a cloud measured from origin_m.
template <class Voxel>
PointCloud centroids_of(const detail::RecycledVector<Voxel>& voxels,
                        const Eigen::Vector3d& origin_m) {
  PointCloud out;
  out.origin_m = origin_m;
  out.points.reserve(voxels.size());
  for (const Voxel& v : voxels) out.points.push_back(v.centroid());
  return out;
}

// The surface at a voxel's centroid from the moments of the points of its 3x3x3 block of voxels
// (sweep_blocks): a 3x3 eigen-solve, against a k-nearest query over the centroids and a
// covariance of its k neighbours (half the time: a Kinect frame's thinning with surfaces 22.9
// against 43.0 ms).
PointSurface block_surface_of(const Moments& block, const Eigen::Vector3f& centroid,
                              const NeighborhoodSettings& stored) {
  const Eigen::Vector3d mean = block.sum / block.count;
  const auto& outer = block.outer;
  Eigen::Matrix3d covariance;
  covariance << outer[0], outer[1], outer[2], outer[1], outer[3], outer[4], outer[2], outer[4],
      outer[5];
  covariance = covariance / block.count - mean * mean.transpose();
  return describe_covariance(centroid, mean, covariance, static_cast<std::size_t>(block.count),
                             stored);
}

// voxel_size_for_count on up to `threads` threads; `settled` (if not null) receives the counting
// pass of the returned size when one counted it (the search ended within its tolerance), else
// nullopt.
double search_voxel_size(const PointCloud& cloud, std::size_t target_points, std::size_t threads,
                         std::optional<VoxelTable<Counted>>* settled) {
  if (settled != nullptr) settled->reset();
  if (target_points == 0 || cloud.size() <= target_points) return 0.0;
  const float largest = largest_coordinate(cloud);
  // Occupied voxels fall as a power of the size, N(v) ~ v^-a: a ~ 2 on surfaces (every sensor's
  // clouds), ~3 in volumes, ~1 on lines. Start from a surface filling the bulk box's diagonal
  // square, then take secant steps in log-log space with the slope measured by the last two.
  const BoundingBox& box = bulk_bounding_box(cloud).box;
  const double diagonal = (box.max - box.min).cast<double>().norm();
  if (!(diagonal > 0.0)) return 0.0;  // all points in one place: nothing to thin
  // A grid fine enough for the bulk cannot index a point 1e20 times farther out (a spurious
  // return robust scaling leaves out): such a cloud is used as it is.
  const double finest = static_cast<double>(largest) / (kMaxVoxelIndex / 4.0);
  if (diagonal / std::sqrt(static_cast<double>(target_points)) / 1e3 < finest) return 0.0;
  const auto target = static_cast<double>(target_points);
  const std::size_t limit = 8 * target_points;  // a count above says "far too small"
  double size = diagonal / std::sqrt(target);
  double previous_size = 0.0;
  double previous_count = 0.0;
  double slope = 2.0;
  // Each point's slot is kept as 32 bits: a larger cloud is counted, not reused.
  const bool keep = settled != nullptr && cloud.size() <= std::numeric_limits<std::uint32_t>::max();
  for (int pass = 0; pass < kVoxelSearchPasses; ++pass) {
    VoxelTable<Counted> counted =
        voxel_table<Counted>(cloud, VoxelGrid(size, largest), target_points, limit, keep, threads);
    const auto count = static_cast<double>(counted.over_limit ? limit + 1 : counted.keys.size());
    if (std::abs(count / target - 1.0) <= kVoxelCountTolerance) {
      if (keep) *settled = std::move(counted);
      break;
    }
    if (previous_size > 0.0 && count <= static_cast<double>(limit) &&
        previous_count <= static_cast<double>(limit) && count != previous_count) {
      slope =
          std::clamp(std::log(previous_count / count) / std::log(size / previous_size), 0.5, 3.0);
    }
    previous_size = size;
    previous_count = count;
    size *= std::pow(count / target, 1.0 / slope);
  }
  return size;
}

// The grid a registration thins `cloud` with (registration_voxel_size); `settled` as for
// search_voxel_size.
double grid_size(const PointCloud& cloud, double voxel_size_m, std::size_t downsample_to,
                 std::size_t threads, std::optional<VoxelTable<Counted>>* settled) {
  if (voxel_size_m > 0.0) return voxel_size_m;
  if (cloud.has_normals() || cloud.has_covariances()) return 0.0;
  return search_voxel_size(cloud, downsample_to, threads, settled);
}

// accumulate_voxels, reusing the hashing of the search's settling pass when there is one.
template <class Voxel>
VoxelTable<Voxel> accumulate(const PointCloud& cloud, double voxel_size_m, std::size_t threads,
                             std::optional<VoxelTable<Counted>>& settled) {
  return settled ? accumulate_counted<Voxel>(cloud, std::move(*settled), threads)
                 : accumulate_voxels<Voxel>(cloud, voxel_size_m, threads);
}

// A voxel's key and slot, for the blocks' sweep in key order.
struct KeyedSlot {
  VoxelKey key;
  std::uint32_t slot;
};

// The block sums of the voxels sorted[begin, end) (sorted by key), adding the 27 voxels in one
// fixed order (dx, dy, dz each from -1 to 1): for each of the 9 columns (x+dx, y+dy) a cursor
// moves forward through the sorted keys as the voxels do, and the column's voxels dz = -1..1 are
// the next ones at its cursor. Sequential reads instead of 26 hash-table probes per voxel, which
// missed the cache and were 22 % of a Kinect registration's cycles (the sweep: 8.6 %).
template <class Visit>
void sweep_blocks(const detail::RecycledVector<KeyedSlot>& sorted,
                  const detail::RecycledVector<Moments>& moments, std::size_t begin,
                  std::size_t end, const Visit& visit) {
  // The lowest voxel of column c (dx = c / 3 - 1, dy = c % 3 - 1) of centre's block.
  const auto lowest_of = [](const VoxelKey& centre, std::size_t c) {
    return VoxelKey{centre.x + static_cast<std::int64_t>(c / 3) - 1,
                    centre.y + static_cast<std::int64_t>(c % 3) - 1, centre.z - 1};
  };
  std::array<std::size_t, 9> cursor{};
  for (std::size_t c = 0; c < 9 && begin < end; ++c) {
    const VoxelKey lowest = lowest_of(sorted[begin].key, c);
    cursor[c] = static_cast<std::size_t>(
        std::partition_point(sorted.begin(), sorted.end(),
                             [&](const KeyedSlot& e) { return e.key < lowest; }) -
        sorted.begin());
  }
  const std::size_t n = sorted.size();
  for (std::size_t i = begin; i < end; ++i) {
    Moments block;
    for (std::size_t c = 0; c < 9; ++c) {
      const VoxelKey lowest = lowest_of(sorted[i].key, c);
      std::size_t& j = cursor[c];
      while (j < n && sorted[j].key < lowest) ++j;
      for (std::size_t k = j; k < n && k < j + 3; ++k) {
        const VoxelKey& key = sorted[k].key;
        if (key.x != lowest.x || key.y != lowest.y || key.z > lowest.z + 2) break;
        block += moments[sorted[k].slot];
      }
    }
    visit(sorted[i].slot, block);
  }
}

// `values` sorted by a least-significant-digit radix sort of their lowest `bits` bits (11-bit
// digits): linear in the count, where a comparison sort of a 20k-voxel grid's keys took 1.3 ms.
void radix_sort(detail::RecycledVector<std::uint64_t>& values, int bits) {
  constexpr int kDigitBits = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
  detail::RecycledVector<std::uint64_t> other(values.size());
  std::vector<std::size_t> start(kBuckets);
  for (int shift = 0; shift < bits; shift += kDigitBits) {
    std::fill(start.begin(), start.end(), 0);
    for (const std::uint64_t v : values) ++start[(v >> shift) & (kBuckets - 1)];
    std::size_t offset = 0;
    for (std::size_t& s : start) offset += std::exchange(s, offset);
    for (const std::uint64_t v : values) other[start[(v >> shift) & (kBuckets - 1)]++] = v;
    values.swap(other);
  }
}

// The voxels' keys with their slots, sorted by key (x, then y, then z). When each axis' index
// range and the slot fit one 64-bit word together (every grid of a registration), the words are
// radix-sorted; otherwise the keys are compared.
detail::RecycledVector<KeyedSlot> sorted_by_key(const detail::RecycledVector<VoxelKey>& keys) {
  const std::size_t n = keys.size();
  detail::RecycledVector<KeyedSlot> out(n);
  if (n == 0) return out;
  VoxelKey low = keys.front();
  VoxelKey high = keys.front();
  for (const VoxelKey& k : keys) {
    low = {std::min(low.x, k.x), std::min(low.y, k.y), std::min(low.z, k.z)};
    high = {std::max(high.x, k.x), std::max(high.y, k.y), std::max(high.z, k.z)};
  }
  // Indices stay within +-2^62 (kMaxVoxelIndex), so the spans fit an unsigned word.
  const auto span = [](std::int64_t a, std::int64_t b) {
    return static_cast<std::uint64_t>(b - a);
  };
  const int bz = std::bit_width(span(low.z, high.z));
  const int by = std::bit_width(span(low.y, high.y));
  const int bx = std::bit_width(span(low.x, high.x));
  const int bs = std::bit_width(n - 1);
  if (bx + by + bz + bs > 64) {
    for (std::size_t v = 0; v < n; ++v) out[v] = {keys[v], static_cast<std::uint32_t>(v)};
    std::sort(out.begin(), out.end(),
              [](const KeyedSlot& a, const KeyedSlot& b) { return a.key < b.key; });
    return out;
  }
  detail::RecycledVector<std::uint64_t> words(n);
  for (std::size_t v = 0; v < n; ++v) {
    const VoxelKey& k = keys[v];
    const std::uint64_t packed =
        (span(low.x, k.x) << (by + bz)) | (span(low.y, k.y) << bz) | span(low.z, k.z);
    words[v] = (packed << bs) | v;  // bs < 64 here: it is 0 only for n = 1, then v = 0
  }
  radix_sort(words, bx + by + bz + bs);
  const std::uint64_t slot_mask = (std::uint64_t{1} << bs) - 1;
  for (std::size_t i = 0; i < n; ++i) {
    const auto slot = static_cast<std::uint32_t>(words[i] & slot_mask);
    out[i] = {keys[slot], slot};
  }
  return out;
}

// Voxels per claim of the block sweep's threads: small enough that a thread that starts late
// (after its side task) still takes its share, large enough that the 9 binary searches that
// start a chunk's cursors stay negligible.
constexpr std::size_t kSweepChunk = 1024;

// The block surface of every voxel of an accumulated table into `normals` and `covariances` (by
// slot); `stored` from in_stored_frame. `side` runs on a second thread while the first sorts the
// keys, and that thread then joins the sweep: the sweep is claimed in chunks by whichever
// thread is free. Each voxel's surface is a pure function of its block (sweep_blocks), so the
// values are the same for any thread count and split.
template <class Side>
void sweep_surfaces(const VoxelTable<Moments>& table, const NeighborhoodSettings& stored,
                    std::size_t threads, std::vector<Eigen::Vector3f>& normals,
                    std::vector<Eigen::Matrix3f>& covariances, const Side& side) {
  const auto& voxels = table.voxels;
  const std::size_t n = voxels.size();
  normals.resize(n);
  covariances.resize(n);
  detail::RecycledVector<KeyedSlot> sorted;
  // The sort's state for the threads that wait for it: pending, done, or failed (its exception
  // reaches the caller through parallel_chunks; nobody sweeps then).
  enum class SortState : int { pending, done, failed };
  std::atomic<SortState> sort_state{SortState::pending};
  std::atomic<std::size_t> next_chunk{0};
  const auto sweep = [&] {
    if (sort_state.load(std::memory_order_acquire) != SortState::done) return;
    for (;;) {
      const std::size_t begin = next_chunk.fetch_add(kSweepChunk, std::memory_order_relaxed);
      if (begin >= n) return;
      sweep_blocks(sorted, voxels, begin, std::min(n, begin + kSweepChunk),
                   [&](std::uint32_t v, const Moments& block) {
                     const PointSurface s = block_surface_of(block, voxels[v].centroid(), stored);
                     normals[v] = s.normal;
                     covariances[v] = s.covariance;
                   });
    }
  };
  const auto sort_keys = [&] {
    SortState state = SortState::failed;
    try {
      sorted = sorted_by_key(table.keys);
      state = SortState::done;
    } catch (...) {
      sort_state.store(state, std::memory_order_release);
      sort_state.notify_all();
      throw;
    }
    sort_state.store(state, std::memory_order_release);
    sort_state.notify_all();
  };
  const std::size_t used = resolve_threads(threads, n);
  if (used == 1) {
    side();
    sort_keys();
    sweep();
    return;
  }
  parallel_chunks(used, used, [&](std::size_t t, std::size_t) {
    if (t == 0) {
      sort_keys();
    } else {
      if (t == 1) side();
      sort_state.wait(SortState::pending, std::memory_order_acquire);
    }
    sweep();
  });
}

// voxel_downsample_with_surfaces of an accumulated table; `stored` from in_stored_frame.
PointCloud with_block_surfaces(const VoxelTable<Moments>& table, const Eigen::Vector3d& origin_m,
                               const NeighborhoodSettings& stored, std::size_t threads) {
  PointCloud out = centroids_of(table.voxels, origin_m);
  sweep_surfaces(table, stored, threads, out.normals, out.covariances, [] {});
  return out;
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

double& counting_share() {
  thread_local double share = 0.5;
  return share;
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

ReferenceIndex registration_index(PointCloud cloud, double voxel_size_m, std::size_t downsample_to,
                                  const NeighborhoodSettings& settings, bool surfaces,
                                  const KdTreeSettings& tree) {
  std::optional<VoxelTable<Counted>> settled;
  voxel_size_m = grid_size(cloud, voxel_size_m, downsample_to, settings.num_threads, &settled);
  if (voxel_size_m == 0.0) return ReferenceIndex(std::move(cloud), tree);
  if (!surfaces) {
    const auto table = accumulate<Centroid>(cloud, voxel_size_m, settings.num_threads, settled);
    return ReferenceIndex::on_voxel_grid(centroids_of(table.voxels, cloud.origin_m), voxel_size_m,
                                         tree);
  }
  check_neighborhood(settings);
  const auto table = accumulate<Moments>(cloud, voxel_size_m, settings.num_threads, settled);
  PointCloud centroids = centroids_of(table.voxels, cloud.origin_m);
  // A 3x3 patch of voxels across a surface holds about 9 * (points per voxel): at least k of
  // them, or the centroids' own k nearest neighbours give the better estimate.
  if (9 * cloud.size() < settings.k * table.voxels.size()) {
    return ReferenceIndex::on_voxel_grid(std::move(centroids), voxel_size_m, tree);
  }
  // The tree over the centroids is built on one thread while the other sorts the keys and
  // starts the sweep: neither waits for the other (sort, sweep and tree on two threads 6.1 ->
  // 4.8-5.2 ms on a KITTI scan, 6.3 -> 5.1 ms on a Kinect frame).
  std::optional<ReferenceIndex> index;
  KdTreeSettings tree_alongside = tree;
  tree_alongside.num_threads = 1;
  std::vector<Eigen::Vector3f> normals;
  std::vector<Eigen::Matrix3f> covariances;
  const auto build_tree = [&] {
    index.emplace(
        ReferenceIndex::on_voxel_grid(std::move(centroids), voxel_size_m, tree_alongside));
  };
  sweep_surfaces(table, in_stored_frame(settings, cloud), settings.num_threads, normals,
                 covariances, build_tree);
  index->set_normals_and_covariances(std::move(normals), std::move(covariances));
  return std::move(*index);
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

PointCloud voxel_downsample(const PointCloud& cloud, double voxel_size_m, std::size_t num_threads) {
  if (num_threads > kMaxThreads) {
    throw InvalidSettingsError("voxel_downsample: num_threads must be at most " +
                               std::to_string(kMaxThreads) + " (0 = all cores), got " +
                               std::to_string(num_threads));
  }
  return centroids_of(accumulate_voxels<Centroid>(cloud, voxel_size_m, num_threads).voxels,
                      cloud.origin_m);
}

PointCloud voxel_downsample_with_surfaces(const PointCloud& cloud, double voxel_size_m,
                                          const NeighborhoodSettings& settings) {
  check_neighborhood(settings);
  return with_block_surfaces(accumulate_voxels<Moments>(cloud, voxel_size_m, settings.num_threads),
                             cloud.origin_m, detail::in_stored_frame(settings, cloud),
                             settings.num_threads);
}

double voxel_size_for_count(const PointCloud& cloud, std::size_t target_points) {
  return search_voxel_size(cloud, target_points, 1, nullptr);
}

double registration_voxel_size(const PointCloud& cloud, double voxel_size_m,
                               std::size_t downsample_to) {
  return grid_size(cloud, voxel_size_m, downsample_to, 1, nullptr);
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
