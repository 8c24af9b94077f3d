// File I/O of sgd_icp: point clouds (read_point_cloud, read_points, write_points), transforms
// (read_transform) and pairs files (read_pairs), with the library's readers and writers.
#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>

#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"
#include "sgdicp/io/transform_io.hpp"
#include "sgdicp/tools/pairs.hpp"

namespace sgdicp::python {
namespace {

using namespace pybind11::literals;

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
  py::object times;  // (N,) float32 seconds, or None
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
  py::object times = py::none();
  if (read.cloud.has_times()) {
    times = py::array_t<float>(static_cast<py::ssize_t>(read.cloud.times_s.size()),
                               read.cloud.times_s.data());
  }
  return ReadPoints{array_from_cloud(std::move(read.cloud)), std::move(times), read.points_in_file,
                    read.non_finite_dropped, to_string(read.format)};
}

}  // namespace

void bind_io(py::module_& m) {
  py::class_<ReadPoints>(m, "ReadResult", "A point cloud read from a file, with its counts.")
      .def_readonly("points", &ReadPoints::points,
                    "(N, 3) float32 array of the finite points, in file order, metres (float64 for "
                    "georeferenced coordinates, which float32 cannot hold: docs/io.md).")
      .def_readonly("times", &ReadPoints::times,
                    "(N,) float32 array of each point's time, seconds from the earliest, when the "
                    "file has a per-point time field (docs/io.md, Per-point times), else None: "
                    "give it to Odometry.register_frame(points, times=...).")
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

}  // namespace sgdicp::python
