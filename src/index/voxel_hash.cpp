#include "index/voxel_hash.hpp"

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/format_number.hpp"

namespace sgdicp::detail {
namespace {

float largest_coordinate_of(const BoundingBox& box) {
  return static_cast<float>(std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff()));
}

// Refuses a cell so small that the box spans more than kMaxCellsPerAxis of them along an axis.
void check_cell_count(const BoundingBox& box, double cell_m) {
  const double cells = ((box.max - box.min) / cell_m).maxCoeff();
  if (!(cells < VoxelHash::kMaxCellsPerAxis)) {
    throw InvalidSettingsError("voxel hash: cell size " + format_number(cell_m) +
                               " m is too small for a reference " +
                               format_number((box.max - box.min).maxCoeff()) +
                               " m across (more than 2^21 cells along an axis)");
  }
}

using Key = std::array<std::int64_t, 3>;

// Each item's slot among the distinct keys of the items (in first-seen order), the keys into
// `keys`: one probe of `slots` per run of equal keys.
template <class KeyOf>
RecycledVector<std::uint32_t> slots_of(std::size_t items, KeyOf key_of, VoxelSlots& slots,
                                       std::vector<Key>& keys) {
  RecycledVector<std::uint32_t> out(items);
  for (std::size_t i = 0; i < items; ++i) {
    const VoxelKey key = key_of(i);
    const std::size_t slot = slots.slot(key);
    if (slot == keys.size()) keys.push_back({key.x, key.y, key.z});
    out[i] = static_cast<std::uint32_t>(slot);
  }
  return out;
}

// A counting sort: place(position, i) for every item i, the items in the order of their groups
// (stably); returns where each group begins in that order, and where the last ends.
template <class Place>
RecycledVector<std::uint32_t> counting_sort(const RecycledVector<std::uint32_t>& group_of,
                                            std::size_t groups, Place place) {
  RecycledVector<std::uint32_t> begins(groups + 1, 0);
  for (const std::uint32_t g : group_of) ++begins[g + 1];
  for (std::size_t g = 0; g < groups; ++g) begins[g + 1] += begins[g];
  RecycledVector<std::uint32_t> next(begins.begin(), begins.end() - 1);
  for (std::size_t i = 0; i < group_of.size(); ++i) place(next[group_of[i]]++, i);
  return begins;
}

}  // namespace

VoxelHash::VoxelHash(const PointCloud& cloud, const BoundingBox& box, double cell_m)
    : cell_m_(cell_m), inverse_cell_(1.0 / cell_m), slots_(cloud.size() / 4) {
  const VoxelGrid grid(cell_m, largest_coordinate_of(box));  // checks the cell size
  check_cell_count(box, cell_m);
  const VoxelKey first = grid.key(box.min.cast<float>());
  const VoxelKey last = grid.key(box.max.cast<float>());
  first_ = {first.x, first.y, first.z};
  last_ = {last.x, last.y, last.z};

  std::vector<Key> keys;
  const RecycledVector<std::uint32_t> cells = slots_of(
      cloud.size(), [&](std::size_t i) { return grid.key(cloud.points[i]); }, slots_, keys);
  entries_.resize(cloud.size());
  const auto begins = counting_sort(cells, keys.size(), [&](std::size_t at, std::size_t i) {
    entries_[at] = {cloud.points[i], static_cast<std::uint32_t>(i)};
  });
  levels_.push_back({blocks_of(keys, begins), {}, cell_m});
  build_pyramid();
}

RecycledVector<VoxelHash::Block> VoxelHash::blocks_of(const std::vector<Key>& keys,
                                                      const RecycledVector<std::uint32_t>& begins) {
  RecycledVector<Block> blocks(keys.size() + 1, Block{Key{}, begins.back()});
  for (std::size_t b = 0; b < keys.size(); ++b) blocks[b] = {keys[b], begins[b]};
  return blocks;
}

void VoxelHash::build_pyramid() {
  while (levels_.back().blocks.size() - 1 > kTopBlocks) {
    const RecycledVector<Block>& below = levels_.back().blocks;
    const std::size_t count = below.size() - 1;
    VoxelSlots slots(count / 8);
    std::vector<Key> keys;
    // An arithmetic shift: the floor of the quotient for negative keys too.
    const RecycledVector<std::uint32_t> parents = slots_of(
        count,
        [&](std::size_t b) {
          const Key& k = below[b].key;
          return VoxelKey{k[0] >> kBlockShift, k[1] >> kBlockShift, k[2] >> kBlockShift};
        },
        slots, keys);
    Level up;
    up.size_m = levels_.back().size_m * (1 << kBlockShift);
    up.members.resize(count);
    const auto begins = counting_sort(parents, keys.size(), [&](std::size_t at, std::size_t b) {
      up.members[at] = static_cast<std::uint32_t>(b);
    });
    up.blocks = blocks_of(keys, begins);
    levels_.push_back(std::move(up));
  }
  roots_.resize(levels_.back().blocks.size() - 1);
  for (std::size_t b = 0; b < roots_.size(); ++b) roots_[b] = static_cast<std::uint32_t>(b);
}

}  // namespace sgdicp::detail
