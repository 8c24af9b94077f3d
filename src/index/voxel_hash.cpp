#include "index/voxel_hash.hpp"

#include <numeric>
#include <string>
#include <utility>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/format_number.hpp"

namespace sgdicp::detail {
namespace {

// The largest absolute coordinate of the finite points (which alone enter), 0 for none.
float largest_coordinate_of(const PointCloud& cloud) {
  float largest = 0.0F;
  for (const Eigen::Vector3f& p : cloud.points) {
    if (p.allFinite()) largest = std::max(largest, p.cwiseAbs().maxCoeff());
  }
  return largest;
}

}  // namespace

VoxelHash::VoxelHash(double cell_m, std::size_t max_points_per_voxel)
    : cell_m_(cell_m),
      inverse_cell_(1.0 / cell_m),
      max_points_(max_points_per_voxel),
      // KISS-ICP's rule: N points of a voxel of side v spread over its surface at ~v / sqrt(N).
      spacing_m_(max_points_per_voxel == kUnbounded || max_points_per_voxel == 0
                     ? 0.0
                     : 0.5 * cell_m / std::sqrt(static_cast<double>(max_points_per_voxel))),
      spacing_sq_(static_cast<float>(spacing_m_ * spacing_m_)) {
  if (!std::isfinite(cell_m) || cell_m <= 0.0) {
    throw InvalidSettingsError("voxel hash: cell size must be positive and finite, got " +
                               format_number(cell_m) + " m");
  }
  if (max_points_per_voxel == 0) {
    throw InvalidSettingsError("voxel hash: at least one point per voxel");
  }
}

std::vector<std::uint32_t> VoxelHash::admitted(const PointCloud& cloud) const {
  std::vector<std::uint32_t> out;
  out.reserve(cloud.size());
  const VoxelGrid grid(0.5 * cell_m_, largest_coordinate_of(cloud));
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  KeySlots mine;  // the voxels this cloud fills, and how far (in `added`)
  std::vector<std::uint32_t> added;
  std::vector<std::uint32_t> latest;    // by voxel of `mine`: its last admitted point (in out)
  std::vector<std::uint32_t> previous;  // by point of out: the one admitted before it in its voxel
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!p.allFinite()) continue;
    if (max_points_ != kUnbounded) {
      const VoxelKey voxel = grid.key(p);
      const std::uint32_t cell = cell_slots_.find(parent(voxel));
      const std::size_t held = cell == KeySlots::kNone ? 0 : cells_[cell].counts[octant(voxel)];
      std::uint32_t at = mine.find(voxel);
      if (at == KeySlots::kNone) {
        at = static_cast<std::uint32_t>(added.size());
        mine.insert(voxel, at);
        added.push_back(0);
        latest.push_back(kNone);
      }
      if (held + added[at] >= max_points_) continue;
      if (held > 0 && crowded(cells_[cell], grid, voxel, p)) continue;
      bool near = false;
      for (std::uint32_t j = latest[at]; j != kNone && !near; j = previous[j]) {
        near = too_close(cloud.points[out[j]], p);
      }
      if (near) continue;
      ++added[at];
      previous.push_back(latest[at]);
      latest[at] = static_cast<std::uint32_t>(out.size());
    }
    out.push_back(static_cast<std::uint32_t>(i));
  }
  return out;
}

// One pass: a point is admitted by the counts and points as they stand, which already hold the
// points of `cloud` added before it (the rule admitted() states, without its second tables).
void VoxelHash::add(const PointCloud& cloud) {
  // A cloud of no points adds nothing and says nothing of surfaces (an odometry frame whose every
  // point falls in full voxels comes as one): taken as "without normals" it ended them for the
  // whole map, and the next frame's plane cost found none (issue 54: frame 1534 of a long run).
  if (cloud.empty()) return;
  if (cloud_.empty()) {
    normals_ = cloud.has_normals();
    covariances_ = cloud.has_covariances();
  }
  // A cloud without them ends them for the whole hash: a cost reads all or none.
  if (normals_ && !cloud.has_normals()) normals_ = false, cloud_.normals.clear();
  if (covariances_ && !cloud.has_covariances()) covariances_ = false, cloud_.covariances.clear();
  const VoxelGrid grid(0.5 * cell_m_, largest_coordinate_of(cloud));
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!p.allFinite()) continue;
    const VoxelKey voxel = grid.key(p);
    std::uint32_t slot = cell_slots_.find(parent(voxel));
    if (slot != KeySlots::kNone) {
      const std::uint32_t held = cells_[slot].counts[octant(voxel)];
      if (held >= max_points_) continue;
      if (held > 0 && spacing_sq_ > 0.0F && crowded(cells_[slot], grid, voxel, p)) continue;
    }
    if (cloud_.size() == std::numeric_limits<std::uint32_t>::max()) {
      refresh();
      throw InvalidInputError("voxel hash: more than 2^32-1 points");
    }
    if (slot == KeySlots::kNone) slot = add_cell(parent(voxel));
    Cell& cell = cells_[slot];
    const auto index = static_cast<std::uint32_t>(cloud_.size());
    owners_.push_back({slot, static_cast<std::uint32_t>(cell.entries.size())});
    cell.entries.push_back({p, index});
    if (cell.counts[octant(voxel)]++ == 0) {
      ++voxels_;
      keep_first(cell);
    }
    cell.min = cell.min.cwiseMin(p);
    cell.max = cell.max.cwiseMax(p);
    cloud_.points.push_back(p);
    if (normals_) cloud_.normals.push_back(cloud.normals[i]);
    if (covariances_) cloud_.covariances.push_back(cloud.covariances[i]);
  }
  refresh();
}

// The entry just appended is its voxel's first point: it moves to the end of the cell's firsts
// (the entry there, a later point of another voxel, takes its place at the end).
void VoxelHash::keep_first(Cell& cell) {
  const std::uint32_t last = static_cast<std::uint32_t>(cell.entries.size() - 1);
  const std::uint32_t to = cell.firsts++;
  if (to == last) return;
  std::swap(cell.entries[to], cell.entries[last]);
  owners_[cell.entries[to].index].at = to;
  owners_[cell.entries[last].index].at = last;
}

void VoxelHash::remove_far_from(const Eigen::Vector3d& centre_m, double radius_m) {
  const double r2 = radius_m * radius_m;
  bool removed = false;
  for (std::uint32_t slot = 0; slot < cells_.size();) {
    const Eigen::Vector3f& first = cells_[slot].entries.front().point;
    if ((first.cast<double>() - centre_m).squaredNorm() > r2) {
      remove_cell(slot);  // the last cell moves into this slot: look at it next
      removed = true;
    } else {
      ++slot;
    }
  }
  if (removed) refresh();
}

void VoxelHash::set_surfaces(std::vector<Eigen::Vector3f> normals,
                             std::vector<Eigen::Matrix3f> covariances) {
  cloud_.normals = std::move(normals);
  cloud_.covariances = std::move(covariances);
  normals_ = cloud_.has_normals();
  covariances_ = cloud_.has_covariances();
}

void VoxelHash::clear() {
  *this = VoxelHash(cell_m_, max_points_);
}

std::uint32_t VoxelHash::add_cell(const VoxelKey& key) {
  const auto slot = static_cast<std::uint32_t>(cells_.size());
  cells_.emplace_back();
  cell_keys_.push_back(key);
  cell_slots_.insert(key, slot);
  mark_above(0, key);
  grow_pyramid();
  return slot;
}

void VoxelHash::remove_cell(std::uint32_t slot) {
  const VoxelKey key = cell_keys_[slot];
  unmark_above(0, key);
  // Read each entry's index afresh: a point moved into a gap may be one of this cell's.
  const std::vector<Entry>& entries = cells_[slot].entries;
  for (std::size_t e = 0; e < entries.size(); ++e) drop_point(entries[e].index);
  for (const std::uint32_t count : cells_[slot].counts) voxels_ -= count > 0 ? 1 : 0;
  const auto last = static_cast<std::uint32_t>(cells_.size() - 1);
  if (slot != last) {
    cells_[slot] = std::move(cells_[last]);
    cell_keys_[slot] = cell_keys_[last];
    cell_slots_.reassign(cell_keys_[slot], slot);
    for (const Entry& e : cells_[slot].entries) owners_[e.index].cell = slot;
  }
  cell_slots_.erase(key);
  cells_.pop_back();
  cell_keys_.pop_back();
}

// Drops point `index` of cloud_: the last point takes its place, and its cell's entry learns so.
void VoxelHash::drop_point(std::uint32_t index) {
  const std::size_t last = cloud_.size() - 1;
  if (index != last) {
    cloud_.points[index] = cloud_.points[last];
    if (normals_) cloud_.normals[index] = cloud_.normals[last];
    if (covariances_) cloud_.covariances[index] = cloud_.covariances[last];
    owners_[index] = owners_[last];
    cells_[owners_[index].cell].entries[owners_[index].at].index = index;
  }
  cloud_.points.pop_back();
  if (normals_) cloud_.normals.pop_back();
  if (covariances_) cloud_.covariances.pop_back();
  owners_.pop_back();
}

void VoxelHash::mark_above(std::size_t level, VoxelKey key) {
  for (; level < levels_.size(); ++level) {
    Level& up = levels_[level];
    const VoxelKey block = parent(key);
    const std::uint32_t slot = up.slots.find(block);
    const auto bit = static_cast<std::uint8_t>(1U << octant(key));
    if (slot != KeySlots::kNone) {
      up.children[slot] |= bit;
      return;
    }
    up.slots.insert(block, static_cast<std::uint32_t>(up.keys.size()));
    up.keys.push_back(block);
    up.children.push_back(bit);
    key = block;
  }
}

void VoxelHash::unmark_above(std::size_t level, VoxelKey key) {
  for (; level < levels_.size(); ++level) {
    Level& up = levels_[level];
    const VoxelKey block = parent(key);
    const std::uint32_t slot = up.slots.find(block);
    up.children[slot] &= static_cast<std::uint8_t>(~(1U << octant(key)));
    if (up.children[slot] != 0) return;
    const auto last = static_cast<std::uint32_t>(up.keys.size() - 1);
    if (slot != last) {
      up.keys[slot] = up.keys[last];
      up.children[slot] = up.children[last];
      up.slots.reassign(up.keys[slot], slot);
    }
    up.slots.erase(block);
    up.keys.pop_back();
    up.children.pop_back();
    key = block;
  }
}

// A level above the top while the top holds more than kTopBlocks blocks (levels are never taken
// away: a map that shrank keeps a pyramid a little taller than it needs).
void VoxelHash::grow_pyramid() {
  while (keys_at(levels_.size()).size() > kTopBlocks) {
    levels_.emplace_back();
    const std::vector<VoxelKey> top = keys_at(levels_.size() - 1);
    for (const VoxelKey& key : top) mark_above(levels_.size() - 1, key);
  }
}

void VoxelHash::refresh() {
  box_ = BoundingBox{};
  first_.fill(std::numeric_limits<std::int64_t>::max());
  last_.fill(std::numeric_limits<std::int64_t>::min());
  for (std::size_t c = 0; c < cells_.size(); ++c) {
    box_.extend(cells_[c].min.cast<double>());
    box_.extend(cells_[c].max.cast<double>());
    const VoxelKey& k = cell_keys_[c];
    first_ = {std::min(first_[0], k.x), std::min(first_[1], k.y), std::min(first_[2], k.z)};
    last_ = {std::max(last_[0], k.x), std::max(last_[1], k.y), std::max(last_[2], k.z)};
  }
  roots_.resize(keys_at(levels_.size()).size());
  std::iota(roots_.begin(), roots_.end(), 0U);
}

}  // namespace sgdicp::detail
