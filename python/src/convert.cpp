// NumPy arrays <-> point clouds and transforms.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "sgdicp/core/error.hpp"

namespace sgdicp::python {
namespace {

// double -> float as the file readers do it (sgdicp::to_float_saturating).
float to_float(double value) {
  return sgdicp::to_float_saturating(value);
}
float to_float(float value) {
  return value;
}

std::string shape_string(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) {
    if (d > 0) s += ", ";
    s += std::to_string(a.shape(d));
  }
  return s + (a.ndim() == 1 ? ",)" : ")");
}

bool native_byte_order(const py::dtype& dtype) {
  const char order = dtype.byteorder();
  constexpr char native = std::endian::native == std::endian::little ? '<' : '>';
  return order == '=' || order == '|' || order == native;
}

// Reads element by element through the strides with memcpy, which is valid for any layout and
// alignment and compiles to plain loads.
template <typename T>
Eigen::Matrix<T, 3, 1> row_at(const py::array& a, py::ssize_t i) {
  const char* row = static_cast<const char*>(a.data()) + i * a.strides(0);
  Eigen::Matrix<T, 3, 1> p;
  for (int j = 0; j < 3; ++j) std::memcpy(&p[j], row + j * a.strides(1), sizeof(T));
  return p;
}

// float64 rows may be georeferenced (UTM, survey data): stored from the origin their first finite
// row gives (zero for a cloud near its frame's origin), as the file readers do.
Eigen::Vector3d origin_of_rows(const py::array& a) {
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    const Eigen::Vector3d p = row_at<double>(a, i);
    if (p.allFinite()) return georeferencing_origin(p);
  }
  return Eigen::Vector3d::Zero();
}

// Copies the rows into out.cloud.points; `kept` (when given) gets one flag per row.
template <typename T>
void copy_rows(const py::array& a, NonFinite non_finite, ConvertedCloud& out,
               std::vector<bool>* kept) {
  const py::ssize_t rows = a.shape(0);
  out.cloud.points.reserve(static_cast<std::size_t>(rows));
  if constexpr (std::is_same_v<T, double>) out.cloud.origin_m = origin_of_rows(a);
  const Eigen::Matrix<T, 3, 1> origin = out.cloud.origin_m.cast<T>();
  for (py::ssize_t i = 0; i < rows; ++i) {
    const Eigen::Matrix<T, 3, 1> row = row_at<T>(a, i);
    Eigen::Vector3f p;
    for (int j = 0; j < 3; ++j) p[j] = to_float(static_cast<T>(row[j] - origin[j]));
    const bool keep = non_finite == NonFinite::keep || p.allFinite();
    if (kept) kept->push_back(keep);
    if (!keep) {
      ++out.non_finite_dropped;
      continue;
    }
    out.cloud.points.push_back(p);
  }
}

// The normals of the kept rows (the points' non-finite rows are dropped with them).
template <typename T>
void copy_normals(const py::array& a, const std::vector<bool>& kept, const std::string& name,
                  ConvertedCloud& out) {
  out.cloud.normals.reserve(out.cloud.points.size());
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    if (!kept[static_cast<std::size_t>(i)]) continue;
    const Eigen::Matrix<T, 3, 1> row = row_at<T>(a, i);
    Eigen::Vector3f n;
    for (int j = 0; j < 3; ++j) n[j] = to_float(row[j]);
    if (!n.allFinite()) {
      throw InvalidInputError(name + " has a non-finite normal at row " + std::to_string(i));
    }
    out.cloud.normals.push_back(n);
  }
}

py::array as_ndarray(const py::handle& value) {
  if (py::isinstance<py::array>(value)) return py::reinterpret_borrow<py::array>(value);
  return py::module_::import("numpy").attr("asarray")(value);
}

// An (N, 3) float32/float64 array with native byte order; InvalidInputError naming `name`
// for another dtype or shape.
py::array checked_rows(const py::handle& value, const std::string& name) {
  py::array a = as_ndarray(value);
  const bool is_float = a.dtype().num() == py::dtype::of<float>().num();
  const bool is_double = a.dtype().num() == py::dtype::of<double>().num();
  if (!(is_float || is_double)) {
    throw InvalidInputError(name + " must be a float32 or float64 array, got dtype " +
                            std::string(py::str(a.dtype())) +
                            " (convert with .astype(np.float64))");
  }
  if (!native_byte_order(a.dtype())) {  // rare (data read from big-endian files): swap first
    a = a.attr("astype")(a.dtype().attr("newbyteorder")("="));
  }
  if (a.ndim() != 2 || a.shape(1) != 3) {
    throw InvalidInputError(name +
                            " must be an (N, 3) array of points (one x y z row per point), " +
                            "got shape " + shape_string(a));
  }
  return a;
}

bool is_double_array(const py::array& a) {
  return a.dtype().num() == py::dtype::of<double>().num();
}

// The points and normals (None when absent) of an Open3D cloud, read through its own attributes
// so that open3d is never imported here: open3d.geometry.PointCloud (Vector3dVector, float64)
// and open3d.t.geometry.PointCloud (tensors on any device, copied to the CPU). nullopt for any
// other object.
std::optional<std::pair<py::object, py::object>> open3d_arrays(const py::handle& value) {
  const py::handle type = py::type::handle_of(value);
  const std::string module = py::str(type.attr("__module__"));
  const std::string class_name = py::str(type.attr("__name__"));
  if (module.rfind("open3d", 0) != 0 || class_name != "PointCloud") return std::nullopt;
  if (py::hasattr(value, "point")) {  // tensor cloud: a TensorMap of named attributes
    const py::object map = value.attr("point");
    const auto array = [&](const char* key) { return map.attr(key).attr("cpu")().attr("numpy")(); };
    const bool has_normals = map.attr("__contains__")("normals").cast<bool>();
    return std::pair{array("positions"), has_normals ? array("normals") : py::object(py::none())};
  }
  const bool has_normals = value.attr("has_normals")().cast<bool>();
  return std::pair{as_ndarray(value.attr("points")),
                   has_normals ? py::object(as_ndarray(value.attr("normals"))) : py::none()};
}

}  // namespace

ConvertedCloud cloud_from_array(const py::handle& points, std::string_view what,
                                NonFinite non_finite, bool allow_empty, const py::handle& normals) {
  const std::string name(what);
  if (py::isinstance<py::str>(points) || py::hasattr(points, "__fspath__")) {
    throw InvalidInputError(name + " must be an (N, 3) array of points, got a path " +
                            std::string(py::str(points)) +
                            " (read files with sgd_icp.read_points(path))");
  }
  py::object rows = py::reinterpret_borrow<py::object>(points);
  py::object normal_rows = py::reinterpret_borrow<py::object>(normals);
  if (auto o3d = open3d_arrays(points)) {
    if (!normals.is_none() && !o3d->second.is_none()) {
      throw InvalidInputError(name + " is an Open3D cloud with normals: drop normals=");
    }
    rows = o3d->first;
    if (normals.is_none()) normal_rows = o3d->second;
  }
  const py::array a = checked_rows(rows, name);
  if (a.shape(0) == 0 && !allow_empty) {
    throw InvalidInputError(name + " has no points (shape " + shape_string(a) + ")");
  }
  std::optional<py::array> n;
  if (!normal_rows.is_none()) {
    n = checked_rows(normal_rows, name + " normals");
    if (n->shape(0) != a.shape(0)) {
      throw InvalidInputError(name + " has " + std::to_string(a.shape(0)) + " points but " +
                              std::to_string(n->shape(0)) + " normals");
    }
  }
  ConvertedCloud out;
  std::vector<bool> kept;
  if (is_double_array(a)) {
    copy_rows<double>(a, non_finite, out, n ? &kept : nullptr);
  } else {
    copy_rows<float>(a, non_finite, out, n ? &kept : nullptr);
  }
  if (n && is_double_array(*n)) {
    copy_normals<double>(*n, kept, name, out);
  } else if (n) {
    copy_normals<float>(*n, kept, name, out);
  }
  if (out.cloud.empty() && !allow_empty) {
    throw InvalidInputError(name + " has no finite points: all " +
                            std::to_string(out.non_finite_dropped) +
                            " rows hold a NaN or infinite coordinate");
  }
  return out;
}

// origin + point in double, for a cloud whose points are stored from a non-zero origin.
py::array_t<double> absolute_points(const PointCloud& cloud) {
  py::array_t<double> out({static_cast<py::ssize_t>(cloud.size()), py::ssize_t{3}});
  auto rows = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.points[i].cast<double>() + cloud.origin_m;
    for (int j = 0; j < 3; ++j) rows(static_cast<py::ssize_t>(i), j) = p[j];
  }
  return out;
}

TimesArray times_from_array(const py::handle& times, std::size_t count) {
  const auto t = py::cast<py::array_t<double, py::array::c_style | py::array::forcecast>>(times);
  if (t.ndim() != 1 || static_cast<std::size_t>(t.shape(0)) != count) {
    throw InvalidInputError("times: one per point, (" + std::to_string(count) + ",), got " +
                            std::to_string(t.size()) + " values");
  }
  const double* data = t.data();
  TimesArray out;
  out.earliest_s = count > 0 ? *std::min_element(data, data + t.size()) : 0.0;
  out.relative_s.reserve(count);
  for (py::ssize_t i = 0; i < t.size(); ++i) {
    const double relative = data[i] - out.earliest_s;
    if (!std::isfinite(relative) || relative > std::numeric_limits<float>::max()) {
      throw InvalidInputError("times: a time is not finite (or too far from the earliest)");
    }
    out.relative_s.push_back(static_cast<float>(relative));
  }
  return out;
}

py::array array_from_cloud(PointCloud&& cloud) {
  if (!cloud.origin_m.isZero()) return absolute_points(cloud);
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "Vector3f must be packed");
  using Storage = std::vector<Eigen::Vector3f>;
  auto storage = std::make_unique<Storage>(std::move(cloud.points));
  const auto rows = static_cast<py::ssize_t>(storage->size());
  float* data = storage->empty() ? nullptr : storage->front().data();
  const py::capsule owner(storage.get(), [](void* p) { delete static_cast<Storage*>(p); });
  storage.release();  // the capsule owns it now
  const std::vector<py::ssize_t> shape{rows, 3};
  if (rows == 0) return py::array_t<float>(shape);
  return py::array_t<float>(shape, data, owner);
}

py::array readonly_view(const PointCloud& cloud, const py::handle& owner) {
  if (!cloud.origin_m.isZero()) {
    py::array copy = absolute_points(cloud);
    copy.attr("setflags")(py::arg("write") = false);
    return copy;
  }
  const auto rows = static_cast<py::ssize_t>(cloud.size());
  const std::vector<py::ssize_t> shape{rows, 3};
  if (rows == 0) return py::array_t<float>(shape);
  py::array_t<float> view(shape, cloud.points.front().data(), owner);
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

Eigen::Matrix4d matrix_from_array(const py::handle& matrix, std::string_view what) {
  const std::string name(what);
  py::array_t<double> a;
  try {
    a = py::module_::import("numpy").attr("asarray")(matrix, py::arg("dtype") = "float64");
  } catch (const py::error_already_set& e) {
    throw InvalidInputError(name + " must be a (4, 4) array of numbers, got " + type_name(matrix) +
                            " (" + e.what() + ")");
  }
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) {
    throw InvalidInputError(name + " must be a (4, 4) transform, got shape " + shape_string(a));
  }
  Eigen::Matrix4d m;
  const auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < 4; ++i) {
    for (py::ssize_t j = 0; j < 4; ++j) m(i, j) = r(i, j);
  }
  return m;
}

py::array_t<double> array_from_matrix(const Eigen::Matrix4d& matrix) {
  py::array_t<double> a(std::vector<py::ssize_t>{4, 4});
  auto w = a.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < 4; ++i) {
    for (py::ssize_t j = 0; j < 4; ++j) w(i, j) = matrix(i, j);
  }
  return a;
}

}  // namespace sgdicp::python
