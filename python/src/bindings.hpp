#pragma once
// Shared pieces of the Python module sgd_icp._core: conversions between NumPy arrays and the
// library's types, the typed parsing of Python values, and the settings bindings.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <Eigen/Core>

#include "sgdicp/batch_icp.hpp"
#include "sgdicp/methods.hpp"
#include "sgdicp/point_cloud.hpp"
#include "sgdicp/registration.hpp"

namespace sgdicp::python {

namespace py = pybind11;

// ---- arrays (convert.cpp)

/// What to do with rows that hold a NaN or an infinite coordinate.
enum class NonFinite { drop, keep };

struct ConvertedCloud {
  PointCloud cloud;
  std::size_t non_finite_dropped = 0;
};

/// Copies an (N, 3) float32/float64 array of any memory layout (C, Fortran, strided, negative
/// strides, unaligned) into a cloud. This copy is the one the library's float storage needs;
/// nothing else is copied. An Open3D cloud (open3d.geometry.PointCloud or
/// open3d.t.geometry.PointCloud) gives its points and, when it has them, its normals, without
/// open3d being imported here. Other non-arrays go through numpy.asarray first. `normals`, an
/// (N, 3) array or None, gives the cloud unit normals row for row (dropped with their points).
/// Throws InvalidInputError (a ValueError in Python) naming `what` for a wrong dimension, shape
/// or dtype, for zero rows unless `allow_empty`, when every row was dropped as non-finite, and
/// for normals of another count or with a non-finite value.
[[nodiscard]] ConvertedCloud cloud_from_array(const py::handle& points, std::string_view what,
                                              NonFinite non_finite, bool allow_empty = false,
                                              const py::handle& normals = py::none());

/// An (N, 3) float32 array that takes over the cloud's storage (no copy); for a georeferenced
/// cloud (origin_m not zero) a float64 array of origin + point, which float32 cannot hold.
[[nodiscard]] py::array array_from_cloud(PointCloud&& cloud);

/// A read-only (N, 3) float32 view of a cloud owned by `owner`, which the view keeps alive (a
/// georeferenced cloud: a read-only float64 copy, as array_from_cloud).
[[nodiscard]] py::array readonly_view(const PointCloud& cloud, const py::handle& owner);

/// A (4, 4) array-like as a matrix; throws InvalidInputError naming `what` for another shape or
/// a non-numeric content.
[[nodiscard]] Eigen::Matrix4d matrix_from_array(const py::handle& matrix, std::string_view what);

/// A new (4, 4) float64 array.
[[nodiscard]] py::array_t<double> array_from_matrix(const Eigen::Matrix4d& matrix);

// ---- Python values (settings.cpp)

/// The Python type name of a value, for error messages.
[[nodiscard]] std::string type_name(const py::handle& value);
/// A non-negative integer (int or NumPy integer, not bool); TypeError / ValueError otherwise.
[[nodiscard]] std::uint64_t as_count(const py::handle& value, std::string_view name);
/// A real number (int, float or NumPy scalar, not bool or str); TypeError otherwise.
[[nodiscard]] double as_real(const py::handle& value, std::string_view name);
/// True or False (or a NumPy bool); TypeError otherwise.
[[nodiscard]] bool as_bool(const py::handle& value, std::string_view name);
/// A CostType or its name ("point-to-plane" or "point_to_plane"); InvalidSettingsError for an
/// unknown name, TypeError for another type.
[[nodiscard]] CostType cost_from_object(const py::handle& value, std::string_view name);

// ---- settings (settings.cpp)

/// Binds Distance, DistanceUnit, OptimizerType, ScalingOrigin and the settings classes
/// (Settings, BatchSettings and their parts).
void bind_settings(py::module_& m);

/// `base` with the flat keyword overrides of docs/python.md applied (the names of the CLI's
/// options), then validated. Throws TypeError for an unknown keyword or a value of the wrong
/// type, and InvalidSettingsError (ValueError) for an invalid value.
[[nodiscard]] SgdSettings with_overrides(SgdSettings base, const py::dict& overrides);

/// `base` with the batch keyword overrides of docs/python.md applied (the CLI's options that apply
/// to the batch methods, plus `cost`), then validated. `method` names the batch method in error
/// messages ("" for BatchSettings(...) itself). Throws TypeError for a keyword that is unknown or
/// applies to the SGD methods only, and InvalidSettingsError for an invalid value.
[[nodiscard]] BatchSettings with_batch_overrides(BatchSettings base, const py::dict& overrides,
                                                 std::string_view method);

/// "name (default, range), ..." for every keyword of a solver, wrapped at 96 columns after
/// `indent`: the keyword lists of register()'s docstring. `core` is the module, with the settings
/// classes bound.
[[nodiscard]] std::string keyword_summary(const py::module_& core, Solver solver,
                                          std::string_view indent);

// ---- preprocessing (preprocessing.cpp)

/// Binds voxel_downsample, random_downsample, estimate_normals and estimate_covariances.
void bind_preprocessing(py::module_& m);

// ---- odometry (odometry.cpp)

/// Binds Odometry and FrameReport.
void bind_odometry(py::module_& m);

// ---- depth images (depth.cpp)

/// Binds read_depth_image and depth_to_points.
void bind_depth(py::module_& m);

// ---- the module (module.cpp)

/// Defines everything of sgd_icp._core in m.
void define_module(py::module_& m);

}  // namespace sgdicp::python
