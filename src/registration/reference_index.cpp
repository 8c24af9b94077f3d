#include "registration/reference_index.hpp"

#include <cmath>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "points/voxel_table.hpp"
#include "surfaces/block_surfaces.hpp"
#include "surfaces/point_surfaces.hpp"

namespace sgdicp::detail {
namespace {

// Where a registration's grid leaves single scan lines in its 3x3x3 blocks, the block normal is
// perpendicular to the beam, not to the surface: on the hand-held spinning LiDAR (BALM) the
// median block linearity is 0.93-0.98 and point-to-plane ends 2.6 cm / 0.183° off (79 % within
// 5 cm and 1°). Above kLinearBlocks each centroid takes the block surface of its voxel in a grid
// kCoarseFactor times coarser, whose blocks span several rings: BALM 0.58 cm / 0.053° / 100 %,
// 2 ms more (23.3 -> 25.3 ms); a factor of 2 left 0.081°. The threshold sits between dense LiDAR
// (KITTI 0.54-0.58, the car 0.54) and sparse rings (KITTI of 32 or 16 beams 0.74-0.99); RGB-D
// and maps are at 0.31-0.33. The same holds for a grid the user gives: BALM at 0.15 m voxels
// 3.2 cm / 0.214° / 76 % with the grid's own blocks, 0.61 cm / 0.051° / 100 % with the rule
// (docs/preprocessing.md, *Scan lines*).
constexpr double kLinearBlocks = 0.65;
constexpr std::int64_t kCoarseFactor = 3;  // integer: fine voxels nest in coarse ones

// Whether the median of the blocks' linearities (NaN, blocks of fewer than 3 points, left out) is
// above `threshold`: the middle of the n sorted values, the (n/2)-th from 0, lies above it
// exactly when at most n/2 lie at or below it. A count, not a sort; false when no block has one.
bool median_above(const std::vector<double>& linearities, double threshold) {
  std::size_t valid = 0;
  std::size_t at_or_below = 0;
  for (const double l : linearities) {
    if (std::isnan(l)) continue;
    ++valid;
    if (l <= threshold) ++at_or_below;
  }
  return valid > 0 && at_or_below <= valid / 2;
}

// The index of the coarse voxel holding fine voxel index i: floor(i / kCoarseFactor).
std::int64_t coarser(std::int64_t i) {
  const std::int64_t q = i / kCoarseFactor;
  return i % kCoarseFactor < 0 ? q - 1 : q;
}

// The grid kCoarseFactor times coarser than `fine`, summed from its voxels (each lies in one
// coarse voxel, so no point is hashed again and every fine voxel finds its own), and in
// `coarse_slot` the coarse slot of each fine slot.
VoxelTable<Moments> coarser_table(const VoxelTable<Moments>& fine,
                                  std::vector<std::uint32_t>& coarse_slot) {
  const std::size_t n = fine.keys.size();
  VoxelTable<Moments> coarse{VoxelSlots(n / 4), {}, {}, {}};
  coarse_slot.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const VoxelKey& f = fine.keys[i];
    const VoxelKey key{coarser(f.x), coarser(f.y), coarser(f.z)};
    const std::size_t slot = coarse.slots.slot(key);
    if (slot == coarse.keys.size()) {
      coarse.keys.push_back(key);
      coarse.voxels.emplace_back();
    }
    coarse.voxels[slot] += fine.voxels[i];
    coarse_slot[i] = static_cast<std::uint32_t>(slot);
  }
  return coarse;
}

// Each fine voxel's normal and covariance replaced by the block surface of its coarse voxel.
void take_coarse_surfaces(const VoxelTable<Moments>& fine, const NeighborhoodSettings& stored,
                          std::size_t threads, std::vector<Eigen::Vector3f>& normals,
                          std::vector<Eigen::Matrix3f>& covariances) {
  std::vector<std::uint32_t> coarse_slot;
  const VoxelTable<Moments> coarse = coarser_table(fine, coarse_slot);
  std::vector<Eigen::Vector3f> coarse_normals;
  std::vector<Eigen::Matrix3f> coarse_covariances;
  sweep_surfaces(coarse, stored, threads, coarse_normals, coarse_covariances, [] {});
  for (std::size_t i = 0; i < coarse_slot.size(); ++i) {
    normals[i] = coarse_normals[coarse_slot[i]];
    covariances[i] = coarse_covariances[coarse_slot[i]];
  }
}

// The index over the grid's centroids with their block surfaces (coarse ones where its blocks
// are scan lines). The tree over the centroids is built on one thread while the other sorts the
// keys and starts the sweep: neither waits for the other (sort, sweep and tree on two threads
// 6.1 -> 4.8-5.2 ms on a KITTI scan, 6.3 -> 5.1 ms on a Kinect frame).
ReferenceIndex with_block_surfaces(const VoxelTable<Moments>& table, PointCloud centroids,
                                   double voxel_size_m, const NeighborhoodSettings& stored,
                                   const KdTreeSettings& tree) {
  std::optional<ReferenceIndex> index;
  KdTreeSettings tree_alongside = tree;
  tree_alongside.num_threads = 1;
  std::vector<Eigen::Vector3f> normals;
  std::vector<Eigen::Matrix3f> covariances;
  std::vector<double> linearities;
  const auto build_tree = [&] {
    index.emplace(
        ReferenceIndex::on_voxel_grid(std::move(centroids), voxel_size_m, tree_alongside));
  };
  sweep_surfaces(table, stored, stored.num_threads, normals, covariances, build_tree, &linearities);
  if (median_above(linearities, kLinearBlocks)) {
    take_coarse_surfaces(table, stored, stored.num_threads, normals, covariances);
  }
  index->set_normals_and_covariances(std::move(normals), std::move(covariances));
  return std::move(*index);
}

}  // namespace

namespace {

// registration_index's, or nullopt when the cloud is to be used as it is.
std::optional<ReferenceIndex> index_on_grid(const PointCloud& cloud,
                                            const DownsamplingSettings& downsampling,
                                            const NeighborhoodSettings& settings, bool surfaces,
                                            const KdTreeSettings& tree) {
  double voxel_size_m = downsampling.voxel_size_m;
  const std::size_t downsample_to = downsampling.downsample_to;
  std::optional<VoxelTable<Counted>> settled;
  voxel_size_m = grid_size(cloud, voxel_size_m, downsample_to, settings.num_threads, &settled);
  if (voxel_size_m == 0.0) return std::nullopt;
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
  return with_block_surfaces(table, std::move(centroids), voxel_size_m,
                             in_stored_frame(settings, cloud), tree);
}

}  // namespace

ReferenceIndex registration_index(const PointCloud& cloud, const DownsamplingSettings& downsampling,
                                  const NeighborhoodSettings& settings, bool surfaces,
                                  const KdTreeSettings& tree) {
  std::optional<ReferenceIndex> index =
      index_on_grid(cloud, downsampling, settings, surfaces, tree);
  return index ? std::move(*index) : ReferenceIndex(PointCloud(cloud), tree);
}

ReferenceIndex registration_index(PointCloud&& cloud, const DownsamplingSettings& downsampling,
                                  const NeighborhoodSettings& settings, bool surfaces,
                                  const KdTreeSettings& tree) {
  std::optional<ReferenceIndex> index =
      index_on_grid(cloud, downsampling, settings, surfaces, tree);
  return index ? std::move(*index) : ReferenceIndex(std::move(cloud), tree);
}

}  // namespace sgdicp::detail
