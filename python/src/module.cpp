// The Python module sgd_icp._core: registration, reference indexes, results, file I/O, metrics
// and the library's errors as Python exceptions. The public names are re-exported by
// sgd_icp/__init__.py; sgd_icp/_core.pyi documents them for type checkers and IDEs.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "sgdicp/batch_icp.hpp"
#include "sgdicp/error.hpp"
#include "sgdicp/io.hpp"
#include "sgdicp/methods.hpp"
#include "sgdicp/metrics.hpp"
#include "sgdicp/nearest_neighbor.hpp"
#include "sgdicp/pairs.hpp"
#include "sgdicp/preprocessing.hpp"
#include "sgdicp/registration.hpp"
#include "sgdicp/transform_io.hpp"

#ifndef SGDICP_VERSION
#define SGDICP_VERSION "0.0.0"
#endif

namespace sgdicp::python {
namespace {

using namespace pybind11::literals;

// ---- exceptions: sgd_icp.Error and its subclasses, which are also ValueError / OSError

struct ExceptionTypes {
  PyObject* error = nullptr;
  PyObject* invalid_input = nullptr;
  PyObject* invalid_settings = nullptr;
  PyObject* format = nullptr;
  PyObject* io = nullptr;
};
ExceptionTypes exception_types;  // created once at import; the module holds the references

PyObject* new_exception(py::module_& m, const char* name, const char* doc, py::tuple bases) {
  const std::string qualified = std::string("sgd_icp.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), /*dict=*/nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.add_object(name, py::reinterpret_steal<py::object>(type));
  return type;
}

void bind_exceptions(py::module_& m) {
  const py::handle value_error = PyExc_ValueError;
  const py::handle os_error = PyExc_OSError;
  auto& t = exception_types;
  t.error = new_exception(m, "Error", "Base class of every error the sgd_icp library raises.",
                          py::make_tuple(py::handle(PyExc_Exception)));
  const py::handle error = t.error;
  t.invalid_input = new_exception(
      m, "InvalidInputError",
      "Input the method cannot work with: a wrong array shape or dtype, an empty or all-NaN "
      "cloud, fewer points than a mini-batch, a non-rigid initial transform. A ValueError.",
      py::make_tuple(error, value_error));
  t.invalid_settings = new_exception(
      m, "InvalidSettingsError", "A setting out of range or contradicting another. A ValueError.",
      py::make_tuple(error, value_error));
  t.format = new_exception(
      m, "FormatError",
      "A file whose content is not valid for its format; the message names the file and the "
      "line or byte where it broke. A ValueError.",
      py::make_tuple(error, value_error));
  t.io = new_exception(m, "IoError",
                       "A file that cannot be opened, read or written; the message names the "
                       "path and the system's reason. An OSError.",
                       py::make_tuple(error, os_error));

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InvalidInputError& e) {
      PyErr_SetString(exception_types.invalid_input, e.what());
    } catch (const InvalidSettingsError& e) {
      PyErr_SetString(exception_types.invalid_settings, e.what());
    } catch (const FormatError& e) {
      PyErr_SetString(exception_types.format, e.what());
    } catch (const IoError& e) {
      PyErr_SetString(exception_types.io, e.what());
    } catch (const Error& e) {
      PyErr_SetString(exception_types.error, e.what());
    }
  });
}

// ---- reference index

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
std::shared_ptr<SharedIndex> build_index(ConvertedCloud&& converted, const IndexBuilder& build) {
  const py::gil_scoped_release release;
  const auto start = std::chrono::steady_clock::now();
  ReferenceIndex index = build(std::move(converted.cloud));
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return std::make_shared<SharedIndex>(
      SharedIndex{std::move(index), converted.non_finite_dropped, ms});
}

/// The error of check_reference_prepared, in the words of the Python API.
void check_prepared(const SharedIndex& shared, CostType cost) {
  const PointCloud& cloud = shared.index.cloud();
  if ((needs_reference_normals(cost) && !cloud.has_normals()) ||
      (needs_covariances(cost) && !cloud.has_covariances())) {
    throw InvalidInputError("the " + std::string(to_string(cost)) + " cost needs reference " +
                            (needs_covariances(cost) ? "covariances" : "normals") +
                            ": build the index with ReferenceIndex(points, cost='" +
                            std::string(to_string(cost)) +
                            "'), or pass the reference points as an array");
  }
}

// ---- results as Python sees them: NumPy arrays and plain values

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

Trace make_trace(const std::vector<TraceEntry>& entries) {
  const auto k = static_cast<py::ssize_t>(entries.size());
  Trace t{py::array_t<std::int64_t>(k),
          py::array_t<std::int64_t>(k),
          py::array_t<double>(std::vector<py::ssize_t>{k, 4, 4}),
          py::array_t<double>(k),
          py::array_t<double>(k),
          py::array_t<std::int64_t>(k),
          py::array_t<double>(k)};
  auto iteration = t.iteration.mutable_unchecked<1>();
  auto points = t.points_processed.mutable_unchecked<1>();
  auto pose = t.T_reference_source.mutable_unchecked<3>();
  auto step = t.step_size.mutable_unchecked<1>();
  auto distance = t.max_distance_m.mutable_unchecked<1>();
  auto inliers = t.inliers.mutable_unchecked<1>();
  auto cost = t.cost.mutable_unchecked<1>();
  for (py::ssize_t i = 0; i < k; ++i) {
    const TraceEntry& e = entries[static_cast<std::size_t>(i)];
    iteration(i) = static_cast<std::int64_t>(e.iteration);
    points(i) = static_cast<std::int64_t>(e.points_processed);
    for (py::ssize_t r = 0; r < 4; ++r) {
      for (py::ssize_t c = 0; c < 4; ++c) pose(i, r, c) = e.T_reference_source(r, c);
    }
    step(i) = e.step_size;
    distance(i) = e.max_distance_m;
    inliers(i) = static_cast<std::int64_t>(e.inliers);
    cost(i) = e.cost;
  }
  return t;
}

// A (rows, 6) array of `rows` values of `at(i, k)`.
template <typename F>
py::array_t<double> pose_rows(py::ssize_t rows, F&& at) {
  py::array_t<double> out(std::vector<py::ssize_t>{rows, 6});
  auto a = out.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < rows; ++i) {
    for (py::ssize_t k = 0; k < 6; ++k) a(i, k) = at(i, k);
  }
  return out;
}

py::array_t<double> pose_vector_array(const Eigen::Matrix<double, 6, 1>& v) {
  py::array_t<double> out(6);
  for (py::ssize_t k = 0; k < 6; ++k) out.mutable_at(k) = v[k];
  return out;
}

Result make_result(RegistrationResult r) {
  Result out;
  out.T_reference_source = array_from_matrix(r.T_reference_source);
  out.trace = make_trace(r.trace);
  r.trace.clear();
  out.covariance = pose_rows(6, [&](auto i, auto k) { return r.covariance(i, k); });
  out.covariance_se3 = pose_rows(6, [&](auto i, auto k) { return r.covariance_se3(i, k); });
  out.samples = pose_rows(static_cast<py::ssize_t>(r.samples.size()), [&](auto i, auto k) {
    return r.samples[static_cast<std::size_t>(i)][k];
  });
  out.sample_mean = pose_vector_array(r.sample_mean);
  for (const PoseMode& m : r.modes) {
    out.modes.append(Mode{m.weight, pose_vector_array(m.mean),
                          pose_rows(6, [&](auto i, auto k) { return m.covariance(i, k); })});
  }
  r.samples.clear();
  out.fields = std::move(r);
  return out;
}

// ---- register

/// A --method of the CLI (methods.hpp), by name.
const Method& method_from_object(const py::handle& value) {
  if (!py::isinstance<py::str>(value)) {
    throw py::type_error("method must be a str (" + method_list() + "), got " + type_name(value));
  }
  return method_from_string(value.cast<std::string>());
}

/// A copy of `settings` (a Settings), or the defaults for None.
SgdSettings settings_or_default(const py::handle& settings, const Method& method) {
  if (settings.is_none()) return SgdSettings{};
  if (!py::isinstance<SgdSettings>(settings)) {
    throw py::type_error("settings must be a sgd_icp.Settings or None, got " + type_name(settings) +
                         (py::isinstance<BatchSettings>(settings)
                              ? " (a BatchSettings is for method='icp', 'icp-plane' or 'gicp'; "
                                "method='" +
                                    std::string(method.name) + "' takes a Settings)"
                              : std::string()));
  }
  return settings.cast<SgdSettings>();
}

/// A copy of `settings` (a BatchSettings), or the defaults for None.
BatchSettings batch_settings_or_default(const py::handle& settings, const Method& method) {
  if (settings.is_none()) return BatchSettings{};
  if (!py::isinstance<BatchSettings>(settings)) {
    throw py::type_error("settings must be a sgd_icp.BatchSettings or None for the batch method '" +
                         std::string(method.name) + "', got " + type_name(settings));
  }
  return settings.cast<BatchSettings>();
}

/// The reference index of a registration, as its settings say: reference_index_for (the
/// library's one rule: voxel grid, threads, and the normals or covariances a batch cost needs in
/// the index), and the cost a given index must be prepared for (batch methods; the SGD methods
/// estimate what they lack during the run: none).
struct ReferenceNeeds {
  std::optional<CostType> cost;
  IndexBuilder build;
};

template <typename Settings>
ReferenceNeeds needs_of(const Settings& s, bool cost_in_index) {
  return {cost_in_index ? std::optional<CostType>(s.cost) : std::nullopt,
          [s](PointCloud cloud) { return reference_index_for(std::move(cloud), s); }};
}

/// Registration with either solver: the index (given, or built as `needs` says), then
/// `run(index)` with the GIL released.
template <typename Run>
Result register_with(const ConvertedCloud& src, const py::handle& reference,
                     const ReferenceNeeds& needs, Run run) {
  std::shared_ptr<const SharedIndex> index;
  double build_ms = 0.0;
  if (py::isinstance<SharedIndex>(reference)) {
    index = reference.cast<std::shared_ptr<SharedIndex>>();  // keeps it alive during the run
    if (needs.cost) check_prepared(*index, *needs.cost);
  } else {
    auto built =
        build_index(cloud_from_array(reference, "reference", NonFinite::drop), needs.build);
    build_ms = built->build_ms;
    index = std::move(built);
  }

  const RegistrationResult r = [&] {
    const py::gil_scoped_release release;
    return run(index->index);
  }();
  Result out = make_result(r);
  out.build_ms = build_ms;
  out.source_non_finite_dropped = src.non_finite_dropped;
  out.reference_non_finite_dropped = index->non_finite_dropped;
  return out;
}

/// The settings of a method with the user's settings object and keyword overrides.
SgdSettings sgd_settings_of(const Method& m, const py::handle& settings,
                            const py::kwargs& overrides) {
  SgdSettings base = settings_or_default(settings, m);
  BatchSettings unused;
  apply_method_cost(m, base, unused);
  return with_overrides(base, overrides);
}
BatchSettings batch_settings_of(const Method& m, const py::handle& settings,
                                const py::kwargs& overrides) {
  BatchSettings base = batch_settings_or_default(settings, m);
  base.cost = *m.cost;
  return with_batch_overrides(base, overrides, std::string(m.name));
}

Result register_clouds(const py::handle& source, const py::handle& reference,
                       const py::handle& init, const py::handle& settings, const py::handle& method,
                       const py::kwargs& overrides) {
  const Method& m = method_from_object(method);
  if (m.cost && overrides.contains("cost")) {
    throw InvalidSettingsError("method='" + std::string(m.name) +
                               "' sets the cost; drop cost= (or use method='sgd' with cost=)");
  }
  const auto T_init = [&] {
    return init.is_none() ? Eigen::Matrix4d::Identity().eval() : matrix_from_array(init, "init");
  };
  if (m.solver == Solver::sgd) {
    const SgdSettings s = sgd_settings_of(m, settings, overrides);
    const Eigen::Matrix4d T = T_init();
    const ConvertedCloud src = cloud_from_array(source, "source", NonFinite::drop);
    return register_with(src, reference, needs_of(s, false), [&](const ReferenceIndex& index) {
      return align(src.cloud, index, s, T);
    });
  }
  const BatchSettings b = batch_settings_of(m, settings, overrides);
  const Eigen::Matrix4d T = T_init();
  const ConvertedCloud src = cloud_from_array(source, "source", NonFinite::drop);
  return register_with(src, reference, needs_of(b, true), [&](const ReferenceIndex& index) {
    return align_batch(src.cloud, index, b, T);
  });
}

/// What the reference index that register_clouds builds for an array reference holds, for the
/// same method, settings and overrides.
ReferenceNeeds reference_needs(const Method& m, const py::handle& settings,
                               const py::kwargs& overrides) {
  if (m.solver == Solver::sgd) return needs_of(sgd_settings_of(m, settings, overrides), false);
  return needs_of(batch_settings_of(m, settings, overrides), true);
}

// ---- file I/O

FileFormat format_from_object(const py::handle& value) {
  if (!py::isinstance<py::str>(value)) {
    throw py::type_error("format must be a str, got " + type_name(value));
  }
  const std::string name = value.cast<std::string>();
  if (const FileFormat* format = find_enum<FileFormat>(name)) return *format;
  throw FormatError("unknown format '" + name + "' (expected " + name_list<FileFormat>() + ")");
}

Encoding encoding_from_object(const py::handle& value) {
  const std::string name = py::isinstance<py::str>(value) ? value.cast<std::string>() : "";
  if (const Encoding* encoding = find_enum<Encoding>(name)) return *encoding;
  throw py::value_error("encoding must be " + name_list<Encoding>() + ", got " +
                        std::string(py::repr(value)));
}

struct ReadPoints {
  py::array points;  // float32, or float64 for a georeferenced cloud
  std::size_t points_in_file = 0;
  std::size_t non_finite_dropped = 0;
  std::string format;
};

ReadPoints read_points_with_info(const std::filesystem::path& path, const py::handle& format) {
  const FileFormat f = format_from_object(format);
  ReadResult read = [&] {
    const py::gil_scoped_release release;
    return read_point_cloud(path, f);
  }();
  return ReadPoints{array_from_cloud(std::move(read.cloud)), read.points_in_file,
                    read.non_finite_dropped, to_string(read.format)};
}

// ---- docstrings

constexpr const char* kRegisterDocTemplate =
    R"doc(Registers `source` to `reference` with SGD-ICP, or with a batch ICP method.

Returns a RegistrationResult whose T_reference_source (4x4, float64, metres) maps source points
into the reference frame: p_ref = R @ p_src + t.

Parameters
----------
source : (N, 3) float32 or float64 array, metres
    The cloud that moves. Any memory layout (C, Fortran, strided slices). It is copied once into
    the library's float32 storage (float64 georeferenced coordinates, e.g. UTM, are stored from an
    origin near the cloud, exactly: docs/io.md); rows with a NaN or infinite coordinate are dropped
    and counted (result.source_non_finite_dropped).
reference : (M, 3) array like `source`, or ReferenceIndex
    The fixed cloud. A ReferenceIndex is built once and reused by any number of registrations,
    also from several threads at once; an array builds one for this call (result.build_ms),
    with the normals or covariances the cost needs.
init : (4, 4) array or None, default None (identity)
    Initial T_reference_source; must be rigid.
settings : Settings, BatchSettings or None, default None
    The base settings: a Settings for the SGD methods (None = Settings()), a BatchSettings for
    the batch methods (None = BatchSettings(), whose cost the method sets).
method : str, default 'sgd'
    The CLI's --method: 'sgd' (SGD-ICP with the settings' cost, point-to-plane by default,
    point-to-point with Settings.paper()), 'sgd-point' / 'sgd-plane' / 'sgd-gicp' (SGD-ICP on
    point-to-point / point-to-plane / plane-to-plane), 'icp' (batch
    point-to-point, closed-form SVD step), 'icp-plane' (batch point-to-plane) or 'gicp' (batch
    plane-to-plane), both Levenberg-Marquardt. All but 'sgd' set the cost (cost= is then an
    error). An unknown name raises InvalidSettingsError.
**overrides
    Flat keyword settings applied on top of `settings`, named like the CLI's options (the
    library's settings table), each with its default and valid range. A distance given as a number
    is in max_distance_unit ('scaled', the default, or 'm'); a Distance keeps its own unit.
    optimizer= also sets learning_rate to that rule's own step unless learning_rate= is given.
    For the batch methods (any other keyword raises TypeError):
@BATCH@.
    For the SGD methods:
@SGD@.
    See docs/python.md for the settings each one sets.

The GIL is released during the registration (and the KD-tree build), so registrations in
several Python threads run in parallel.

Raises
------
InvalidInputError (ValueError)
    A wrong shape or dtype, no finite points, fewer source points than batch_size, a non-rigid
    init, a ReferenceIndex without the normals or covariances of a batch method's cost (build
    it with ReferenceIndex(points, cost=...); the SGD methods estimate what they use).
InvalidSettingsError (ValueError)
    An invalid setting or method name.
TypeError
    An unknown keyword, a keyword of the other solver, or a value of the wrong type.
)doc";

// kRegisterDocTemplate with the keyword lists of both solvers filled in.
std::string register_doc(const py::module_& m) {
  std::string doc = kRegisterDocTemplate;
  const auto fill = [&](const std::string& marker, const std::string& text) {
    doc.replace(doc.find(marker), marker.size(), text);
  };
  fill("@BATCH@", keyword_summary(m, Solver::batch, "    "));
  fill("@SGD@", keyword_summary(m, Solver::sgd, "    "));
  return doc;
}

void bind_reference_index(py::module_& m) {
  py::class_<SharedIndex, std::shared_ptr<SharedIndex>>(
      m, "ReferenceIndex",
      "A KD-tree over a reference cloud, built once and reused by any number of registrations, "
      "also from several threads at once (queries are read-only).")
      .def(py::init([](const py::handle& points, const py::handle& normals,
                       const py::handle& leaf_size, const py::handle& cost,
                       const py::handle& neighborhood, const py::handle& threads) {
             const CostType c = cost_from_object(cost, "cost");
             const NeighborhoodSettings n = neighborhood.is_none()
                                                ? NeighborhoodSettings{}
                                                : py::cast<NeighborhoodSettings>(neighborhood);
             auto converted =
                 cloud_from_array(points, "reference", NonFinite::drop, false, normals);
             const KdTreeSettings tree{as_count(leaf_size, "leaf_size"),
                                       as_count(threads, "threads")};
             return build_index(std::move(converted), [&](PointCloud cloud) {
               ReferenceIndex index(std::move(cloud), tree);
               prepare_reference(index, c, n);
               return index;
             });
           }),
           "points"_a, py::kw_only(), "normals"_a = py::none(),
           "leaf_size"_a = KdTreeSettings{}.leaf_size, "cost"_a = "point-to-point",
           "neighborhood"_a = py::none(), "threads"_a = KdTreeSettings{}.num_threads,
           "Builds the tree over an (N, 3) float32/float64 array of points in metres (copied "
           "once into float32 storage; rows with a NaN or infinite coordinate are dropped and "
           "counted in non_finite_dropped), or over an Open3D PointCloud (legacy or tensor; its "
           "normals too when it has them). normals: (N, 3) unit normals, one per row of points, "
           "default None; the point-to-plane cost uses them instead of estimating its own. "
           "leaf_size: points per KD-tree leaf, default 24. threads: threads of the build, "
           "default 1, 0 = every core (the same tree for any count). "
           "cost: the cost the index will serve, default 'point-to-point'; 'point-to-plane' "
           "estimates the reference normals (unless given), 'plane-to-plane' the covariances, with "
           "`neighborhood` (NeighborhoodSettings, default None = NeighborhoodSettings(): plain "
           "k-nearest "
           "neighbourhoods, as the batch methods' defaults; pass Settings().neighborhood to give "
           "the SGD methods the normals they would estimate themselves). The GIL "
           "is released during the build. The index never changes afterwards: the SGD methods "
           "estimate the normals or covariances they use during the run; a batch method whose "
           "cost needs them raises InvalidInputError when the index lacks them.")
      .def_static(
          "for_registration",
          [](const py::handle& points, const py::handle& method, const py::handle& settings,
             const py::kwargs& overrides) {
            const ReferenceNeeds needs =
                reference_needs(method_from_object(method), settings, overrides);
            return build_index(cloud_from_array(points, "reference", NonFinite::drop), needs.build);
          },
          "points"_a, py::kw_only(), "method"_a = "sgd", "settings"_a = py::none(),
          "The index that register(source, points, method=method, settings=settings, "
          "**overrides) builds for its reference (for a batch method the cost's normals or "
          "covariances with the settings' neighbourhood), for reuse over many sources with the "
          "same arguments: the results are the same as passing points each time. points: an "
          "array or an Open3D PointCloud, as for register(). Raises the errors of register() for "
          "the method, settings and keywords.")
      .def("__len__", [](const SharedIndex& s) { return s.index.size(); })
      .def_property_readonly(
          "points",
          [](const py::object& self) {
            return readonly_view(self.cast<const SharedIndex&>().index.cloud(), self);
          },
          "The indexed points: a read-only (N, 3) float32 view (no copy); a float64 copy for "
          "georeferenced points.")
      .def_property_readonly(
          "voxel_size_m", [](const SharedIndex& s) { return s.index.voxel_size_m(); },
          "The voxel grid the points were thinned with before indexing, metres (0 = indexed as "
          "given); registrations against the index thin their source on the same grid.")
      .def_property_readonly(
          "non_finite_dropped", [](const SharedIndex& s) { return s.non_finite_dropped; },
          "Rows of the input dropped for a NaN or infinite coordinate.")
      .def_property_readonly(
          "build_ms", [](const SharedIndex& s) { return s.build_ms; },
          "Wall time of the KD-tree build (and of the normals or covariances), milliseconds.")
      .def_property_readonly(
          "has_normals", [](const SharedIndex& s) { return s.index.cloud().has_normals(); },
          "Whether the reference has normals (built with cost='point-to-plane' or "
          "'plane-to-plane').")
      .def_property_readonly(
          "has_covariances", [](const SharedIndex& s) { return s.index.cloud().has_covariances(); },
          "Whether the reference has covariances (built with cost='plane-to-plane').")
      .def_property_readonly(
          "bounding_box",
          [](const SharedIndex& s) {
            const BoundingBox& box = s.index.bounding_box();
            py::array_t<double> lower(3);
            py::array_t<double> upper(3);
            for (py::ssize_t i = 0; i < 3; ++i) {
              lower.mutable_at(i) = box.min[i];
              upper.mutable_at(i) = box.max[i];
            }
            return py::make_tuple(lower, upper);
          },
          "(min, max) corners of the axis-aligned bounding box, two (3,) float64 arrays, "
          "metres.")
      .def("__repr__", [](const SharedIndex& s) {
        return "<sgd_icp.ReferenceIndex of " + std::to_string(s.index.size()) + " points (" +
               std::to_string(s.non_finite_dropped) + " non-finite rows dropped)>";
      });
}

void bind_results(py::module_& m) {
  py::class_<Trace>(m, "Trace",
                    "Per-iteration record of a registration (Settings.record_trace), one array "
                    "element per iteration.")
      .def_readonly("iteration", &Trace::iteration, "(K,) int64, iteration number.")
      .def_readonly("points_processed", &Trace::points_processed,
                    "(K,) int64, source points drawn so far.")
      .def_readonly("T_reference_source", &Trace::T_reference_source,
                    "(K, 4, 4) float64, metric pose after each iteration.")
      .def_readonly("step_size", &Trace::step_size,
                    "(K,) float64, effective learning rate of each iteration.")
      .def_readonly("max_distance_m", &Trace::max_distance_m, "(K,) float64, d_max used, metres.")
      .def_readonly("inliers", &Trace::inliers, "(K,) int64, pairs kept in each mini-batch.")
      .def_readonly("cost", &Trace::cost, "(K,) float64, mini-batch cost F, scaled units^2.")
      .def("__len__", [](const Trace& t) { return t.iteration.size(); })
      .def("__repr__", [](const Trace& t) {
        return "<sgd_icp.Trace of " + std::to_string(t.iteration.size()) + " iterations>";
      });

  py::class_<Mode>(m, "PoseMode",
                   "One mode of the svgd particles (RegistrationResult.modes; "
                   "docs/uncertainty.md).")
      .def_readonly("weight", &Mode::weight, "Fraction of the particles in this mode.")
      .def_readonly("mean", &Mode::mean,
                    "(6,) float64: mean theta = (x, y, z, roll, pitch, yaw), metres and radians.")
      .def_readonly("covariance", &Mode::covariance,
                    "(6, 6) float64: covariance of theta in this mode, metres and radians.")
      .def("__repr__", [](const Mode& mode) {
        return std::string(py::str("<sgd_icp.PoseMode weight {:.3g}>").format(mode.weight));
      });

  py::class_<Result> result(
      m, "RegistrationResult",
      "What register() returns: the transform, why it stopped, the work done and "
      "the final inlier statistics (every field of the C++ RegistrationResult, "
      "plus the non-finite rows dropped and the KD-tree build time).");
  result
      .def_readonly("T_reference_source", &Result::T_reference_source,
                    "(4, 4) float64, metres: maps source points into the reference frame, p_ref "
                    "= R @ p_src + t.")
      .def_readonly("build_ms", &Result::build_ms,
                    "Wall time of the KD-tree build (and reference normals/covariances) for an "
                    "array reference, milliseconds (0 for a ReferenceIndex).")
      .def_readonly("source_non_finite_dropped", &Result::source_non_finite_dropped,
                    "Source rows dropped for a NaN or infinite coordinate.")
      .def_readonly("reference_non_finite_dropped", &Result::reference_non_finite_dropped,
                    "Reference rows dropped for a NaN or infinite coordinate.")
      .def_readonly("trace", &Result::trace, "Per-iteration Trace; empty unless record_trace=True.")
      .def_readonly("covariance", &Result::covariance,
                    "(6, 6) float64: covariance of theta = (x, y, z, roll, pitch, yaw) of "
                    "T_reference_source (R = Rz(yaw) Ry(pitch) Rx(roll)), metres and radians; "
                    "zeros unless uncertainty='laplace', 'sgld' or 'svgd' (svgd: the heaviest "
                    "mode's; docs/uncertainty.md).")
      .def_readonly("covariance_se3", &Result::covariance_se3,
                    "(6, 6) float64: the same in the tangent space of SE(3), xi = (rho, phi) "
                    "translation first, right perturbation T = T_reference_source @ Exp(xi).")
      .def_readonly("samples", &Result::samples,
                    "(K, 6) float64: the SGLD samples (sgld) or the particles (svgd) of theta (as "
                    "covariance); (0, 6) otherwise.")
      .def_readonly("sample_mean", &Result::sample_mean,
                    "(6,) float64: the mean of the samples (zeros without samples).")
      .def_readonly("modes", &Result::modes,
                    "uncertainty='svgd': the modes of the particles (PoseMode), heaviest first "
                    "(covariance is the first's); empty otherwise.")
      .def("__repr__", [](const Result& r) {
        return std::string(py::str("<sgd_icp.RegistrationResult {}: {} iterations, {} points "
                                   "processed, inlier RMSE {:.4g} m ({:.1%} inliers), {:.1f} ms>")
                               .format(to_string(r.fields.stop_reason), r.fields.iterations,
                                       r.fields.points_processed, r.fields.inlier_rmse_m,
                                       r.fields.inlier_ratio, r.fields.time_ms));
      });
  // The fields of the C++ result, from its one list (result.hpp).
  for_each_result_field([&](const char* name, auto member, const char* doc) {
    result.def_property_readonly(
        name,
        [member](const Result& r) {
          if constexpr (std::is_same_v<std::remove_cvref_t<decltype(r.fields.*member)>,
                                       StopReason>) {
            return std::string(to_string(r.fields.*member));
          } else {
            return r.fields.*member;
          }
        },
        doc);
  });
}

void bind_register_and_io(py::module_& m) {
  // The keyword lists come from the settings table; the docstring must outlive the module.
  static const std::string doc = register_doc(m);
  m.def("register", &register_clouds, doc.c_str(), "source"_a, "reference"_a, "init"_a = py::none(),
        "settings"_a = py::none(), "method"_a = "sgd");

  py::class_<ReadPoints>(m, "ReadResult", "A point cloud read from a file, with its counts.")
      .def_readonly("points", &ReadPoints::points,
                    "(N, 3) float32 array of the finite points, in file order, metres (float64 for "
                    "georeferenced coordinates, which float32 cannot hold: docs/io.md).")
      .def_readonly("points_in_file", &ReadPoints::points_in_file,
                    "Points the file declares or contains (= N + non_finite_dropped).")
      .def_readonly("non_finite_dropped", &ReadPoints::non_finite_dropped,
                    "Points dropped for a NaN or infinite coordinate.")
      .def_readonly("format", &ReadPoints::format,
                    "The format read: 'pcd', 'ply', 'kitti_bin', 'xyz', 'vtk' or 'f32'.")
      .def("__repr__", [](const ReadPoints& r) {
        return "<sgd_icp.ReadResult " + r.format + ": " + std::to_string(r.points.shape(0)) +
               " points (" + std::to_string(r.non_finite_dropped) + " of " +
               std::to_string(r.points_in_file) + " dropped as non-finite)>";
      });

  m.def("read_point_cloud", &read_points_with_info, "path"_a, "format"_a = "auto",
        "Reads the x y z of every point of a file (PCD, PLY, KITTI .bin, .xyz/.txt/.csv, ASCII "
        "VTK, .f32; docs/io.md) into a ReadResult. format: 'auto' (from the extension, the "
        "default), 'pcd', 'ply', 'kitti_bin', 'xyz', 'vtk' or 'f32'. Points with a NaN or "
        "infinite coordinate are dropped and counted. Raises IoError (OSError) or FormatError "
        "(ValueError).");
  m.def(
      "read_points",
      [](const std::filesystem::path& path, const py::handle& format) {
        return read_points_with_info(path, format).points;
      },
      "path"_a, "format"_a = "auto",
      "Reads a point-cloud file into an (N, 3) float32 array (metres) of its finite points "
      "(float64 for georeferenced coordinates, docs/io.md); see read_point_cloud for the "
      "formats, the counts and the errors.");
  m.def(
      "read_transform",
      [](const std::filesystem::path& path) { return array_from_matrix(read_transform(path)); },
      "path"_a,
      "Reads a transform file as the CLI's --init does (12 numbers, a 3x4 [R | t], or 16, a "
      "4x4, row-major; '#' comment lines; projected onto the nearest rotation) into a (4, 4) "
      "float64 array. Raises IoError (OSError) or FormatError "
      "(ValueError).");
  m.def(
      "read_pairs",
      [](const std::filesystem::path& path) {
        py::list pairs;
        for (const RegistrationPair& p : read_pairs_file(path)) {
          pairs.append(py::make_tuple(p.source.string(), p.reference.string(),
                                      array_from_matrix(p.T_reference_source_gt), p.line));
        }
        return pairs;
      },
      "path"_a,
      "Reads a pairs file (one SOURCE REFERENCE and ground-truth T_reference_source per line, "
      "the format of `sgdicp bench`: shared/data/PAIRS.md) into a list of (source, reference, "
      "T_gt, line) tuples: the paths resolved against the file's folder, T_gt a (4, 4) float64 "
      "array, line the line number in the file. Raises IoError (OSError) or FormatError "
      "(ValueError) naming the file and line.");
  m.def(
      "write_points",
      [](const std::filesystem::path& path, const py::handle& points, const py::handle& format,
         const py::handle& encoding) {
        const FileFormat f = format_from_object(format);
        const Encoding e = encoding_from_object(encoding);
        const ConvertedCloud cloud =
            cloud_from_array(points, "points", NonFinite::keep, /*allow_empty=*/true);
        const py::gil_scoped_release release;
        write_point_cloud(path, cloud.cloud, f, e);
      },
      "path"_a, "points"_a, "format"_a = "auto", "encoding"_a = "binary",
      "Writes an (N, 3) float32/float64 array as PLY, PCD or XYZ (float32 values; "
      "georeferenced float64 coordinates as float64), chosen from the extension unless format "
      "('ply', 'pcd', 'xyz') is given. encoding: 'binary' (default) or 'ascii' (XYZ is always "
      "text). Reading the file back gives the same values. Raises IoError (OSError) or FormatError "
      "(ValueError).");
}

void bind_metrics(py::module_& m) {
  m.def(
      "translation_error",
      [](const py::handle& T_est, const py::handle& T_gt) {
        return translation_error(matrix_from_array(T_est, "T_est"),
                                 matrix_from_array(T_gt, "T_gt"));
      },
      "T_est"_a, "T_gt"_a, "|t_est - t_gt| of two (4, 4) transforms, in their unit (metres).");
  m.def(
      "rotation_error_geodesic",
      [](const py::handle& T_est, const py::handle& T_gt) {
        return rotation_error_geodesic(matrix_from_array(T_est, "T_est"),
                                       matrix_from_array(T_gt, "T_gt"));
      },
      "T_est"_a, "T_gt"_a,
      "Angle of the relative rotation R_est^T R_gt of two (4, 4) transforms, radians in [0, "
      "pi].");
  m.def(
      "rotation_error_euler_sum",
      [](const py::handle& T_est, const py::handle& T_gt) {
        return rotation_error_euler_sum(matrix_from_array(T_est, "T_est"),
                                        matrix_from_array(T_gt, "T_gt"));
      },
      "T_est"_a, "T_gt"_a,
      "The paper's rotation error: |d roll| + |d pitch| + |d yaw| of two (4, 4) transforms, "
      "each wrapped to (-pi, pi], radians.");
}

}  // namespace

void define_module(py::module_& m) {
  m.doc() = "SGD-ICP point-cloud registration (C++ core of the sgd_icp package).";
  m.attr("__version__") = SGDICP_VERSION;

  bind_exceptions(m);
  bind_settings(m);
  bind_preprocessing(m);
  bind_reference_index(m);
  bind_results(m);
  bind_register_and_io(m);
  bind_depth(m);
  bind_metrics(m);
  bind_odometry(m);
}

}  // namespace sgdicp::python

PYBIND11_MODULE(_core, m) {
  sgdicp::python::define_module(m);
}
