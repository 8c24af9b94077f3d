#pragma once
// The voxel-hash backend of ReferenceIndex and the odometry map's storage (private): points kept
// by cubic cell (a hash from a cell to its points), and above the cells a pyramid of blocks
// (2^3 cells, 2^3 of those, ...) up to a level of a few blocks. It grows and shrinks in place:
// adding a point costs one probe of the hash (and a few more when its cell is new), dropping a
// cell moves the last points of the flat cloud into its gaps, so a map that gains a frame and
// loses its far cells is never rebuilt. A cell is 2x2x2 voxels, each admitting at most a bound of
// points, and a point only while no point of its voxel lies within the spacing sqrt(v^2 / bound)
// of it, v the voxel's side (the odometry map's rule: a surface seen again adds nothing once it
// is covered); a reference indexed as given (unbounded) takes every point.
// A query visits the cells around its own shell by shell (Chebyshev rings, up to kShells),
// skipping every cell whose box lies no closer than the worst distance its result set still
// accepts, and stops once nothing outside can be closer. A query whose answer lies farther (new
// ground, a sensor moved by metres) would need shells of many empty cells: it goes down the
// pyramid instead, nearest block first, pruned as the cells are. The result sets are the
// KD-tree's (nanoflann's interface) and the distances the same float arithmetic, so the answers
// are the tree's, ties aside.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "index/key_slots.hpp"
#include "index/squared_distance.hpp"
#include "points/voxel_table.hpp"
#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp::detail {

class VoxelHash {
 public:
  static constexpr std::size_t kUnbounded = std::numeric_limits<std::size_t>::max();

  /// An empty hash of cubic cells of side cell_m, each of 2x2x2 voxels admitting at most
  /// max_points_per_voxel points, no two within spacing_m() (none for kUnbounded). Throws
  /// InvalidSettingsError for a cell that is not positive and finite or a bound of 0.
  explicit VoxelHash(double cell_m, std::size_t max_points_per_voxel = kUnbounded);

  /// The indices of the points of `cloud` that add(cloud) keeps, in order: a finite point enters
  /// while its voxel holds fewer than the bound and none within spacing_m() of it, counting the
  /// points of `cloud` admitted before it.
  [[nodiscard]] std::vector<std::uint32_t> admitted(const PointCloud& cloud) const;
  /// Adds the admitted points of `cloud` at the end of cloud(), with their normals (covariances)
  /// while every point added since the hash was last empty came with one; a cloud of no points
  /// changes nothing. Throws
  /// InvalidSettingsError for a coordinate too large for the cell size, InvalidInputError beyond
  /// 2^32 - 1 points.
  void add(const PointCloud& cloud);
  /// Drops every cell whose first point lies farther than radius_m from centre_m; the last
  /// points of cloud() move into the gaps.
  void remove_far_from(const Eigen::Vector3d& centre_m, double radius_m);
  /// Stores normals and covariances for cloud() (one per point each, or empty).
  void set_surfaces(std::vector<Eigen::Vector3f> normals, std::vector<Eigen::Matrix3f> covariances);
  void clear();

  /// Every point held, in no particular order (an index into it is what a search returns).
  [[nodiscard]] const PointCloud& cloud() const noexcept { return cloud_; }
  /// The box of cloud()'s points.
  [[nodiscard]] const BoundingBox& box() const noexcept { return box_; }
  /// Occupied voxels (a cell holds up to 8).
  [[nodiscard]] std::size_t voxels() const noexcept { return voxels_; }
  [[nodiscard]] double cell_m() const noexcept { return cell_m_; }
  [[nodiscard]] std::size_t max_points_per_voxel() const noexcept { return max_points_; }
  /// The least distance between two points of a voxel: sqrt(v^2 / bound) for a voxel of side v
  /// (half a cell), 0 for an unbounded hash.
  [[nodiscard]] double spacing_m() const noexcept { return spacing_m_; }

  /// Offers every point that can be closer than result.worstDist() to result.addPoint(squared
  /// distance, index), as nanoflann's findNeighbors does with its result sets.
  /// With first_per_voxel, only the first point each voxel received is offered (one point per
  /// voxel: the coarse view of a map, ReferenceIndex::coarse_view()).
  template <class Result>
  void search(const Eigen::Vector3f& query, Result& result, bool first_per_voxel = false) const {
    if (!query.allFinite() || cells_.empty()) return;  // the tree finds nothing for it either
    const Eigen::Vector3d q = query.cast<double>();
    Key centre;
    for (std::size_t d = 0; d < 3; ++d) {
      // Outside the box, the nearest cell of the grid: the shells then grow into the grid.
      const double i = std::clamp(std::floor(q[static_cast<Eigen::Index>(d)] * inverse_cell_),
                                  static_cast<double>(first_[d]), static_cast<double>(last_[d]));
      centre[d] = static_cast<std::int64_t>(i);
    }
    for (std::int64_t r = 0;; ++r) {
      if (r > 0) {
        const double outside = distance_beyond_block(q, centre, r - 1);
        if (std::isinf(outside) || beyond(outside * outside, result.worstDist())) return;
      }
      // Shells grow as r^2: past a few, the pyramid finds the far points for less.
      const auto side = static_cast<std::size_t>(2 * r + 1);
      if (r > kShells || side * side * side > cells_.size()) {
        return visit_blocks(levels_.size(), roots_, query, Visited{centre, r - 1, first_per_voxel},
                            result);
      }
      visit_shell(query, centre, r, first_per_voxel, result);
    }
  }

  /// Shells visited cell by cell before the search goes down the pyramid.
  static constexpr std::int64_t kShells = 2;
  /// The pyramid grows a level once its top holds more than this many blocks.
  static constexpr std::size_t kTopBlocks = 64;

 private:
  using Key = std::array<std::int64_t, 3>;
  struct Entry {
    Eigen::Vector3f point;
    std::uint32_t index;  // into cloud_
  };
  struct Cell {
    std::vector<Entry> entries;  // each occupied voxel's first point first (`firsts` of them)
    std::uint32_t firsts = 0;
    std::array<std::uint32_t, 8> counts{};  // points per voxel of the cell (by octant)
    Eigen::Vector3f min{Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity())};
    Eigen::Vector3f max{Eigen::Vector3f::Constant(-std::numeric_limits<float>::infinity())};
  };
  // Where a point of cloud_ is listed: cells_[cell].entries[at].
  struct Owner {
    std::uint32_t cell;
    std::uint32_t at;
  };
  // A level of blocks above the cells (level l >= 1: blocks of 2^l cells a side), dense by slot;
  // a block's children are the occupied octants of the level below, a bit each.
  struct Level {
    KeySlots slots;
    std::vector<VoxelKey> keys;
    std::vector<std::uint8_t> children;
  };
  // The cells the shells visited: within Chebyshev radius r of centre (and what they offered).
  struct Visited {
    Key centre;
    std::int64_t r;
    bool first_per_voxel;
    [[nodiscard]] bool holds(const VoxelKey& key) const {
      return std::abs(key.x - centre[0]) <= r && std::abs(key.y - centre[1]) <= r &&
             std::abs(key.z - centre[2]) <= r;
    }
  };

  // Whether a cell (or block) whose squared gap to the query is gap_sq can hold no point the
  // result set accepts. The gap is shrunk by a relative 1e-5, far above the float rounding of a
  // squared distance (a few 1e-8) and of a point's cell (an ulp of a coordinate), so that a
  // skipped cell never holds a point the tree would take.
  [[nodiscard]] static bool beyond(double gap_sq, float worst) {
    return gap_sq * (1.0 - 1e-5) >= static_cast<double>(worst);
  }

  // The gap from coordinate q to the i-th interval of length size_m along one axis, metres (0
  // inside it).
  [[nodiscard]] static double gap(std::int64_t i, double q, double size_m) {
    const double low = static_cast<double>(i) * size_m;
    return std::max({0.0, low - q, q - (low + size_m)});
  }
  [[nodiscard]] static double gap_sq(const VoxelKey& key, const Eigen::Vector3d& q, double size_m) {
    const double x = gap(key.x, q.x(), size_m);
    const double y = gap(key.y, q.y(), size_m);
    const double z = gap(key.z, q.z(), size_m);
    return x * x + y * y + z * z;
  }

  // The least distance from q to a cell of the grid outside the block of cells within Chebyshev
  // radius r of centre; infinity when the block covers the grid.
  [[nodiscard]] double distance_beyond_block(const Eigen::Vector3d& q, const Key& centre,
                                             std::int64_t r) const {
    double least = std::numeric_limits<double>::infinity();
    for (std::size_t d = 0; d < 3; ++d) {
      const double qd = q[static_cast<Eigen::Index>(d)];
      if (centre[d] - r > first_[d]) {
        least = std::min(least, qd - static_cast<double>(centre[d] - r) * cell_m_);
      }
      if (centre[d] + r < last_[d]) {
        least = std::min(least, static_cast<double>(centre[d] + r + 1) * cell_m_ - qd);
      }
    }
    return std::max(0.0, least);
  }

  // The cells at Chebyshev distance exactly r from centre (inside the grid), z, then y, then x.
  template <class Result>
  void visit_shell(const Eigen::Vector3f& query, const Key& centre, std::int64_t r,
                   bool first_per_voxel, Result& result) const {
    const Eigen::Vector3d q = query.cast<double>();
    const auto lo = [&](std::size_t d) { return std::max(centre[d] - r, first_[d]); };
    const auto hi = [&](std::size_t d) { return std::min(centre[d] + r, last_[d]); };
    for (std::int64_t z = lo(2); z <= hi(2); ++z) {
      const double gz = gap(z, q.z(), cell_m_);
      if (beyond(gz * gz, result.worstDist())) continue;
      for (std::int64_t y = lo(1); y <= hi(1); ++y) {
        const double gy = gap(y, q.y(), cell_m_);
        const double gzy = gz * gz + gy * gy;
        if (beyond(gzy, result.worstDist())) continue;
        const bool on_face =
            z == centre[2] - r || z == centre[2] + r || y == centre[1] - r || y == centre[1] + r;
        const std::int64_t step = on_face || r == 0 ? 1 : 2 * r;  // inside: the two x ends only
        for (std::int64_t x = centre[0] - r; x <= centre[0] + r; x += step) {
          if (x < first_[0] || x > last_[0]) continue;
          const double gx = gap(x, q.x(), cell_m_);
          if (beyond(gzy + gx * gx, result.worstDist())) continue;
          const std::uint32_t slot = cell_slots_.find(VoxelKey{x, y, z});
          if (slot != KeySlots::kNone) visit_cell(slot, query, first_per_voxel, result);
        }
      }
    }
  }

  // Level 0: the cells; level l > 0: levels_[l - 1].
  [[nodiscard]] const std::vector<VoxelKey>& keys_at(std::size_t level) const {
    return level == 0 ? cell_keys_ : levels_[level - 1].keys;
  }
  [[nodiscard]] const KeySlots& slots_at(std::size_t level) const {
    return level == 0 ? cell_slots_ : levels_[level - 1].slots;
  }

  // The blocks `slots` of a level other than the cells the shells visited: the one nearest the
  // query first, then every other not beyond the result's worst; for a block, its children.
  template <class Result>
  void visit_blocks(std::size_t level, std::span<const std::uint32_t> slots,
                    const Eigen::Vector3f& query, const Visited& visited, Result& result) const {
    const Eigen::Vector3d q = query.cast<double>();
    const std::vector<VoxelKey>& keys = keys_at(level);
    const double size_m = std::ldexp(cell_m_, static_cast<int>(level));
    const auto visit = [&](std::uint32_t b) {
      if (level == 0) {
        if (!visited.holds(keys[b])) visit_cell(b, query, visited.first_per_voxel, result);
        return;
      }
      std::array<std::uint32_t, 8> children{};
      std::size_t count = 0;
      const std::uint8_t bits = levels_[level - 1].children[b];
      for (unsigned o = 0; o < 8; ++o) {
        if ((bits >> o & 1U) != 0) children[count++] = slots_at(level - 1).find(child(keys[b], o));
      }
      visit_blocks(level - 1, std::span(children.data(), count), query, visited, result);
    };
    std::size_t nearest = slots.size();
    double least = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < slots.size(); ++i) {
      const double g = gap_sq(keys[slots[i]], q, size_m);
      if (g < least) {
        least = g;
        nearest = i;
      }
    }
    if (nearest == slots.size() || beyond(least, result.worstDist())) return;
    visit(slots[nearest]);
    for (std::size_t i = 0; i < slots.size(); ++i) {
      if (i != nearest && !beyond(gap_sq(keys[slots[i]], q, size_m), result.worstDist())) {
        visit(slots[i]);
      }
    }
  }

  template <class Result>
  void visit_cell(std::uint32_t slot, const Eigen::Vector3f& query, bool first_per_voxel,
                  Result& result) const {
    const Cell& cell = cells_[slot];
    const std::size_t n = first_per_voxel ? cell.firsts : cell.entries.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Entry& e = cell.entries[i];
      const float d = tree_squared_distance(query, e.point);
      if (d < result.worstDist()) result.addPoint(d, e.index);
    }
  }

  // A key's block one level up (an arithmetic shift: the floor of the quotient for negative keys
  // too), its octant in that block, and the key of a block's octant one level down.
  [[nodiscard]] static VoxelKey parent(const VoxelKey& k) { return {k.x >> 1, k.y >> 1, k.z >> 1}; }
  [[nodiscard]] static unsigned octant(const VoxelKey& k) {
    return static_cast<unsigned>((k.x & 1) | (k.y & 1) << 1 | (k.z & 1) << 2);
  }
  [[nodiscard]] static VoxelKey child(const VoxelKey& k, unsigned o) {
    return {k.x * 2 + (o & 1U), k.y * 2 + (o >> 1 & 1U), k.z * 2 + (o >> 2 & 1U)};
  }

  // Whether a point of `voxel` (of `cell`) lies closer than the spacing to p. The distance first,
  // the voxel only for an entry that close: a cell lists its 8 voxels' points in no order, and
  // a byte per entry naming its voxel, kept beside the entries, cost more memory than it saved
  // time (docs/design.md, *The map's spacing rule*).
  [[nodiscard]] bool crowded(const Cell& cell, const VoxelGrid& grid, const VoxelKey& voxel,
                             const Eigen::Vector3f& p) const {
    for (const Entry& e : cell.entries) {
      if (too_close(e.point, p) && grid.key(e.point) == voxel) return true;
    }
    return false;
  }
  [[nodiscard]] bool too_close(const Eigen::Vector3f& a, const Eigen::Vector3f& b) const {
    return (a - b).squaredNorm() < spacing_sq_;
  }

  std::uint32_t add_cell(const VoxelKey& key);
  void remove_cell(std::uint32_t slot);
  void drop_point(std::uint32_t index);
  void keep_first(Cell& cell);
  // Marks `key` (of level `level`) occupied in the levels above; unmark: no longer occupied.
  void mark_above(std::size_t level, VoxelKey key);
  void unmark_above(std::size_t level, VoxelKey key);
  void grow_pyramid();
  // The box, the grid's corner cells and the pyramid's roots, after points came or went.
  void refresh();

  double cell_m_;
  double inverse_cell_;
  std::size_t max_points_;
  double spacing_m_;
  float spacing_sq_;                  // its square, the test's (0: none)
  KeySlots cell_slots_;               // a cell's key -> its slot
  std::vector<VoxelKey> cell_keys_;   // by slot
  std::vector<Cell> cells_;           // by slot
  std::vector<Level> levels_;         // the blocks above the cells, coarser and coarser
  std::vector<std::uint32_t> roots_;  // every slot of the top level
  PointCloud cloud_;
  std::vector<Owner> owners_;                   // by point of cloud_
  bool normals_ = false, covariances_ = false;  // kept for every point of cloud_
  BoundingBox box_;
  Key first_{}, last_{};  // the least and greatest cell keys, by axis
  std::size_t voxels_ = 0;
};

}  // namespace sgdicp::detail
