// Point-cloud file I/O. Every reader works on one in-memory copy of the whole file and checks
// each access against its size, so a truncated or lying file ends in a FormatError, never in
// an out-of-bounds read or an allocation the file cannot back.
// This file picks the format and holds the public entry points of sgdicp/io/io.hpp; each format
// has its own file beside it (io_internal.hpp lists them).
#include "io/io_internal.hpp"

namespace sgdicp {

using namespace io_detail;

namespace {

// The one parser behind both entry points: the bytes of a whole file in a known format.
ReadResult parse_point_cloud(const std::string& name, std::string_view data, FileFormat format) {
  if (data.empty()) fail_byte(name, 0, "empty file");
  ReadResult result;
  result.format = format;
  PointSink sink(name, result);
  switch (format) {
    case FileFormat::pcd:
      read_pcd(name, data, sink);
      break;
    case FileFormat::ply:
      read_ply(name, data, sink);
      break;
    case FileFormat::kitti_bin:
      read_float_records(name, data, 4, "float32 x y z intensity", sink);
      break;
    case FileFormat::xyz:
      read_xyz(name, data, sink);
      break;
    case FileFormat::vtk:
      read_vtk(name, data, sink);
      break;
    case FileFormat::f32:
      read_float_records(name, data, 3, "float32 x y z", sink);
      break;
    case FileFormat::automatic:
      break;  // resolved by the callers
  }
  sink.finish();
  return result;
}

}  // namespace

FileFormat format_from_extension(const std::filesystem::path& path) {
  const std::string extension = lowercase(path.extension().string());
  if (extension == ".pcd") return FileFormat::pcd;
  if (extension == ".ply") return FileFormat::ply;
  if (extension == ".bin") return FileFormat::kitti_bin;
  if (extension == ".xyz" || extension == ".txt" || extension == ".csv") return FileFormat::xyz;
  if (extension == ".vtk") return FileFormat::vtk;
  if (extension == ".f32") return FileFormat::f32;
  throw FormatError(path.string() + ": " +
                    (extension.empty() ? std::string("no file extension")
                                       : "unknown file extension " + shown(extension)) +
                    " (known: .pcd .ply .bin .xyz .txt .csv .vtk .f32)");
}

ReadResult read_point_cloud(const std::filesystem::path& path, FileFormat format) {
  const FileFormat resolved =
      format == FileFormat::automatic ? format_from_extension(path) : format;
  const std::string name = path.string();
  const std::vector<char> bytes = read_whole_file(path, name);
  return parse_point_cloud(name, std::string_view(bytes.data(), bytes.size()), resolved);
}

ReadResult read_point_cloud_from_memory(std::span<const std::byte> bytes, FileFormat format,
                                        std::string_view name) {
  if (bytes.size() > kMaxFileBytes) {
    throw FormatError(std::string(name) + ": larger than the largest file read (" +
                      limit_text(kMaxFileBytes) + ")");
  }
  if (format == FileFormat::automatic) {
    throw FormatError(std::string(name) +
                      ": reading from memory needs an explicit format (no extension to go by)");
  }
  return parse_point_cloud(
      std::string(name),
      std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), format);
}

void write_point_cloud(const std::filesystem::path& path, const PointCloud& cloud,
                       FileFormat format, Encoding encoding) {
  const FileFormat resolved =
      format == FileFormat::automatic ? format_from_extension(path) : format;
  const std::string name = path.string();
  std::string out;
  switch (resolved) {
    case FileFormat::ply:
      out = ply_text(cloud, encoding);
      break;
    case FileFormat::pcd:
      out = pcd_text(cloud, encoding);
      break;
    case FileFormat::xyz:
      append_points_text(out, cloud);
      break;
    default:
      throw FormatError(name + ": cannot write " + to_string(resolved) +
                        " files (PLY, PCD and XYZ can be written)");
  }
  write_whole_file(path, name, out);
}

}  // namespace sgdicp
