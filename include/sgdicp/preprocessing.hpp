#pragma once
// Preprocessing for the plane-based costs and for thinning clouds: local covariances and normals
// from k-nearest neighbourhoods (point-to-plane, GICP), the one estimator every caller uses (also
// prepare_reference for a reference index), and voxel-grid and random downsampling.
// See docs/preprocessing.md for settings, costs and an example.
#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "sgdicp/cost.hpp"
#include "sgdicp/nearest_neighbor.hpp"
#include "sgdicp/point_cloud.hpp"

namespace sgdicp {

/// How the local neighbourhood of every point is formed and summarised.
struct NeighborhoodSettings {
  /// Neighbours per point, including the point itself. In [3, 1000].
  std::size_t k = 20;
  /// Neighbours of a neighbourhood that is already flat, the point included: where the
  /// flat_k nearest points have a surface variation lambda_0 / (lambda_0 + lambda_1 + lambda_2)
  /// of at most `flatness` (and are not degenerate), they alone give the surface; elsewhere the
  /// k nearest do. More neighbours only average the noise of a rough surface, but on a smooth
  /// one they add its curvature: a sparse scan of a small object loses its shape in k = 20
  /// (docs/preprocessing.md, *Flat neighbourhoods*). 0 = always k (plain k-nearest
  /// neighbourhoods); otherwise in [3, k) to have an effect, at most 1000.
  std::size_t flat_k = 0;
  /// The largest surface variation (0 for a plane, 1/3 for an isotropic blob) of a flat_k
  /// neighbourhood taken as flat. In [0, 1/3].
  double flatness = 0.05;
  /// Worker threads; 0 = std::thread::hardware_concurrency(). At most 1024. Results are
  /// bit-identical for any thread count.
  std::size_t num_threads = 0;
  /// Replace each covariance by the GICP plane model (Segal et al. 2009):
  /// C = V diag(epsilon, 1, 1) V^T, V the eigenvectors of the raw covariance, smallest first.
  /// Regularized covariances are unitless; raw ones are in m^2.
  bool regularize = true;
  /// Variance along the normal in the plane model, relative to 1 in the plane. In (0, 1].
  double epsilon = 1e-3;
  /// Normals are flipped to face this point (metres): n.dot(viewpoint - p) >= 0.
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();

  /// Throws InvalidSettingsError for k, flat_k, flatness, num_threads or epsilon out of range
  /// or a non-finite viewpoint. SgdSettings::validate() and BatchSettings::validate() call it.
  void validate() const;

  bool operator==(const NeighborhoodSettings&) const = default;
};

/// Fills cloud.covariances and cloud.normals (one per point) from the k nearest neighbours of
/// each point (itself included), found in a KD-tree built here over cloud.points.
///
/// With settings.flat_k, a point whose flat_k nearest neighbours lie flat (surface variation at
/// most settings.flatness) is summarised by those alone, any other by its k nearest.
///
/// Raw covariance: (1/n) sum (q - mean)(q - mean)^T over the n = min(k, size) neighbours, in m^2
/// (the 1/n of PCL and Open3D). Normal: unit eigenvector of its smallest eigenvalue, facing the
/// viewpoint. With settings.regularize, covariances are the unitless plane model instead.
///
/// Degenerate neighbourhoods (fewer than 3 points, all points identical, or collinear: the
/// second-largest eigenvalue is at most 1e-6 of the largest or at float-resolution level) have
/// no defined surface: their normal is set to zero (test with normal.isZero()), their regularized
/// covariance to the identity (uninformative in every direction: such points neither dominate
/// nor constrain a plane cost), and their raw covariance is the (finite, singular) sample one.
/// No output is ever NaN.
///
/// Throws InvalidSettingsError for out-of-range settings, InvalidInputError for an empty cloud
/// or a non-finite point. On throw the cloud is unchanged.
void estimate_covariances(PointCloud& cloud, const NeighborhoodSettings& settings = {});

/// The same, reusing a KD-tree built over exactly cloud.points (same size and same points, in
/// the same order; otherwise InvalidInputError).
void estimate_covariances(PointCloud& cloud, const ReferenceIndex& index,
                          const NeighborhoodSettings& settings = {});

/// The normals of estimate_covariances only: fills cloud.normals and leaves cloud.covariances
/// untouched (no covariance is computed or stored). settings.regularize and epsilon are ignored
/// for the output but still validated.
void estimate_normals(PointCloud& cloud, const NeighborhoodSettings& settings = {});
void estimate_normals(PointCloud& cloud, const ReferenceIndex& index,
                      const NeighborhoodSettings& settings = {});

/// Gives the reference what `cost` needs (cost.hpp: normals for point-to-plane, covariances for
/// plane-to-plane), estimated with estimate_covariances over its own tree, unless it has it
/// already. Not thread-safe: call it before sharing the index between threads.
void prepare_reference(ReferenceIndex& reference, CostType cost,
                       const NeighborhoodSettings& neighborhood = {});

/// Throws InvalidInputError when the reference lacks what `cost` needs, saying how to get it.
void check_reference_prepared(const ReferenceIndex& reference, CostType cost);

/// One point per occupied cubic voxel of side voxel_size_m (metres): the centroid of the input
/// points in it. Voxel (i, j, l) holds the points with floor(x / voxel_size_m) = i, etc.
/// Output order is the order of each voxel's first point in the input, so the result is
/// deterministic. Normals and covariances are not carried over (the output has none):
/// estimate them after downsampling.
///
/// num_threads (0 = every core): clouds of 32,768 points or more are hashed and summed in two
/// fixed halves, merged in order, which two threads make at once; the result is the same for any
/// count.
///
/// An empty cloud gives an empty cloud. Throws InvalidSettingsError when voxel_size_m is not
/// positive and finite or so small that voxel indices would exceed 2^62 in magnitude, or
/// num_threads is above 1024, and InvalidInputError for a non-finite point.
[[nodiscard]] PointCloud voxel_downsample(const PointCloud& cloud, double voxel_size_m,
                                          std::size_t num_threads = 1);

/// voxel_downsample (same points, same order), with each centroid's normal and covariance
/// estimated as estimate_covariances does (settings: regularize, epsilon, viewpoint,
/// num_threads; the same degenerate cases) but over the input points of its 3x3x3 block of
/// voxels instead of its k nearest neighbours (settings.k is only validated). On a grid that
/// holds several points per voxel this summarises every input point at the cost of 26 table
/// look-ups per centroid, about half of a k-nearest estimate over the centroids
/// (docs/preprocessing.md); the registrations use it for their reference grid when the grid
/// holds at least k/9 points per voxel. Throws as voxel_downsample and estimate_covariances.
[[nodiscard]] PointCloud voxel_downsample_with_surfaces(const PointCloud& cloud,
                                                        double voxel_size_m,
                                                        const NeighborhoodSettings& settings = {});

/// The voxel size, metres, at which voxel_downsample keeps about `target_points` of the cloud
/// (within ~15 %; a few counting passes over the cloud, each cheaper than one voxel_downsample),
/// or 0 when there is nothing to thin: target_points is 0, the cloud has at most that many
/// points, they all lie in one place, or a point lies so far beyond the bulk (1e30 m) that no
/// grid fine enough for the bulk can index it. How the registrations choose their grid from the
/// data (SgdSettings::downsample_to, docs/preprocessing.md). Throws InvalidInputError for a
/// non-finite point.
[[nodiscard]] double voxel_size_for_count(const PointCloud& cloud, std::size_t target_points);

/// The voxel grid a registration thins `cloud` with, metres (0 = none): voxel_size_m when
/// positive, else voxel_size_for_count(cloud, downsample_to), except for a cloud that carries
/// normals or covariances, which the automatic grid leaves as it is so that they are used.
[[nodiscard]] double registration_voxel_size(const PointCloud& cloud, double voxel_size_m,
                                             std::size_t downsample_to);

/// `count` distinct points chosen uniformly at random without replacement (every subset of
/// that size is equally likely), returned in input order with their normals and covariances
/// when the cloud has them. Seeded and reproducible on any standard library (std::mt19937_64 raw
/// output, our own bounded draws). count >= size returns a copy of the cloud; count = 0 returns
/// an empty cloud. Throws InvalidInputError when normals or covariances are present but not one
/// per point.
[[nodiscard]] PointCloud random_downsample(const PointCloud& cloud, std::size_t count,
                                           std::uint64_t seed);

/// random_downsample with count = round(ratio * size), at least 1 for a non-empty cloud.
/// Throws InvalidSettingsError unless ratio is in (0, 1].
[[nodiscard]] PointCloud random_downsample_ratio(const PointCloud& cloud, double ratio,
                                                 std::uint64_t seed);

}  // namespace sgdicp
