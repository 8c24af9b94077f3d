#pragma once
// The voxel grids of the library (private): occupied voxels in first-seen order with what each
// keeps of its points (nothing, their centroid, their moments), made in parts on the calling
// thread and its helpers with the same result for any thread count. voxel_grid.cpp makes them;
// the thinning (voxel_grid.hpp), the block surfaces (surfaces/) and a registration's reference
// grid (registration/) read them.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>

#include <Eigen/Core>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/format_number.hpp"
#include "sgdicp/core/point_cloud.hpp"
#include "util/recycling_allocator.hpp"

namespace sgdicp::detail {

struct VoxelKey {
  std::int64_t x = 0;
  std::int64_t y = 0;
  std::int64_t z = 0;
  bool operator==(const VoxelKey&) const = default;
  auto operator<=>(const VoxelKey&) const = default;  // x, then y, then z
};

inline std::uint64_t mix(std::uint64_t h) {  // splitmix64 finaliser
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  h ^= h >> 31;
  return h;
}

// One finaliser over the three indices spread by odd constants: a third of the dependent
// multiplications of mixing each in turn, and as well spread for a table.
inline std::size_t hash_of(const VoxelKey& key) {
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

  // The number of keys, and the bytes the table holds.
  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] std::size_t bytes() const noexcept { return entries_.size() * sizeof(Entry); }

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
    RecycledVector<Entry> old(capacity);
    old.swap(entries_);
    const std::size_t mask = capacity - 1;
    for (const Entry& e : old) {
      if (e.slot == kNone) continue;
      std::size_t i = hash_of(e.key) & mask;
      while (entries_[i].slot != kNone) i = (i + 1) & mask;
      entries_[i] = e;
    }
  }

  RecycledVector<Entry> entries_;
  std::size_t size_ = 0;
  VoxelKey last_key_;
  std::size_t last_slot_ = 0;
};

// Voxel indices stay well inside int64 so that neighbouring-voxel arithmetic by callers and
// the conversion below can never overflow.
constexpr double kMaxVoxelIndex = 0x1p62;

/// Throws InvalidSettingsError unless voxel_size_m is positive and finite.
void check_voxel_size(double voxel_size_m);

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

  // floor() without the libm call a portable build makes of std::floor (8 % of a downsampling),
  // of a product with the inverse size: the three divisions were a third of a counting pass
  // (3-4 % of a dense frame's registration: PCL Kinect frames 26.4 -> 25.3 ms). A key can
  // differ from the quotient's only for a coordinate within an ulp of a voxel boundary. Int:
  // std::int32_t where the caller knows that |coordinate| / size < 2^30 (the size search's
  // bitmaps: a loop of these vectorises), the same index as the int64 one.
  template <class Int = std::int64_t>
  [[nodiscard]] Int index(float coordinate) const noexcept {
    const double q = static_cast<double>(coordinate) * inverse_size_;
    const auto i = static_cast<Int>(q);
    return static_cast<double>(i) > q ? i - 1 : i;
  }

  [[nodiscard]] double inverse_size() const noexcept { return inverse_size_; }

 private:
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
  VoxelSlots slots;               // once parts are merged, the first part's only (merge_later)
  RecycledVector<VoxelKey> keys;  // by slot
  RecycledVector<Voxel> voxels;   // by slot
  RecycledVector<std::uint32_t> point_slots;
  bool over_limit = false;  // a counting pass stopped above its limit: keys and voxels partial
};

/// The centroids of a table's voxels, as a cloud measured from origin_m.
template <class Voxel>
PointCloud centroids_of(const RecycledVector<Voxel>& voxels, const Eigen::Vector3d& origin_m) {
  PointCloud out;
  out.origin_m = origin_m;
  out.points.reserve(voxels.size());
  for (const Voxel& v : voxels) out.points.push_back(v.centroid());
  return out;
}

/// The calling thread's share of the points that its next voxel counting pass gives the first of
/// its two parts (voxel_grid.cpp, counting_parts), set by each pass from its parts' times.
/// Any share gives the same table; tests set it to check that.
[[nodiscard]] double& counting_share();

/// The voxels of a cloud with their sums (Centroid or Moments), on up to `threads` threads; the
/// same table for any thread count. InvalidInputError "`what` has a non-finite point at index i".
template <class Voxel>
VoxelTable<Voxel> accumulate_voxels(const PointCloud& cloud, double voxel_size_m,
                                    std::size_t threads, const char* what = "cloud");

/// voxel_downsample, its error naming the cloud `what`: a caller that thins a cloud it has not
/// checked needs no pass of its own over it for non-finite points.
[[nodiscard]] PointCloud thinned(const PointCloud& cloud, double voxel_size_m, std::size_t threads,
                                 const char* what);

/// The grid a registration thins `cloud` with (registration_voxel_size, voxel_grid.hpp), on up
/// to `threads` threads; `settled` (if not null) receives the size search's counting pass of the
/// returned size when one counted it (the search ended within its tolerance), else nullopt.
double grid_size(const PointCloud& cloud, double voxel_size_m, std::size_t downsample_to,
                 std::size_t threads, std::optional<VoxelTable<Counted>>* settled);

/// accumulate_voxels, reusing the hashing of the size search's settling pass when there is one.
template <class Voxel>
VoxelTable<Voxel> accumulate(const PointCloud& cloud, double voxel_size_m, std::size_t threads,
                             std::optional<VoxelTable<Counted>>& settled);

}  // namespace sgdicp::detail
