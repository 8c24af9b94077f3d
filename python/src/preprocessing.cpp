// Preprocessing of sgd_icp: voxel-grid and random downsampling, normals and covariances from
// k-nearest neighbourhoods (include/sgdicp/surfaces/normals.hpp, points/); arrays in, arrays out.
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/points/random_downsample.hpp"
#include "sgdicp/points/voxel_grid.hpp"
#include "sgdicp/surfaces/normals.hpp"

namespace sgdicp::python {
namespace {

using namespace pybind11::literals;

/// The points of an array whose every row must be finite: the estimators return one row per
/// input row, so a row cannot be dropped silently.
PointCloud finite_cloud(const py::handle& points) {
  ConvertedCloud converted = cloud_from_array(points, "points", NonFinite::keep);
  const auto& p = converted.cloud.points;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!p[i].allFinite()) {
      throw InvalidInputError("points: row " + std::to_string(i) +
                              " holds a NaN or infinite coordinate (drop such rows first: "
                              "points[np.isfinite(points).all(axis=1)])");
    }
  }
  return std::move(converted.cloud);
}

NeighborhoodSettings neighborhood_from(const py::handle& k, const py::handle& num_threads) {
  NeighborhoodSettings n;
  n.k = static_cast<std::size_t>(as_count(k, "k"));
  n.num_threads = static_cast<std::size_t>(as_count(num_threads, "num_threads"));
  return n;
}

Eigen::Vector3f viewpoint_from(const py::handle& value) {
  if (value.is_none()) return Eigen::Vector3f::Zero();
  py::array_t<double> v;
  try {
    v = py::module_::import("numpy").attr("asarray")(value, "dtype"_a = "float64");
  } catch (const py::error_already_set&) {
    throw InvalidSettingsError("viewpoint must be 3 numbers (x, y, z, metres), got " +
                               type_name(value));
  }
  if (v.ndim() != 1 || v.shape(0) != 3) {
    throw InvalidSettingsError("viewpoint must be 3 numbers (x, y, z, metres)");
  }
  return Eigen::Vector3f(static_cast<float>(v.at(0)), static_cast<float>(v.at(1)),
                         static_cast<float>(v.at(2)));
}

constexpr const char* kVoxelDoc =
    R"doc(One point per occupied cubic voxel: the centroid of the points in it.

Parameters
----------
points : (N, 3) float32 or float64 array, metres
    Any memory layout; rows with a NaN or infinite coordinate are dropped first. May be empty.
voxel_size_m : float
    Side of the voxels, metres, positive. Voxel (i, j, l) holds the points with
    floor(x / voxel_size_m) = i, etc.

Returns
-------
(M, 3) float32 array, metres, M <= N: in the order of each voxel's first point in the input
(deterministic). The GIL is released while it runs.

Raises
------
InvalidSettingsError (ValueError)
    voxel_size_m not positive and finite, or so small that voxel indices overflow.
InvalidInputError (ValueError)
    Not an (N, 3) float32/float64 array.
)doc";

constexpr const char* kRandomDoc =
    R"doc(`count` distinct points chosen uniformly at random without replacement.

Parameters
----------
points : (N, 3) float32 or float64 array, metres
    Any memory layout; rows with a NaN or infinite coordinate are dropped first. May be empty.
count : int
    Points to keep, >= 0; count >= N returns all the (finite) points.
seed : int, default 2019
    Seed of the draw (std::mt19937_64): the same points, count and seed give the same result on
    any platform.

Returns
-------
(min(count, N), 3) float32 array, metres, in input order. The GIL is released while it runs.
)doc";

constexpr const char* kNormalsDoc = R"doc(Unit normals from the k nearest neighbours of every point.

The normal is the eigenvector of the smallest eigenvalue of the neighbourhood's covariance (PCA),
flipped to face `viewpoint`. Degenerate neighbourhoods (all points identical or collinear) have
no surface: their normal is (0, 0, 0). The results are the same for any thread count.

Parameters
----------
points : (N, 3) float32 or float64 array, metres
    Any memory layout; every row must be finite (one normal is returned per row).
k : int, default 20
    Neighbours per point, the point itself included, in [3, 1000].
num_threads : int, default 0
    Worker threads, 0 = all cores, at most 1024. The GIL is released while it runs.
viewpoint : (3,) array or None, default None (the origin)
    Normals are flipped to face this point (metres): n . (viewpoint - p) >= 0.

Returns
-------
(N, 3) float32 array of unit normals (or zero rows), one per input row.

Raises
------
InvalidInputError (ValueError)
    Not an (N, 3) float32/float64 array, no rows, or a non-finite row.
InvalidSettingsError (ValueError)
    k or num_threads out of range.
)doc";

constexpr const char* kCovariancesDoc =
    R"doc(Local covariances from the k nearest neighbours of every point.

Raw covariance: (1/n) sum (q - mean)(q - mean)^T over the n = min(k, N) neighbours, in m^2.
With regularize=True (the default, as GICP uses them) each is replaced by the unitless plane
model V diag(epsilon, 1, 1) V^T, V its eigenvectors (smallest first); degenerate neighbourhoods
then get the identity. The results are the same for any thread count.

Parameters
----------
points : (N, 3) float32 or float64 array, metres
    Any memory layout; every row must be finite (one covariance is returned per row).
k : int, default 20
    Neighbours per point, the point itself included, in [3, 1000].
num_threads : int, default 0
    Worker threads, 0 = all cores, at most 1024. The GIL is released while it runs.
regularize : bool, default True
    Return the GICP plane model (unitless) instead of the raw covariance (m^2).
epsilon : float, default 1e-3
    Variance along the normal in the plane model, relative to 1 in the plane, in (0, 1].

Returns
-------
(N, 3, 3) float32 array of symmetric matrices, one per input row.

Raises
------
InvalidInputError (ValueError)
    Not an (N, 3) float32/float64 array, no rows, or a non-finite row.
InvalidSettingsError (ValueError)
    k, num_threads or epsilon out of range.
)doc";

}  // namespace

void bind_preprocessing(py::module_& m) {
  m.def(
      "voxel_downsample",
      [](const py::handle& points, const py::handle& voxel_size_m) {
        const double size = as_real(voxel_size_m, "voxel_size_m");
        const ConvertedCloud cloud =
            cloud_from_array(points, "points", NonFinite::drop, /*allow_empty=*/true);
        PointCloud out = [&] {
          const py::gil_scoped_release release;
          return voxel_downsample(cloud.cloud, size);
        }();
        return array_from_cloud(std::move(out));
      },
      kVoxelDoc, "points"_a, "voxel_size_m"_a);

  m.def(
      "random_downsample",
      [](const py::handle& points, const py::handle& count, const py::handle& seed) {
        const auto n = static_cast<std::size_t>(as_count(count, "count"));
        const std::uint64_t s = as_count(seed, "seed");
        const ConvertedCloud cloud =
            cloud_from_array(points, "points", NonFinite::drop, /*allow_empty=*/true);
        PointCloud out = [&] {
          const py::gil_scoped_release release;
          return random_downsample(cloud.cloud, n, s);
        }();
        return array_from_cloud(std::move(out));
      },
      kRandomDoc, "points"_a, "count"_a, "seed"_a = SgdSettings{}.sampling.seed);

  m.def(
      "estimate_normals",
      [](const py::handle& points, const py::handle& k, const py::handle& num_threads,
         const py::handle& viewpoint) {
        NeighborhoodSettings n = neighborhood_from(k, num_threads);
        n.viewpoint = viewpoint_from(viewpoint);
        PointCloud cloud = finite_cloud(points);
        {
          const py::gil_scoped_release release;
          estimate_normals(cloud, n);
        }
        PointCloud normals;
        normals.points = std::move(cloud.normals);
        return array_from_cloud(std::move(normals));
      },
      kNormalsDoc, "points"_a, "k"_a = NeighborhoodSettings{}.k,
      "num_threads"_a = NeighborhoodSettings{}.num_threads, py::kw_only(),
      "viewpoint"_a = py::none());

  m.def(
      "estimate_covariances",
      [](const py::handle& points, const py::handle& k, const py::handle& num_threads,
         const py::handle& regularize, const py::handle& epsilon) {
        NeighborhoodSettings n = neighborhood_from(k, num_threads);
        n.regularize = as_bool(regularize, "regularize");
        n.epsilon = as_real(epsilon, "epsilon");
        PointCloud cloud = finite_cloud(points);
        {
          const py::gil_scoped_release release;
          estimate_covariances(cloud, n);
        }
        const auto rows = static_cast<py::ssize_t>(cloud.covariances.size());
        py::array_t<float> out(std::vector<py::ssize_t>{rows, 3, 3});
        auto w = out.mutable_unchecked<3>();
        for (py::ssize_t i = 0; i < rows; ++i) {
          const Eigen::Matrix3f& c = cloud.covariances[static_cast<std::size_t>(i)];
          for (py::ssize_t r = 0; r < 3; ++r) {
            for (py::ssize_t col = 0; col < 3; ++col) w(i, r, col) = c(r, col);
          }
        }
        return out;
      },
      kCovariancesDoc, "points"_a, "k"_a = NeighborhoodSettings{}.k,
      "num_threads"_a = NeighborhoodSettings{}.num_threads, py::kw_only(),
      "regularize"_a = NeighborhoodSettings{}.regularize,
      "epsilon"_a = NeighborhoodSettings{}.epsilon);
}

}  // namespace sgdicp::python
