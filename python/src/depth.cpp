// read_depth_image and depth_to_points: depth images as (N, 3) arrays (docs/depth.md).
#include <filesystem>
#include <limits>
#include <string>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/depth_image.hpp"

namespace sgdicp::python {
namespace {

using namespace pybind11::literals;

// (fx, fy, cx, cy), a 3x3 camera matrix, or a path: a K file, else "fx,fy,cx,cy" text.
PinholeIntrinsics intrinsics_from_object(const py::handle& value) {
  if (py::isinstance<py::str>(value) ||
      py::isinstance(value, py::module_::import("os").attr("PathLike"))) {
    const std::filesystem::path path = value.cast<std::filesystem::path>();
    std::error_code ec;
    if (std::filesystem::exists(path, ec) || !py::isinstance<py::str>(value)) {
      return read_intrinsics(path);
    }
    return parse_intrinsics(value.cast<std::string>());
  }
  const auto K = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!K) {
    throw py::type_error(
        "intrinsics must be (fx, fy, cx, cy), a 3x3 camera matrix or a path, got " +
        type_name(value));
  }
  const double* k = K.data();
  if (K.ndim() == 1 && K.shape(0) == 4) {
    const PinholeIntrinsics out{k[0], k[1], k[2], k[3]};
    out.validate();
    return out;
  }
  if (K.ndim() == 2 && K.shape(0) == 3 && K.shape(1) == 3) {
    if (k[1] != 0.0 || k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0) {
      throw InvalidInputError(
          "intrinsics: a 3x3 camera matrix must be [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]");
    }
    const PinholeIntrinsics out{k[0], k[4], k[2], k[5]};
    out.validate();
    return out;
  }
  throw InvalidInputError("intrinsics must be 4 numbers (fx, fy, cx, cy) or a 3x3 matrix");
}

DepthImageSettings depth_settings(const py::handle& depth_scale, const py::handle& max_depth,
                                  const py::handle& min_depth, const py::handle& pixel_stride,
                                  const py::handle& border) {
  DepthImageSettings s;
  s.depth_units_per_m = as_real(depth_scale, "depth_scale");
  s.max_depth_m = as_real(max_depth, "max_depth");
  s.min_depth_m = as_real(min_depth, "min_depth");
  const std::uint64_t stride = as_count(pixel_stride, "pixel_stride");
  s.pixel_stride = stride > 1U << 30 ? 0 : static_cast<int>(stride);  // 0: validate() says why
  const std::uint64_t band = as_count(border, "border");
  s.border_px = band > 1U << 30 ? -1 : static_cast<int>(band);  // -1: validate() says why
  s.validate();
  return s;
}

// A 2-D uint16 (depth units) or float32/float64 (metres) array, any layout.
PointCloud cloud_from_depth_array(const py::handle& depth, const PinholeIntrinsics& K,
                                  const DepthImageSettings& s) {
  const py::array array = py::array::ensure(depth);
  if (!array || array.ndim() != 2) {
    throw InvalidInputError("depth must be a 2-D array (rows, columns), got " +
                            (array ? std::to_string(array.ndim()) + "-D" : type_name(depth)));
  }
  const auto too_large = [](py::ssize_t n) { return n > std::numeric_limits<int>::max(); };
  if (too_large(array.shape(0)) || too_large(array.shape(1))) {
    throw InvalidInputError("depth: more rows or columns than a depth image has");
  }
  const int height = static_cast<int>(array.shape(0));
  const int width = static_cast<int>(array.shape(1));
  const py::dtype dtype = array.dtype();
  if (dtype.is(py::dtype::of<std::uint16_t>())) {
    const auto c = py::array_t<std::uint16_t, py::array::c_style>::ensure(array);
    const py::gil_scoped_release release;
    return depth_image_to_cloud(c.data(), width, height, K, s, nullptr);
  }
  if (dtype.is(py::dtype::of<float>()) || dtype.is(py::dtype::of<double>())) {
    const auto c = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(array);
    const py::gil_scoped_release release;
    return depth_image_to_cloud(c.data(), width, height, K, s, nullptr);
  }
  throw InvalidInputError("depth must be uint16 (depth units) or float32/float64 (metres), got " +
                          std::string(py::str(dtype)));
}

}  // namespace

void bind_depth(py::module_& m) {
  const DepthImageSettings d;
  m.def(
      "read_depth_image",
      [](const std::filesystem::path& path, const py::handle& intrinsics,
         const py::handle& depth_scale, const py::handle& max_depth, const py::handle& min_depth,
         const py::handle& pixel_stride, const py::handle& border) {
        const PinholeIntrinsics K = intrinsics_from_object(intrinsics);
        const DepthImageSettings s =
            depth_settings(depth_scale, max_depth, min_depth, pixel_stride, border);
        PointCloud cloud = [&] {
          const py::gil_scoped_release release;
          return read_depth_image(path, K, s);
        }();
        return array_from_cloud(std::move(cloud));
      },
      "path"_a, "intrinsics"_a, "depth_scale"_a = d.depth_units_per_m,
      "max_depth"_a = d.max_depth_m, "min_depth"_a = d.min_depth_m,
      "pixel_stride"_a = d.pixel_stride, "border"_a = d.border_px,
      "Reads a 16-bit greyscale PNG depth image and back-projects its valid pixels into an (N, 3) "
      "float32 array, metres, in the camera frame (x right, y down, z forward), row by row "
      "(docs/depth.md). intrinsics: (fx, fy, cx, cy) in pixels, a 3x3 camera matrix, or the path "
      "of a 3x3 K file (the 7-Scenes camera-intrinsics.txt). depth_scale: stored units per metre, "
      "0 = 1000 (millimetres; TUM RGB-D: 5000). Pixels of depth 0, or outside [min_depth, "
      "max_depth] metres, are "
      "dropped; pixel_stride takes every n-th pixel in x and y; border drops a band of that many "
      "pixels along each edge (a Kinect v1's depth is off by up to ~1 cm toward its left and "
      "right edges). Raises IoError (OSError), "
      "FormatError (not a 16-bit greyscale PNG, truncated, too many pixels) or "
      "InvalidSettingsError (ValueError).");
  m.def(
      "depth_to_points",
      [](const py::handle& depth, const py::handle& intrinsics, const py::handle& depth_scale,
         const py::handle& max_depth, const py::handle& min_depth, const py::handle& pixel_stride,
         const py::handle& border) {
        const PinholeIntrinsics K = intrinsics_from_object(intrinsics);
        const DepthImageSettings s =
            depth_settings(depth_scale, max_depth, min_depth, pixel_stride, border);
        return array_from_cloud(cloud_from_depth_array(depth, K, s));
      },
      "depth"_a, "intrinsics"_a, "depth_scale"_a = d.depth_units_per_m,
      "max_depth"_a = d.max_depth_m, "min_depth"_a = d.min_depth_m,
      "pixel_stride"_a = d.pixel_stride, "border"_a = d.border_px,
      "Back-projects a depth image held in memory, as read_depth_image: a 2-D array (rows, "
      "columns) of uint16 stored units (depth_scale per metre) or of float32/float64 metres "
      "(depth_scale unused; NaN and infinite depths are dropped too). Returns (N, 3) float32, "
      "metres, camera frame (x right, y down, z forward). Raises InvalidInputError for another "
      "dtype or shape, InvalidSettingsError for bad intrinsics or settings.");
}

}  // namespace sgdicp::python
