#pragma once
// The nearest-neighbour structure over the reference cloud (paper eq. 8). Built once per
// reference and reused by any number of registrations, also from several threads at once:
// every query method is const and touches no shared mutable state.
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/points/scaling.hpp"

namespace sgdicp {
namespace detail {
class VoxelHash;
}

struct Neighbor {
  std::uint32_t index = 0;        ///< index into the reference cloud
  float squared_distance = 0.0F;  ///< metres^2
};

struct KdTreeSettings {
  /// Points per leaf. Larger leaves make the build cheaper (fewer levels to split) and, up to
  /// ~32, cost the single-nearest queries nothing measurable, since scanning a leaf is cheaper
  /// than descending the tree. 24 measured fastest end to end over ../shared/data/pairs
  /// (build -20 % against nanoflann's default of 10; median run 35.6 -> 29.4 ms over 72 runs).
  std::size_t leaf_size = 24;
  /// Threads that build the tree; 0 = std::thread::hardware_concurrency(), at most 1024. The
  /// tree, and so every query result, is the same for any count; clouds under 32,768 points are
  /// built on one thread (a thread start would cost more than it saves).
  std::size_t num_threads = 1;
  /// Thin the reference with a voxel grid of this side before indexing it, metres
  /// (voxel_downsample, points/voxel_grid.hpp: one centroid per occupied voxel); 0 = index every
  /// point as given. align() thins its source with the same grid (registration.hpp).
  double voxel_size_m = 0.0;

  /// Throws InvalidSettingsError for a leaf size of 0, more than 1024 threads or a negative or
  /// non-finite voxel size.
  void validate() const;
  bool operator==(const KdTreeSettings&) const = default;
};

/// A nearest-neighbour index over a reference cloud it owns: a KD-tree (nanoflann), or a voxel
/// hash (with_voxel_hash). Both give the same answers to every query (ties between points at the
/// same distance aside). Non-copyable, cheap to move.
class ReferenceIndex {
 public:
  /// Builds the tree, over the reference thinned by settings.voxel_size_m when it is set. Throws
  /// InvalidInputError for an empty cloud or a non-finite point.
  explicit ReferenceIndex(PointCloud reference, const KdTreeSettings& settings = {});
  /// An index over a cloud already thinned with a voxel grid of side voxel_size_m (e.g. by
  /// voxel_downsample_with_surfaces, keeping its normals and covariances), indexed as given;
  /// voxel_size_m() reports that grid, so that align() thins its source on it too.
  /// settings.voxel_size_m must be 0. Throws as the constructor, and InvalidSettingsError for a
  /// voxel size that is not positive and finite.
  [[nodiscard]] static ReferenceIndex on_voxel_grid(PointCloud thinned, double voxel_size_m,
                                                    const KdTreeSettings& settings = {});
  /// An index over `reference` as given (every point, with the normals and covariances it
  /// carries) by a voxel hash instead of a tree: the points sorted by cubic cell of side cell_m
  /// into one array, a hash from a cell to its range, and a pyramid of blocks of cells above
  /// them, built in O(n) (a KD-tree's build is O(n log n): 4-5x the time on an odometry map). A
  /// query searches the cells around its own, shell by shell, skipping those that cannot hold a
  /// closer point; an answer more than two cells away is found down the pyramid instead. Its
  /// queries cost more than the tree's (about 1.5x at a cell twice the spacing of the points):
  /// for a reference queried a few times per point and rebuilt often, such as an odometry map
  /// (odometry.hpp: cells of two map voxels). Cells much smaller than the usual query distance
  /// make queries slow; much larger ones scan many points each. voxel_size_m() is 0: the cell is
  /// for the search only, and align() uses its source as given. Throws InvalidInputError as the
  /// constructor, and InvalidSettingsError for a cell that is not positive and finite or is so
  /// small that the reference spans more than 2^21 cells along an axis.
  [[nodiscard]] static ReferenceIndex with_voxel_hash(PointCloud reference, double cell_m);
  /// An index over a voxel hash kept elsewhere, read in place: no copy, no build (an odometry
  /// map's, VoxelMap::index(), which grows and shrinks frame by frame). Valid while that hash
  /// lives and is not changed; its surfaces come with its points (set_normals_and_covariances
  /// throws). Throws InvalidInputError for an empty hash.
  [[nodiscard]] static ReferenceIndex viewing(const detail::VoxelHash& hash);
  /// A view of a map that keeps several points per voxel (viewing()) searching only the first
  /// point each voxel received: one per voxel, the same cloud() and point indices. SGD-ICP's
  /// coarse stage pairs with it (registration.hpp); nullptr for any other index.
  [[nodiscard]] const ReferenceIndex* coarse_view() const noexcept;
  ~ReferenceIndex();
  ReferenceIndex(ReferenceIndex&&) noexcept;
  ReferenceIndex& operator=(ReferenceIndex&&) noexcept;
  ReferenceIndex(const ReferenceIndex&) = delete;
  ReferenceIndex& operator=(const ReferenceIndex&) = delete;

  [[nodiscard]] const PointCloud& cloud() const noexcept;
  [[nodiscard]] const BoundingBox& bounding_box() const noexcept;
  /// The box of the bulk of the reference (scaling.hpp), computed on first use and kept.
  [[nodiscard]] const ScalingBox& bulk_bounding_box() const;
  [[nodiscard]] std::size_t size() const noexcept { return cloud().size(); }
  /// The voxel grid the reference was thinned with before indexing, metres (0 = none).
  [[nodiscard]] double voxel_size_m() const noexcept;
  /// The cell of a voxel-hash index (with_voxel_hash), metres; 0 for a KD-tree.
  [[nodiscard]] double voxel_hash_cell_m() const noexcept;

  /// The nearest reference point to query, if one lies within sqrt(max_squared_distance).
  /// Bounding the search prunes the tree early, so rejected queries are cheap.
  [[nodiscard]] std::optional<Neighbor> nearest(
      const Eigen::Vector3f& query,
      float max_squared_distance = std::numeric_limits<float>::max()) const;

  /// nearest(), the same point for the same arguments, and in `others_squared_distance` a lower
  /// bound on the squared distance from query to every other reference point: the second
  /// nearest's, or max_squared_distance when no second point lies within it. Slower than
  /// nearest() (the search prunes against the second distance); it lets a caller certify later
  /// queries near this one without the tree (detail::NearestMemory).
  [[nodiscard]] std::optional<Neighbor> nearest_and_bound(const Eigen::Vector3f& query,
                                                          float max_squared_distance,
                                                          float& others_squared_distance) const;

  /// Stores the reference's normals and covariances in cloud() (one per point each, or empty),
  /// as estimate_covariances (surfaces/normals.hpp) computes them over this tree; prepare_reference
  /// does both. Throws InvalidInputError for another count. Not thread-safe: call it before
  /// sharing the index between threads.
  void set_normals_and_covariances(std::vector<Eigen::Vector3f> normals,
                                   std::vector<Eigen::Matrix3f> covariances);

  /// The k nearest reference points to query, closest first (fewer if the cloud is smaller).
  /// `neighbors` is cleared and refilled; pass the same vector again to avoid allocations.
  void k_nearest(const Eigen::Vector3f& query, std::size_t k,
                 std::vector<Neighbor>& neighbors) const;

  /// The k nearest reference points closer than sqrt(squared_radius) to query, closest first
  /// (ties by index). Cheaper than k_nearest when the radius holds about k points or fewer: the
  /// search prunes at the radius from the start (FPFH's neighbourhoods, global/fpfh.hpp).
  void nearest_within(const Eigen::Vector3f& query, float squared_radius, std::size_t k,
                      std::vector<Neighbor>& neighbors) const;

 private:
  ReferenceIndex() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sgdicp
