// NumPy arrays <-> point clouds and transforms.
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "sgdicp/error.hpp"

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
void copy_rows(const py::array& a, NonFinite non_finite, ConvertedCloud& out) {
  const auto* base = static_cast<const char*>(a.data());
  const py::ssize_t rows = a.shape(0);
  const py::ssize_t row_stride = a.strides(0);
  const py::ssize_t column_stride = a.strides(1);
  out.cloud.points.reserve(static_cast<std::size_t>(rows));
  for (py::ssize_t i = 0; i < rows; ++i) {
    const char* row = base + i * row_stride;
    Eigen::Vector3f p;
    for (int j = 0; j < 3; ++j) {
      T value;
      std::memcpy(&value, row + j * column_stride, sizeof(T));
      p[j] = to_float(value);
    }
    if (non_finite == NonFinite::drop && !p.allFinite()) {
      ++out.non_finite_dropped;
      continue;
    }
    out.cloud.points.push_back(p);
  }
}

py::array as_ndarray(const py::handle& value) {
  if (py::isinstance<py::array>(value)) return py::reinterpret_borrow<py::array>(value);
  return py::module_::import("numpy").attr("asarray")(value);
}

}  // namespace

ConvertedCloud cloud_from_array(const py::handle& points, std::string_view what,
                                NonFinite non_finite, bool allow_empty) {
  const std::string name(what);
  if (py::isinstance<py::str>(points) || py::hasattr(points, "__fspath__")) {
    throw InvalidInputError(name + " must be an (N, 3) array of points, got a path " +
                            std::string(py::str(points)) +
                            " (read files with sgd_icp.read_points(path))");
  }
  py::array a = as_ndarray(points);
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
  if (a.shape(0) == 0 && !allow_empty) {
    throw InvalidInputError(name + " has no points (shape " + shape_string(a) + ")");
  }
  ConvertedCloud out;
  if (is_float) {
    copy_rows<float>(a, non_finite, out);
  } else {
    copy_rows<double>(a, non_finite, out);
  }
  if (out.cloud.empty() && !allow_empty) {
    throw InvalidInputError(name + " has no finite points: all " +
                            std::to_string(out.non_finite_dropped) +
                            " rows hold a NaN or infinite coordinate");
  }
  return out;
}

py::array_t<float> array_from_cloud(PointCloud&& cloud) {
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

py::array_t<float> readonly_view(const PointCloud& cloud, const py::handle& owner) {
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
