#pragma once
// The voxel-hash backend of ReferenceIndex (private): the reference's points sorted by cubic cell
// into one array, and a hash from a cell to its range of that array. The build is O(n): one key
// per point, one probe of the hash per run of points in one cell (the odometry map hands its
// points voxel by voxel), a counting sort. A query visits the cells around its own ring by ring
// (Chebyshev shells), skips every cell whose box lies no closer than the worst distance its
// result set still accepts, and stops once nothing outside the rings visited can be closer: the
// same result sets as the KD-tree's (nanoflann's interface), the same distances in the same
// float arithmetic, so the same answers, ties aside.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
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
    std::size_t visited = 0;
    for (std::int64_t r = 0;; ++r) {
      if (r > 0) {
        const double outside = distance_beyond_block(q, centre, r - 1);
        if (std::isinf(outside) || beyond(outside * outside, result.worstDist())) return;
      }
      const auto side = static_cast<std::size_t>(2 * r + 1);
      visited += side * side * side;
      // Far past the occupied cells' count the shells are mostly empty: scan the cells instead.
      if (r > 0 && visited > scan_threshold_) return scan_outside_block(query, centre, r, result);
      visit_shell(query, centre, r, result);
    }
  }

  /// Cells along an axis of the box at most (a larger count is a cell size given in the wrong
  /// unit, and the shells' cell arithmetic stays far from overflow).
  static constexpr double kMaxCellsPerAxis = 0x1p21;

 private:
  using Key = std::array<std::int64_t, 3>;
  struct Entry {
    Eigen::Vector3f point;
    std::uint32_t index;  // into the reference cloud
  };

  // Whether a cell (or region) whose squared gap to the query is gap_sq can hold no point the
  // result set accepts. The gap is shrunk by a relative 1e-5, far above the float rounding of a
  // squared distance (a few 1e-8) and of a point's cell (an ulp of a coordinate), so that a
  // skipped cell never holds a point the tree would take.
  [[nodiscard]] static bool beyond(double gap_sq, float worst) {
    return gap_sq * (1.0 - 1e-5) >= static_cast<double>(worst);
  }

  // The gap from coordinate q to cell i along one axis, metres (0 inside it).
  [[nodiscard]] double gap(std::int64_t i, double q) const {
    const double low = static_cast<double>(i) * cell_m_;
    return std::max({0.0, low - q, q - (low + cell_m_)});
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
      const double gz = gap(z, q.z());
      if (beyond(gz * gz, result.worstDist())) continue;
      for (std::int64_t y = lo(1); y <= hi(1); ++y) {
        const double gy = gap(y, q.y());
        const double gzy = gz * gz + gy * gy;
        if (beyond(gzy, result.worstDist())) continue;
        const bool on_face =
            z == centre[2] - r || z == centre[2] + r || y == centre[1] - r || y == centre[1] + r;
        const std::int64_t step = on_face || r == 0 ? 1 : 2 * r;  // inside: the two x ends only
        for (std::int64_t x = centre[0] - r; x <= centre[0] + r; x += step) {
          if (x < first_[0] || x > last_[0]) continue;
          const double gx = gap(x, q.x());
          if (!beyond(gzy + gx * gx, result.worstDist())) visit_cell({x, y, z}, query, result);
        }
      }
    }
  }

  // Every occupied cell outside the block of radius r - 1 (visited already), in slot order.
  template <class Result>
  void scan_outside_block(const Eigen::Vector3f& query, const Key& centre, std::int64_t r,
                          Result& result) const {
    const Eigen::Vector3d q = query.cast<double>();
    for (std::size_t slot = 0; slot < keys_.size(); ++slot) {
      const VoxelKey& k = keys_[slot];
      const Key key{k.x, k.y, k.z};
      double gap_sq = 0.0;
      bool inside = true;
      for (std::size_t d = 0; d < 3; ++d) {
        inside = inside && std::abs(key[d] - centre[d]) < r;
        const double g = gap(key[d], q[static_cast<Eigen::Index>(d)]);
        gap_sq += g * g;
      }
      if (!inside && !beyond(gap_sq, result.worstDist())) visit_slot(slot, query, result);
    }
  }

  template <class Result>
  void visit_cell(const Key& key, const Eigen::Vector3f& query, Result& result) const {
    const std::size_t slot = slots_.find(VoxelKey{key[0], key[1], key[2]});
    if (slot != VoxelSlots::kNone) visit_slot(slot, query, result);
  }

  template <class Result>
  void visit_slot(std::size_t slot, const Eigen::Vector3f& query, Result& result) const {
    for (std::uint32_t e = begins_[slot]; e < begins_[slot + 1]; ++e) {
      const float d = tree_squared_distance(query, entries_[e].point);
      if (d < result.worstDist()) result.addPoint(d, entries_[e].index);
    }
  }

  double cell_m_;
  double inverse_cell_;
  Key first_{}, last_{};  // the cells of the box's corners
  VoxelSlots slots_;
  std::vector<VoxelKey> keys_;         // by slot
  std::vector<std::uint32_t> begins_;  // by slot, and the end of the last
  std::vector<Entry> entries_;         // by cell
  std::size_t scan_threshold_ = 0;
};

}  // namespace sgdicp::detail
