#pragma once
// Shared pieces of the Python module sgd_icp._core: conversions between NumPy arrays and the
// library's types, the typed parsing of Python values, the types that several parts of the module
// use (the shared reference index, the result as Python sees it), and each part's bind function.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/result.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/registration/batch_icp.hpp"
#include "sgdicp/registration/methods.hpp"
#include "sgdicp/registration/registration.hpp"

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

/// Per-point times given as an array: the times relative to the earliest (computed in double,
/// so that absolute clocks keep their microseconds in float), and the earliest.
struct TimesArray {
  std::vector<float> relative_s;
  double earliest_s = 0.0;
};

/// An (N,) array of times, seconds, one per point of a cloud of `count` points. Throws
/// InvalidInputError for another shape or count, or a time that is not finite (or whose distance
/// from the earliest float cannot hold).
[[nodiscard]] TimesArray times_from_array(const py::handle& times, std::size_t count);

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

// ---- Python values (keywords.cpp)

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
/// A bound enum E (OptimizerType, ScalingOrigin, CostType, KernelType, UncertaintyType or
/// Distance::Unit) or one of its names; InvalidSettingsError for an unknown name, TypeError for
/// another type.
template <typename E>
[[nodiscard]] E enum_from_object(const py::handle& value, std::string_view name);
/// A Distance; TypeError for anything else.
[[nodiscard]] Distance distance_from_object(const py::handle& value, std::string_view name);
/// The keyword of a setting of the settings table: its name with '_' for '-' (the CLI's option).
[[nodiscard]] std::string keyword_of(std::string_view name);

// ---- settings (settings.cpp: the classes; keywords.cpp: the keyword overrides;
// settings_docs.cpp: the docstrings from the settings table, and its keywords for the stub)

/// Binds Distance, DistanceUnit, OptimizerType, ScalingOrigin and the settings classes
/// (Settings, BatchSettings and their parts), then documents them (document_settings).
void bind_settings(py::module_& m);

/// Gives every attribute that the library's settings tables describe its docstring from its table
/// entry (help, unit, range, keyword, default); the classes bind those with an empty docstring.
void document_settings(py::module_& m);

/// Binds _settings_keywords(solver): the keywords of the settings tables with their kinds, from
/// which python/tools/stub_signatures.py writes the keyword parameters of the type stub.
void bind_settings_keywords(py::module_& m);

/// A value as Python writes it, for repr and "Default X." (which the package tests evaluate):
/// enums as Class.member, arrays as tuples.
[[nodiscard]] std::string python_literal(const py::object& value);

/// `base` with the flat keyword overrides of docs/python.md applied (the names of the CLI's
/// options), then validated. Throws TypeError for an unknown keyword or a value of the wrong
/// type, and InvalidSettingsError (ValueError) for an invalid value.
[[nodiscard]] SgdSettings with_overrides(SgdSettings base, const py::dict& overrides);
/// A copy of the `settings` argument (a Settings) for an SGD `method`, or the defaults for None;
/// TypeError for anything else.
[[nodiscard]] SgdSettings settings_or_default(const py::handle& settings, const Method& method);
/// The same, a BatchSettings, for a batch `method`.
[[nodiscard]] BatchSettings batch_settings_or_default(const py::handle& settings,
                                                      const Method& method);

/// `base` with the batch keyword overrides of docs/python.md applied (the CLI's options that apply
/// to the batch methods, plus `cost`), then validated. `method` names the batch method in error
/// messages ("" for BatchSettings(...) itself). Throws TypeError for a keyword that is unknown or
/// applies to the SGD methods only, and InvalidSettingsError for an invalid value.
[[nodiscard]] BatchSettings with_batch_overrides(BatchSettings base, const py::dict& overrides,
                                                 std::string_view method);

/// `base` with the keywords of `overrides` that name a setting of `table` (the odometry's, the
/// global registration's: no distances) set in table order and removed from `overrides`, then
/// validated; the other keywords stay for the registration's settings. Throws TypeError for a
/// value of the wrong type and InvalidSettingsError (ValueError) for an invalid one, naming the
/// keyword.
template <typename S>
[[nodiscard]] S take_keywords(S base, py::dict& overrides, const std::vector<Setting<S>>& table);

/// "name (default, range), ..." for every keyword of a solver, wrapped at 96 columns after
/// `indent`: the keyword lists of register()'s docstring. `core` is the module, with the settings
/// classes bound.
[[nodiscard]] std::string keyword_summary(const py::module_& core, Solver solver,
                                          std::string_view indent);
/// The same for the keywords of register(init='global') (global_settings_table), their defaults
/// read from GlobalSettings{}.
[[nodiscard]] std::string global_keyword_summary(std::string_view indent);

// ---- reference indexes (reference_index.cpp)

/// A ReferenceIndex shared by the Python object and every registration that uses it, so
/// it outlives a `del` of the Python object while a registration runs in another thread. It is
/// never changed after construction (reference normals and covariances are estimated there), so
/// any number of threads can use it at once.
struct SharedIndex {
  ReferenceIndex index;
  std::size_t non_finite_dropped = 0;
  double build_ms = 0.0;
};

/// How a reference index is built from its cloud (with the GIL released by build_index).
using IndexBuilder = std::function<ReferenceIndex(PointCloud)>;

/// Builds the index with `build`, with the GIL released, and times it.
[[nodiscard]] std::shared_ptr<SharedIndex> build_index(ConvertedCloud&& converted,
                                                       const IndexBuilder& build);

/// The error of check_reference_prepared, in the words of the Python API.
void check_prepared(const SharedIndex& shared, CostType cost);

/// Binds ReferenceIndex.
void bind_reference_index(py::module_& m);

// ---- results as Python sees them: NumPy arrays and plain values (results.cpp)

struct Trace {
  py::array_t<std::int64_t> iteration;
  py::array_t<std::int64_t> points_processed;
  py::array_t<double> T_reference_source;
  py::array_t<double> step_size;
  py::array_t<double> max_distance_m;
  py::array_t<std::int64_t> inliers;
  py::array_t<double> cost;
};

/// One mode of the svgd particles (PoseMode), its arrays as numpy.
struct Mode {
  double weight = 0.0;
  py::array_t<double> mean;        // (6,)
  py::array_t<double> covariance;  // (6, 6)
};

struct Result {
  RegistrationResult fields;  ///< the C++ result (its trace moved into `trace`)
  py::array_t<double> T_reference_source;
  double build_ms = 0.0;
  std::size_t source_non_finite_dropped = 0;
  std::size_t reference_non_finite_dropped = 0;
  Trace trace;
  py::array_t<double> covariance;      // (6, 6)
  py::array_t<double> covariance_se3;  // (6, 6)
  py::array_t<double> samples;         // (K, 6)
  py::array_t<double> sample_mean;     // (6,)
  py::list modes;                      // of Mode
};

/// The Python result of a C++ result (its trace and samples moved into arrays).
[[nodiscard]] Result make_result(RegistrationResult r);

/// Binds Trace, PoseMode and RegistrationResult.
void bind_results(py::module_& m);

// ---- registration (registration.cpp)

/// A --method of the CLI (methods.hpp), by name.
[[nodiscard]] const Method& method_from_object(const py::handle& value);

/// The reference index of a registration, as its settings say: reference_index_for (the
/// library's one rule: voxel grid, threads, and the normals or covariances a batch cost needs in
/// the index), and the cost a given index must be prepared for (batch methods; the SGD methods
/// estimate what they lack during the run: none).
struct ReferenceNeeds {
  std::optional<CostType> cost;
  IndexBuilder build;
};

/// What the reference index that register() builds for an array reference holds, for the same
/// method, settings and overrides.
[[nodiscard]] ReferenceNeeds reference_needs(const Method& m, const py::handle& settings,
                                             const py::dict& overrides);

/// Binds register (its docstring lists the keywords of the settings table: after bind_settings).
void bind_registration(py::module_& m);

// ---- file I/O (io.cpp)

/// Binds ReadResult, read_point_cloud, read_points, read_transform, read_pairs and write_points.
void bind_io(py::module_& m);

// ---- metrics (metrics.cpp)

/// Binds translation_error, rotation_error_geodesic and rotation_error_euler_sum.
void bind_metrics(py::module_& m);

// ---- normals, covariances and downsampling (preprocessing.cpp)

/// Binds voxel_downsample, random_downsample, estimate_normals and estimate_covariances.
void bind_preprocessing(py::module_& m);

// ---- odometry (odometry.cpp)

/// Binds Odometry and FrameReport.
void bind_odometry(py::module_& m);

// ---- depth images (depth.cpp)

/// Binds read_depth_image and depth_to_points.
void bind_depth(py::module_& m);

// ---- the module (module.cpp)

/// Defines everything of sgd_icp._core in m: the exceptions, then each part above.
void define_module(py::module_& m);

}  // namespace sgdicp::python
