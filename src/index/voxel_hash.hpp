#pragma once
// The voxel-hash backend of ReferenceIndex (private): the reference's points sorted by cubic cell
// into one array, a hash from a cell to its range of that array, and above the cells a pyramid of
// blocks (2^3 cells, 2^3 of those, ...) up to a level of a few blocks. The build is O(n): one key
// per point, one probe of a hash per run of points in one cell (the odometry map hands its points
// voxel by voxel), counting sorts. A query visits the cells around its own shell by shell
// (Chebyshev rings, up to kShells), skipping every cell whose box lies no closer than the worst
// distance its result set still accepts, and stops once nothing outside can be closer. A query
// whose answer lies farther (new ground, a sensor moved by metres) would need shells of many
// empty cells: it goes down the pyramid instead, nearest block first, pruned as the cells are.
// The result sets are the KD-tree's (nanoflann's interface) and the distances the same float
// arithmetic, so the answers are the tree's, ties aside.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "index/squared_distance.hpp"
#include "points/voxel_table.hpp"
#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp::detail {

class VoxelHash {
 public:
  /// Indexes `cloud` (finite points, box its bounding box). Throws InvalidSettingsError for a
  /// cell that is not positive and finite, or so small that the box spans more than
  /// kMaxCellsPerAxis cells along an axis.
  VoxelHash(const PointCloud& cloud, const BoundingBox& box, double cell_m);

  /// Offers every point that can be closer than result.worstDist() to result.addPoint(squared
  /// distance, index), as nanoflann's findNeighbors does with its result sets.
  template <class Result>
  void search(const Eigen::Vector3f& query, Result& result) const {
    if (!query.allFinite()) return;  // the tree finds nothing for it either
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
      if (r > kShells || side * side * side > cells().size()) {
        const std::size_t top = levels_.size() - 1;
        return visit_blocks(top, roots_.data(), roots_.data() + roots_.size(), query,
                            Visited{centre, r - 1}, result);
      }
      visit_shell(query, centre, r, result);
    }
  }

  /// Cells along an axis of the box at most (a larger count is a cell size given in the wrong
  /// unit, and the shells' cell arithmetic stays far from overflow).
  static constexpr double kMaxCellsPerAxis = 0x1p21;
  /// Shells visited cell by cell before the search goes down the pyramid.
  static constexpr std::int64_t kShells = 2;
  /// A block is 2^kBlockShift blocks of the level below a side (a cell's block: a shift of its
  /// key).
  static constexpr int kBlockShift = 1;
  /// The pyramid stops at a level of at most this many blocks.
  static constexpr std::size_t kTopBlocks = 64;

 private:
  using Key = std::array<std::int64_t, 3>;
  struct Entry {
    Eigen::Vector3f point;
    std::uint32_t index;  // into the reference cloud
  };
  // A cell (level 0) or a block: its key at its level, and where its members begin (level 0: in
  // entries_; above: in Level::members). Each level ends with a sentinel that ends the last.
  struct Block {
    Key key;
    std::uint32_t begin;
  };
  struct Level {
    RecycledVector<Block> blocks;
    RecycledVector<std::uint32_t> members;  // the blocks of the level below, by block (level > 0)
    double size_m = 0.0;                    // a block's side
  };
  // The cells the shells visited: within Chebyshev radius r of centre.
  struct Visited {
    Key centre;
    std::int64_t r;
    [[nodiscard]] bool holds(const Key& key) const {
      return std::abs(key[0] - centre[0]) <= r && std::abs(key[1] - centre[1]) <= r &&
             std::abs(key[2] - centre[2]) <= r;
    }
  };

  // The cells by slot, with the end sentinel.
  [[nodiscard]] std::span<const Block> cells() const {
    return {levels_.front().blocks.data(), levels_.front().blocks.size() - 1};
  }

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
  [[nodiscard]] static double gap_sq(const Key& key, const Eigen::Vector3d& q, double size_m) {
    const double x = gap(key[0], q.x(), size_m);
    const double y = gap(key[1], q.y(), size_m);
    const double z = gap(key[2], q.z(), size_m);
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
                   Result& result) const {
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
          if (!beyond(gzy + gx * gx, result.worstDist())) visit_cell({x, y, z}, query, result);
        }
      }
    }
  }

  // The blocks `members` of a level other than the cells the shells visited: the one nearest the
  // query first, then every other not beyond the result's worst; for a block, its members below.
  template <class Result>
  void visit_blocks(std::size_t level, const std::uint32_t* first, const std::uint32_t* last,
                    const Eigen::Vector3f& query, const Visited& visited, Result& result) const {
    const Eigen::Vector3d q = query.cast<double>();
    const Level& at = levels_[level];
    const auto visit = [&](std::uint32_t b) {
      if (level == 0) {
        if (!visited.holds(at.blocks[b].key)) visit_slot(b, query, result);
      } else {
        const std::uint32_t* members = at.members.data();
        visit_blocks(level - 1, members + at.blocks[b].begin, members + at.blocks[b + 1].begin,
                     query, visited, result);
      }
    };
    const std::uint32_t* nearest = last;
    double least = std::numeric_limits<double>::infinity();
    for (const std::uint32_t* b = first; b != last; ++b) {
      const double g = gap_sq(at.blocks[*b].key, q, at.size_m);
      if (g < least) {
        least = g;
        nearest = b;
      }
    }
    if (nearest == last || beyond(least, result.worstDist())) return;
    visit(*nearest);
    for (const std::uint32_t* b = first; b != last; ++b) {
      if (b != nearest && !beyond(gap_sq(at.blocks[*b].key, q, at.size_m), result.worstDist())) {
        visit(*b);
      }
    }
  }

  template <class Result>
  void visit_cell(const Key& key, const Eigen::Vector3f& query, Result& result) const {
    const std::size_t slot = slots_.find(VoxelKey{key[0], key[1], key[2]});
    if (slot != VoxelSlots::kNone) visit_slot(slot, query, result);
  }

  template <class Result>
  void visit_slot(std::size_t slot, const Eigen::Vector3f& query, Result& result) const {
    const RecycledVector<Block>& cells = levels_.front().blocks;
    for (std::uint32_t e = cells[slot].begin; e < cells[slot + 1].begin; ++e) {
      const float d = tree_squared_distance(query, entries_[e].point);
      if (d < result.worstDist()) result.addPoint(d, entries_[e].index);
    }
  }

  // The blocks of `keys` whose members begin at `begins` (which ends with the end of the last).
  static RecycledVector<Block> blocks_of(const std::vector<Key>& keys,
                                         const RecycledVector<std::uint32_t>& begins);
  // The levels above the cells, up to one of at most kTopBlocks blocks.
  void build_pyramid();

  double cell_m_;
  double inverse_cell_;
  Key first_{}, last_{};              // the cells of the box's corners
  VoxelSlots slots_;                  // a cell's key -> its slot
  RecycledVector<Entry> entries_;     // by cell (the arrays of a map rebuilt every frame are kept)
  std::vector<Level> levels_;         // the cells, then the blocks, coarser and coarser
  std::vector<std::uint32_t> roots_;  // every block of the top level
};

}  // namespace sgdicp::detail
