#include "sgdicp/points/voxel_grid.hpp"

#include <array>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/checks.hpp"
#include "points/voxel_table.hpp"
#include "sgdicp/points/scaling.hpp"
#include "util/parallel_chunks.hpp"
#include "util/stopwatch.hpp"

namespace sgdicp {
namespace detail {
namespace {

// voxel_size_for_count: counting passes at most, and the relative error in the count that
// ends the search early (the count is a budget, not a contract).
constexpr int kVoxelSearchPasses = 6;
constexpr double kVoxelCountTolerance = 0.15;

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
// took 0.94 and 0.48 ms), which left one thread waiting a third of each pass. Each calling thread
// keeps the share of the points that its last counting pass would have split evenly
// (counting_share).
std::vector<PointRange> counting_parts(std::size_t n) {
  if (n < kMinPointsToSplit) return {{0, n}};
  const double share = std::clamp(counting_share(), 0.0, 1.0);
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
  counting_share() = std::clamp(even, 0.125, 0.875);
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
RecycledVector<std::size_t> look_up(const VoxelSlots& slots, const RecycledVector<VoxelKey>& keys,
                                    std::size_t threads) {
  RecycledVector<std::size_t> found(keys.size());
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
  const RecycledVector<std::size_t> found = look_up(t.slots, later.keys, threads);
  RecycledVector<std::uint32_t> renumbered(later.voxels.size());
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
    const Stopwatch clock;
    tables[part] = table_of<Voxel>(cloud, grid, parts[part], expected, limit, record);
    ms[part] = clock.elapsed_ms();
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
  std::vector<RecycledVector<Voxel>> sums(parts.size());
  for_parts(parts.size(), threads, [&](std::size_t part) {
    RecycledVector<Voxel>& voxels = sums[part];
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

// The size search's counts need no voxel's slot, key or first-seen order, only how many: a
// bitmap over the box of voxels that the cloud spans, one bit a voxel, when it is small enough
// to clear (at most kBitmapBitsPerPoint bits per point, within [2^23, 2^28] bits). A bit is one
// load and store where the hash table's voxel is a 32-byte entry found by probing: a KITTI
// scan's counting passes 1.1-2.2 -> 0.5-0.9 ms.
constexpr double kBitmapBitsPerPoint = 128.0;
constexpr double kMinBitmapBits = 0x1p23;
constexpr double kMaxBitmapBits = 0x1p28;

// Points per block of set_voxel_bits: their indices (3 int32 each) stay in the L1 cache.
constexpr std::size_t kBitmapBlock = 256;

// The set bits of a word, inline: a portable build (no POPCNT instruction) makes std::popcount a
// library call, 3.5 % of a KITTI scan's reference preparation when ranking its bitmap.
inline std::uint32_t set_bits(std::uint64_t word) {
  word -= (word >> 1) & 0x5555555555555555ULL;
  word = (word & 0x3333333333333333ULL) + ((word >> 2) & 0x3333333333333333ULL);
  word = (word + (word >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return static_cast<std::uint32_t>((word * 0x0101010101010101ULL) >> 56);
}

// The box of voxels that a cloud spans on a grid, for bitmaps of one bit a voxel: the lowest
// voxel and the spans along x and y, the bits (voxels) and 64-bit words.
struct BitmapBox {
  std::array<std::int32_t, 3> low{};
  std::uint64_t nx = 0;
  std::uint64_t ny = 0;
  std::size_t words = 0;
};

// The box of `grid`'s voxels that `box` (the cloud's exact bounding box) spans, or nullopt when
// it has more voxels than a bitmap may clear or its indices exceed int32.
std::optional<BitmapBox> bitmap_box(const PointCloud& cloud, const VoxelGrid& grid,
                                    const BoundingBox& box) {
  const double largest = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff());
  if (!(largest * grid.inverse_size() < 0x1p30)) return std::nullopt;
  const VoxelKey low = grid.key(box.min.cast<float>());
  const VoxelKey high = grid.key(box.max.cast<float>());
  const double nx = static_cast<double>(high.x - low.x) + 1.0;
  const double ny = static_cast<double>(high.y - low.y) + 1.0;
  const double nz = static_cast<double>(high.z - low.z) + 1.0;
  const double budget = std::clamp(kBitmapBitsPerPoint * static_cast<double>(cloud.size()),
                                   kMinBitmapBits, kMaxBitmapBits);
  if (!(nx * ny * nz <= budget)) return std::nullopt;
  return BitmapBox{{static_cast<std::int32_t>(low.x), static_cast<std::int32_t>(low.y),
                    static_cast<std::int32_t>(low.z)},
                   static_cast<std::uint64_t>(nx),
                   static_cast<std::uint64_t>(ny),
                   static_cast<std::size_t>(nx * ny * nz) / 64 + 1};
}

// The number of occupied voxels of `grid` among the points of `range`, counted in `bits` (all
// clear, one bit per voxel of `box`): the bits it sets. With `bit_of_point`, each point's bit
// (below 2^28: kMaxBitmapBits) goes to bit_of_point[i]. The indices of a block of points are
// made first in one loop over their coordinates, in int32 lanes the compiler vectorises, then
// the bits.
std::size_t set_voxel_bits(const PointCloud& cloud, const VoxelGrid& grid, PointRange range,
                           const BitmapBox& box, RecycledVector<std::uint64_t>& bits,
                           std::uint32_t* bit_of_point = nullptr) {
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  std::array<std::int32_t, 3 * kBitmapBlock> indices{};
  std::size_t count = 0;
  for (std::size_t first = range.begin; first < range.end; first += kBitmapBlock) {
    const std::size_t points = std::min(kBitmapBlock, range.end - first);
    const float* coordinates = cloud.points[first].data();
    for (std::size_t k = 0; k < 3 * points; ++k) {
      indices[k] = grid.index<std::int32_t>(coordinates[k]);
    }
    for (std::size_t j = 0; j < points; ++j) {
      const auto along = [&](std::size_t axis) {
        return static_cast<std::uint64_t>(
            static_cast<std::uint32_t>(indices[3 * j + axis] - box.low[axis]));
      };
      const std::uint64_t bit = along(0) + box.nx * (along(1) + box.ny * along(2));
      std::uint64_t& word = bits[bit >> 6];
      const std::uint64_t mask = std::uint64_t{1} << (bit & 63);
      count += (word & mask) == 0 ? 1 : 0;
      word |= mask;
      if (bit_of_point != nullptr) bit_of_point[first + j] = static_cast<std::uint32_t>(bit);
    }
  }
  return count;
}

// The number of occupied voxels of `grid` in a bitmap over `box`. On two threads or more, each
// half of the cloud (point_parts) sets its own bitmap and the count is that of their union: the
// same count for any thread count.
std::size_t count_in_bitmap(const PointCloud& cloud, const VoxelGrid& grid, const BitmapBox& box,
                            std::size_t threads) {
  const std::vector<PointRange> parts = resolve_thread_count(threads) >= 2
                                            ? point_parts(cloud.size())
                                            : std::vector<PointRange>{{0, cloud.size()}};
  std::vector<RecycledVector<std::uint64_t>> bits(parts.size());
  std::vector<std::size_t> counts(parts.size());
  for_parts(parts.size(), threads, [&](std::size_t part) {
    bits[part].assign(box.words, 0);
    counts[part] = set_voxel_bits(cloud, grid, parts[part], box, bits[part]);
  });
  if (parts.size() == 1) return counts.front();
  std::size_t count = 0;
  for (std::size_t w = 0; w < box.words; ++w) {
    std::uint64_t word = 0;
    for (const auto& part : bits) word |= part[w];
    count += set_bits(word);
  }
  return count;
}

// The counting table of `grid` with every point's slot (as voxel_table<Counted> records it: the
// voxels in first-seen order), on one thread, from a bitmap over `box`: a voxel's rank among the
// set bits numbers it without a hash table, and a first-seen slot per rank (a few tens of KB)
// renumbers it. Over `limit` voxels, only the count is kept (over_limit).
VoxelTable<Counted> ranked_table(const PointCloud& cloud, const VoxelGrid& grid,
                                 const BitmapBox& box, std::size_t limit) {
  const std::size_t n = cloud.size();
  VoxelTable<Counted> t{VoxelSlots(0), {}, {}, {}};
  t.point_slots.resize(n);
  RecycledVector<std::uint64_t> bits(box.words, 0);
  const std::size_t count = set_voxel_bits(cloud, grid, {0, n}, box, bits, t.point_slots.data());
  if (count > limit) {
    t.over_limit = true;
    t.point_slots.clear();
    return t;
  }
  RecycledVector<std::uint32_t> rank_before(box.words);  // set bits in the words before
  std::uint32_t rank = 0;
  for (std::size_t w = 0; w < box.words; ++w) {
    rank_before[w] = rank;
    rank += set_bits(bits[w]);
  }
  constexpr std::uint32_t kUnseen = std::numeric_limits<std::uint32_t>::max();
  RecycledVector<std::uint32_t> slot_of_rank(count, kUnseen);
  t.keys.reserve(count);
  t.voxels.resize(count);
  // Scans and depth images visit a voxel in runs: its slot is looked up when the bit changes.
  std::uint32_t last_bit = kUnseen;
  std::uint32_t last_slot = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t bit = t.point_slots[i];
    if (bit != last_bit) {
      const std::uint64_t word = bits[bit >> 6];
      const std::uint64_t below = (std::uint64_t{1} << (bit & 63)) - 1;
      std::uint32_t& slot = slot_of_rank[rank_before[bit >> 6] + set_bits(word & below)];
      if (slot == kUnseen) {
        slot = static_cast<std::uint32_t>(t.keys.size());
        t.keys.push_back(grid.key(cloud.points[i]));
      }
      last_bit = bit;
      last_slot = slot;
    }
    t.point_slots[i] = last_slot;
  }
  return t;
}

// The number of occupied voxels of `grid`, or limit + 1 when there are more than `limit`;
// `expected` sizes a hash table where the bitmap would be too large.
std::size_t count_voxels(const PointCloud& cloud, const VoxelGrid& grid, const BoundingBox& box,
                         std::size_t expected, std::size_t limit, std::size_t threads) {
  if (const std::optional<BitmapBox> bitmap = bitmap_box(cloud, grid, box)) {
    return std::min(count_in_bitmap(cloud, grid, *bitmap, threads), limit + 1);
  }
  const VoxelTable<Counted> counted =
      voxel_table<Counted>(cloud, grid, expected, limit, false, threads);
  return counted.over_limit ? limit + 1 : counted.keys.size();
}

// The counting table of `grid` with every point's slot (voxel_table<Counted> recording them),
// ranked in a bitmap on one thread when it fits (a KITTI scan's 1.5-1.7 -> ~0.9 ms), hashed
// otherwise; the same table either way.
VoxelTable<Counted> recorded_table(const PointCloud& cloud, const VoxelGrid& grid,
                                   const BoundingBox& box, std::size_t expected, std::size_t limit,
                                   std::size_t threads) {
  if (resolve_thread_count(threads) == 1) {
    if (const std::optional<BitmapBox> bitmap = bitmap_box(cloud, grid, box)) {
      return ranked_table(cloud, grid, *bitmap, limit);
    }
  }
  return voxel_table<Counted>(cloud, grid, expected, limit, true, threads);
}

}  // namespace

// The voxels of a cloud with their sums. On two threads or more, a counting pass (its split
// measured: counting_parts) numbers every point's voxel and the sums follow by slot in fixed
// halves (accumulate_counted); on one, a table ranked in a bitmap (ranked_table) numbers them
// where the box allows (a KITTI scan's thinning 2.0 -> 1.8 ms, a Kinect frame's 3.9 -> 2.8 ms),
// else one pass hashes and sums, as for a cloud too small to split. The sums are added in the
// same order either way (each half's in point order, then the halves'), so the same table for
// any thread count.
template <class Voxel>
VoxelTable<Voxel> accumulate_voxels(const PointCloud& cloud, double voxel_size_m,
                                    std::size_t threads, const char* what) {
  const CloudExtent extent = extent_of(cloud, what);
  const VoxelGrid grid(voxel_size_m, extent.largest);
  const std::size_t n = cloud.size();
  constexpr std::size_t kNoLimit = std::numeric_limits<std::size_t>::max();
  if (n < kMinPointsToSplit || n > std::numeric_limits<std::uint32_t>::max()) {
    return voxel_table<Voxel>(cloud, grid, n / 8, kNoLimit, false, threads);
  }
  if (resolve_thread_count(threads) >= 2) {
    return accumulate_counted<Voxel>(
        cloud, voxel_table<Counted>(cloud, grid, n / 8, kNoLimit, true, threads), threads);
  }
  if (const std::optional<BitmapBox> bitmap = bitmap_box(cloud, grid, extent.box)) {
    return accumulate_counted<Voxel>(cloud, ranked_table(cloud, grid, *bitmap, kNoLimit), threads);
  }
  return voxel_table<Voxel>(cloud, grid, n / 8, kNoLimit, false, threads);
}

namespace {

// voxel_size_for_count on up to `threads` threads; `settled` (if not null) receives the counting
// pass of the returned size when one counted it (the search ended within its tolerance), else
// nullopt.
double search_voxel_size(const PointCloud& cloud, std::size_t target_points, std::size_t threads,
                         std::optional<VoxelTable<Counted>>* settled) {
  if (settled != nullptr) settled->reset();
  if (target_points == 0 || cloud.size() <= target_points) return 0.0;
  const CloudExtent extent = extent_of(cloud);  // every point's, for the bitmaps
  // Occupied voxels fall as a power of the size, N(v) ~ v^-a: a ~ 2 on surfaces (every sensor's
  // clouds), ~3 in volumes, ~1 on lines. Start from a surface filling the bulk box's diagonal
  // square, then take secant steps in log-log space with the slope measured by the last two.
  const BoundingBox box = bulk_bounding_box(cloud, extent.box).box;
  const double diagonal = (box.max - box.min).cast<double>().norm();
  if (!(diagonal > 0.0)) return 0.0;  // all points in one place: nothing to thin
  // A grid fine enough for the bulk cannot index a point 1e20 times farther out (a spurious
  // return robust scaling leaves out): such a cloud is used as it is.
  const double finest = static_cast<double>(extent.largest) / (kMaxVoxelIndex / 4.0);
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
    const VoxelGrid grid(size, extent.largest);
    // The thinning needs the table of the size found, which the bitmaps do not give: a pass
    // that follows a count within a factor 2 of the target (it lands within the tolerance on
    // every cloud of the pairs files) makes it at once, the others count in a bitmap first.
    const bool near = previous_count >= 0.5 * target && previous_count <= 2.0 * target;
    std::optional<VoxelTable<Counted>> counted;
    if (keep && near) {
      counted = recorded_table(cloud, grid, extent.box, target_points, limit, threads);
    }
    const auto count = static_cast<double>(
        counted ? (counted->over_limit ? limit + 1 : counted->keys.size())
                : count_voxels(cloud, grid, extent.box, target_points, limit, threads));
    if (std::abs(count / target - 1.0) <= kVoxelCountTolerance) {
      if (keep && !counted) {
        counted = recorded_table(cloud, grid, extent.box, target_points, limit, threads);
      }
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

}  // namespace

void check_voxel_size(double voxel_size_m) {
  if (!std::isfinite(voxel_size_m) || voxel_size_m <= 0.0) {
    throw InvalidSettingsError("voxel size must be positive and finite, got " +
                               format_number(voxel_size_m) + " m");
  }
}

double& counting_share() {
  thread_local double share = 0.5;
  return share;
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

template VoxelTable<Centroid> accumulate_voxels(const PointCloud&, double, std::size_t,
                                                const char*);
template VoxelTable<Moments> accumulate_voxels(const PointCloud&, double, std::size_t, const char*);
template VoxelTable<Centroid> accumulate(const PointCloud&, double, std::size_t,
                                         std::optional<VoxelTable<Counted>>&);
template VoxelTable<Moments> accumulate(const PointCloud&, double, std::size_t,
                                        std::optional<VoxelTable<Counted>>&);

}  // namespace detail

namespace {

// The mean time of each voxel's points, in the voxels' first-seen order (the centroids'): one
// counting pass that numbers every point's voxel, only for a cloud with times.
std::vector<float> voxel_mean_times(const PointCloud& cloud, double voxel_size_m) {
  const detail::VoxelGrid grid(voxel_size_m, detail::largest_coordinate(cloud));
  const auto table = detail::voxel_table<detail::Counted>(
      cloud, grid, cloud.size() / 8, std::numeric_limits<std::size_t>::max(), true, 1);
  std::vector<double> sums(table.keys.size(), 0.0);
  std::vector<double> counts(table.keys.size(), 0.0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    sums[table.point_slots[i]] += static_cast<double>(cloud.times_s[i]);
    counts[table.point_slots[i]] += 1.0;
  }
  std::vector<float> out(sums.size());
  for (std::size_t v = 0; v < out.size(); ++v) out[v] = static_cast<float>(sums[v] / counts[v]);
  return out;
}

}  // namespace

PointCloud detail::thinned(const PointCloud& cloud, double voxel_size_m, std::size_t threads,
                           const char* what) {
  PointCloud out = centroids_of(
      accumulate_voxels<Centroid>(cloud, voxel_size_m, threads, what).voxels, cloud.origin_m);
  if (cloud.has_times()) out.times_s = voxel_mean_times(cloud, voxel_size_m);
  return out;
}

PointCloud voxel_downsample(const PointCloud& cloud, double voxel_size_m, std::size_t num_threads) {
  if (num_threads > kMaxThreads) {
    throw InvalidSettingsError("voxel_downsample: num_threads must be at most " +
                               std::to_string(kMaxThreads) + " (0 = all cores), got " +
                               std::to_string(num_threads));
  }
  return detail::thinned(cloud, voxel_size_m, num_threads, "cloud");
}

double voxel_size_for_count(const PointCloud& cloud, std::size_t target_points) {
  return detail::search_voxel_size(cloud, target_points, 1, nullptr);
}

double registration_voxel_size(const PointCloud& cloud, double voxel_size_m,
                               std::size_t downsample_to) {
  return detail::grid_size(cloud, voxel_size_m, downsample_to, 1, nullptr);
}

}  // namespace sgdicp
