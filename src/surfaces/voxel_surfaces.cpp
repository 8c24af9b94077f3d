#include "surfaces/block_surfaces.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <optional>
#include <ranges>
#include <utility>
#include <vector>

#include "sgdicp/surfaces/voxel_surfaces.hpp"
#include "surfaces/point_surfaces.hpp"
#include "util/parallel_chunks.hpp"
#include "util/recycling_allocator.hpp"

namespace sgdicp {
namespace detail {
namespace {

// The surface at a voxel's centroid from the moments of the points of its 3x3x3 block of voxels
// (sweep_blocks): a 3x3 eigen-solve, against a k-nearest query over the centroids and a
// covariance of its k neighbours (half the time: a Kinect frame's thinning with surfaces 22.9
// against 43.0 ms).
PointSurface block_surface_of(const Moments& block, const Eigen::Vector3f& centroid,
                              const NeighborhoodSettings& stored, double* linearity) {
  const Eigen::Vector3d mean = block.sum / block.count;
  // outer / count - mean mean^T element by element (the same roundings as the matrix
  // expression, whose temporaries were stored and reloaded across a failed store forwarding: a
  // tenth of the sweep), each of the 6 once: mean_i mean_j = mean_j mean_i exactly.
  const auto& outer = block.outer;
  const auto centred = [&](std::size_t k, int i, int j) {
    return outer[k] / block.count - mean[i] * mean[j];
  };
  const double xx = centred(0, 0, 0);
  const double xy = centred(1, 0, 1);
  const double xz = centred(2, 0, 2);
  const double yy = centred(3, 1, 1);
  const double yz = centred(4, 1, 2);
  const double zz = centred(5, 2, 2);
  Eigen::Matrix3d covariance;
  covariance << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  return describe_covariance(centroid, mean, covariance, static_cast<std::size_t>(block.count),
                             stored, nullptr, linearity);
}

// A voxel's key and slot, for the blocks' sweep in key order.
struct KeyedSlot {
  VoxelKey key;
  std::uint32_t slot;
};

// The voxels' keys in the sweep's order as they are: the lowest voxel of column c (dx = c / 3 - 1,
// dy = c % 3 - 1) of a centre's block, and whether a key at or after it lies within the column's
// three (x, y equal, z at most 2 higher).
struct Keys {
  const RecycledVector<KeyedSlot>& sorted;

  [[nodiscard]] const VoxelKey& operator[](std::size_t k) const { return sorted[k].key; }
  [[nodiscard]] static VoxelKey lowest(const VoxelKey& centre, std::size_t c) {
    return VoxelKey{centre.x + static_cast<std::int64_t>(c / 3) - 1,
                    centre.y + static_cast<std::int64_t>(c % 3) - 1, centre.z - 1};
  }
  [[nodiscard]] static bool within(const VoxelKey& key, const VoxelKey& lowest) {
    return key.x == lowest.x && key.y == lowest.y && key.z <= lowest.z + 2;
  }
};

// The same keys packed in one word each, x then y then z from the most significant bits, each
// index offset by 1 from the grid's lowest with a spare bit (PackedKeys::of), so that a block's
// neighbours (+-1 along x and y, -1..+1 along z) are sums and differences of the word that never
// carry into the next field: one integer comparison where the keys' took up to three, whose
// branches were a quarter of the sweep's cycles.
struct PackedKeys {
  RecycledVector<std::uint64_t> words;
  std::uint64_t step_x = 0;  // +1 along x in the word
  std::uint64_t step_y = 0;

  [[nodiscard]] std::uint64_t operator[](std::size_t k) const { return words[k]; }
  [[nodiscard]] std::uint64_t lowest(std::uint64_t centre, std::size_t c) const {
    return centre + (c / 3) * step_x + (c % 3) * step_y - step_x - step_y - 1;
  }
  [[nodiscard]] static bool within(std::uint64_t key, std::uint64_t lowest) {
    return key <= lowest + 2;
  }

  // The packed keys of `sorted`, or nullopt when the indices' spans with their spare bits need
  // more than 64 bits.
  static std::optional<PackedKeys> of(const RecycledVector<KeyedSlot>& sorted);
};

std::optional<PackedKeys> PackedKeys::of(const RecycledVector<KeyedSlot>& sorted) {
  if (sorted.empty()) return PackedKeys{};
  VoxelKey low = sorted.front().key;
  VoxelKey high = sorted.front().key;
  for (const KeyedSlot& e : sorted) {
    low = {std::min(low.x, e.key.x), std::min(low.y, e.key.y), std::min(low.z, e.key.z)};
    high = {std::max(high.x, e.key.x), std::max(high.y, e.key.y), std::max(high.z, e.key.z)};
  }
  // An index i of a field with span s = high - low is stored as i - low + 1, and its neighbours
  // from i - low to i - low + 2 <= s + 2 < 2^(bit_width(s) + 1).
  const auto width = [](std::int64_t a, std::int64_t b) {
    return std::bit_width(static_cast<std::uint64_t>(b - a)) + 1;
  };
  const int bz = width(low.z, high.z);
  const int by = width(low.y, high.y);
  const int bx = width(low.x, high.x);
  if (bx + by + bz > 64) return std::nullopt;
  PackedKeys packed;
  packed.step_y = std::uint64_t{1} << bz;
  packed.step_x = std::uint64_t{1} << (by + bz);
  packed.words.resize(sorted.size());
  for (std::size_t k = 0; k < sorted.size(); ++k) {
    const VoxelKey& key = sorted[k].key;
    const auto field = [](std::int64_t i, std::int64_t from) {
      return static_cast<std::uint64_t>(i - from) + 1;
    };
    packed.words[k] = field(key.x, low.x) * packed.step_x + field(key.y, low.y) * packed.step_y +
                      field(key.z, low.z);
  }
  return packed;
}

// The block sums of the voxels sorted[begin, end) (sorted by key; `keys` the same keys, as they
// are or packed), adding the 27 voxels in one fixed order (dx, dy, dz each from -1 to 1): for
// each of the 9 columns (x+dx, y+dy) a cursor moves forward through the sorted keys as the
// voxels do, and the column's voxels dz = -1..1 are the next ones at its cursor. Sequential
// reads instead of 26 hash-table probes per voxel, which missed the cache and were 22 % of a
// Kinect registration's cycles (the sweep: 8.6 %). `moments` are in the keys' order (sorted[k]'s
// at k), so that the cursors read them in sequence too; visit(slot, block sum, the voxel's own
// moments).
template <class KeysInOrder, class Visit>
void sweep_blocks(const RecycledVector<KeyedSlot>& sorted, const KeysInOrder& keys,
                  const RecycledVector<Moments>& moments, std::size_t begin, std::size_t end,
                  const Visit& visit) {
  const std::size_t n = sorted.size();
  std::array<std::size_t, 9> cursor{};
  for (std::size_t c = 0; c < 9 && begin < end; ++c) {
    const auto lowest = keys.lowest(keys[begin], c);
    // The first key not below `lowest`: a binary search over the indices of `keys`.
    cursor[c] = *std::ranges::partition_point(std::views::iota(std::size_t{0}, n),
                                              [&](std::size_t k) { return keys[k] < lowest; });
  }
  for (std::size_t i = begin; i < end; ++i) {
    Moments block;
    for (std::size_t c = 0; c < 9; ++c) {
      const auto lowest = keys.lowest(keys[i], c);
      std::size_t& j = cursor[c];
      while (j < n && keys[j] < lowest) ++j;
      for (std::size_t k = j; k < n && k < j + 3; ++k) {
        if (!KeysInOrder::within(keys[k], lowest)) break;
        block += moments[k];
      }
    }
    visit(sorted[i].slot, block, moments[i]);
  }
}

// `values` sorted by a least-significant-digit radix sort of their lowest `bits` bits (11-bit
// digits): linear in the count, where a comparison sort of a 20k-voxel grid's keys took 1.3 ms.
void radix_sort(RecycledVector<std::uint64_t>& values, int bits) {
  constexpr int kDigitBits = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
  RecycledVector<std::uint64_t> other(values.size());
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
RecycledVector<KeyedSlot> sorted_by_key(const RecycledVector<VoxelKey>& keys) {
  const std::size_t n = keys.size();
  RecycledVector<KeyedSlot> out(n);
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
  RecycledVector<std::uint64_t> words(n);
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

}  // namespace

// The block surface of every voxel of an accumulated table into `normals` and `covariances` (by
// slot), and each block's linearity into `linearities` when given; `stored` from
// in_stored_frame. `side` runs on a second thread while the first sorts the keys, and that
// thread then joins the sweep: the sweep is claimed in chunks by whichever thread is free. Each
// voxel's surface is a pure function of its block (sweep_blocks), so the values are the same for
// any thread count and split.
void sweep_surfaces(const VoxelTable<Moments>& table, const NeighborhoodSettings& stored,
                    std::size_t threads, std::vector<Eigen::Vector3f>& normals,
                    std::vector<Eigen::Matrix3f>& covariances, const std::function<void()>& side,
                    std::vector<double>* linearities) {
  const auto& voxels = table.voxels;
  const std::size_t n = voxels.size();
  normals.resize(n);
  covariances.resize(n);
  if (linearities != nullptr) linearities->resize(n);
  RecycledVector<KeyedSlot> sorted;
  RecycledVector<Moments> in_key_order;  // voxels[sorted[k].slot] at k
  std::optional<PackedKeys> packed;
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
      const auto surface = [&](std::uint32_t v, const Moments& block, const Moments& own) {
        double* linearity = linearities != nullptr ? &(*linearities)[v] : nullptr;
        const PointSurface s = block_surface_of(block, own.centroid(), stored, linearity);
        normals[v] = s.normal;
        covariances[v] = s.covariance;
      };
      const std::size_t chunk_end = std::min(n, begin + kSweepChunk);
      if (packed) {
        sweep_blocks(sorted, *packed, in_key_order, begin, chunk_end, surface);
      } else {
        sweep_blocks(sorted, Keys{sorted}, in_key_order, begin, chunk_end, surface);
      }
    }
  };
  const auto sort_keys = [&] {
    SortState state = SortState::failed;
    try {
      sorted = sorted_by_key(table.keys);
      in_key_order.resize(n);
      for (std::size_t k = 0; k < n; ++k) in_key_order[k] = voxels[sorted[k].slot];
      packed = PackedKeys::of(sorted);
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

}  // namespace detail

PointCloud voxel_downsample_with_surfaces(const PointCloud& cloud, double voxel_size_m,
                                          const NeighborhoodSettings& settings) {
  detail::check_neighborhood(settings);
  const auto table =
      detail::accumulate_voxels<detail::Moments>(cloud, voxel_size_m, settings.num_threads);
  PointCloud out = detail::centroids_of(table.voxels, cloud.origin_m);
  detail::sweep_surfaces(table, detail::in_stored_frame(settings, cloud), settings.num_threads,
                         out.normals, out.covariances, [] {});
  return out;
}

}  // namespace sgdicp
