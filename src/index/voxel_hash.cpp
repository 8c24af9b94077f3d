#include "index/voxel_hash.hpp"

#include <string>

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

}  // namespace

VoxelHash::VoxelHash(const PointCloud& cloud, const BoundingBox& box, double cell_m)
    : cell_m_(cell_m), inverse_cell_(1.0 / cell_m), slots_(cloud.size() / 4) {
  const VoxelGrid grid(cell_m, largest_coordinate_of(box));  // checks the cell size
  check_cell_count(box, cell_m);
  const VoxelKey first = grid.key(box.min.cast<float>());
  const VoxelKey last = grid.key(box.max.cast<float>());
  first_ = {first.x, first.y, first.z};
  last_ = {last.x, last.y, last.z};

  // Counting sort by cell: each point's slot (cells in first-seen order) and each cell's count.
  std::vector<std::uint32_t> point_slots(cloud.size());
  std::vector<std::uint32_t> counts;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const VoxelKey key = grid.key(cloud.points[i]);
    const std::size_t slot = slots_.slot(key);
    if (slot == keys_.size()) {
      keys_.push_back(key);
      counts.push_back(0);
    }
    ++counts[slot];
    point_slots[i] = static_cast<std::uint32_t>(slot);
  }
  begins_.assign(keys_.size() + 1, 0);
  for (std::size_t s = 0; s < keys_.size(); ++s) begins_[s + 1] = begins_[s] + counts[s];
  std::vector<std::uint32_t> next(begins_.begin(), begins_.end() - 1);
  entries_.resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    entries_[next[point_slots[i]]++] = {cloud.points[i], static_cast<std::uint32_t>(i)};
  }
  scan_threshold_ = keys_.size();
}

}  // namespace sgdicp::detail
