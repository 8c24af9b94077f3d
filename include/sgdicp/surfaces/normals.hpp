#pragma once
// Local covariances and normals from k-nearest neighbourhoods (point-to-plane, GICP): the one
// estimator every caller uses. See docs/preprocessing.md for settings, costs and an example.
#include <cstddef>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"

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

/// The points `which` of `cloud` (indices, each below cloud.size()) as a cloud of their own, with
/// their normals, and their covariances when with_covariances, each estimated from its
/// neighbourhood in the whole cloud: the same surfaces estimate_normals / estimate_covariances
/// give those points, without estimating the others'. Throws as estimate_covariances, and
/// InvalidInputError for an index out of range.
[[nodiscard]] PointCloud subset_with_surfaces(const PointCloud& cloud,
                                              const std::vector<std::uint32_t>& which,
                                              const NeighborhoodSettings& settings,
                                              bool with_covariances);

}  // namespace sgdicp
