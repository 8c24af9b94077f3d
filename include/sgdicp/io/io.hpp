#pragma once
// Reading and writing point-cloud files.
//
// Read: PCD (ascii, binary, binary_compressed), PLY (ascii, binary little/big endian),
// KITTI .bin (float32 x y z intensity), text x y z (.xyz, .txt, .csv; a header line is
// allowed), legacy ASCII VTK POLYDATA, and headerless float32 x y z (.f32).
// Written: PLY, PCD and XYZ.
//
// Readers are strict and bounds-checked: a truncated or malformed file raises FormatError whose
// message names the file and where it broke (line number for text, byte offset for binary).
// Points with a non-finite coordinate are dropped and counted, never returned. PCD and PLY files
// with a per-point time field (Ouster t, Livox offset_time, Velodyne time, Hesai timestamp) fill
// PointCloud::times_s (docs/io.md, "Per-point times").
//
// Resources are bounded by the input: every count or size a header claims is checked against the
// bytes that are really there before anything is allocated, and no input larger than
// kMaxFileBytes or cloud larger than kMaxCloudPoints is read (docs/io.md).
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

#include "sgdicp/core/enum_names.hpp"
#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp {

/// Largest cloud read: 2^28 (268 million) points, 3 GiB as float x y z. A header declaring
/// more, or a file holding more, raises FormatError naming the limit.
inline constexpr std::uint64_t kMaxCloudPoints = std::uint64_t{1} << 28;

/// Largest file (or memory block) read: 16 GiB, room for kMaxCloudPoints as text. A larger
/// file raises IoError, a larger memory block FormatError. Only regular files are read: a
/// directory, device (/dev/zero), FIFO or socket raises IoError, since it has no size to bound.
inline constexpr std::uint64_t kMaxFileBytes = std::uint64_t{1} << 34;

enum class FileFormat {
  automatic,  ///< from the file extension (.pcd .ply .bin .xyz .txt .csv .vtk .f32)
  pcd,
  ply,
  kitti_bin,  ///< float32 little-endian x y z intensity, 16 bytes per point
  xyz,        ///< text, one point per line, separated by spaces, tabs, commas or semicolons
  vtk,        ///< legacy ASCII VTK POLYDATA (POINTS n float|double)
  f32,        ///< headerless float32 little-endian x y z, 12 bytes per point
};

inline constexpr std::array<EnumName<FileFormat>, 8> kFileFormatNames{{
    {FileFormat::automatic, "auto"},
    {FileFormat::pcd, "pcd"},
    {FileFormat::ply, "ply"},
    {FileFormat::kitti_bin, "kitti_bin"},
    {FileFormat::xyz, "xyz"},
    {FileFormat::vtk, "vtk"},
    {FileFormat::f32, "f32"},
    {FileFormat::automatic, "automatic"},
}};
constexpr const auto& enum_names(FileFormat) {
  return kFileFormatNames;
}
constexpr std::string_view enum_noun(FileFormat) {
  return "format";
}

/// Short lowercase name of a format ("pcd", "ply", ..., "auto"), from kFileFormatNames.
[[nodiscard]] inline std::string to_string(FileFormat format) {
  return std::string(enum_name(format));
}

/// The format implied by a path's extension; throws FormatError when it is not known.
[[nodiscard]] FileFormat format_from_extension(const std::filesystem::path& path);

struct ReadResult {
  PointCloud cloud;                           ///< the finite points, in file order
  std::size_t points_in_file = 0;             ///< points the file declares / contains
  std::size_t non_finite_dropped = 0;         ///< points dropped for a NaN or infinite coordinate
  FileFormat format = FileFormat::automatic;  ///< the format that was read
};

/// Reads the x y z of every point of a file, and each point's time when a PCD or PLY file has a
/// time field. Throws IoError (cannot open/read) or FormatError.
[[nodiscard]] ReadResult read_point_cloud(const std::filesystem::path& path,
                                          FileFormat format = FileFormat::automatic);

/// Parses a whole file's bytes held in memory, with the very parser read_point_cloud uses (same
/// result, same errors); `name` stands for the file in messages. `format` must be explicit:
/// FileFormat::automatic throws FormatError. The entry point of the fuzz targets.
[[nodiscard]] ReadResult read_point_cloud_from_memory(std::span<const std::byte> bytes,
                                                      FileFormat format,
                                                      std::string_view name = "<memory>");

/// Encoding of the written file (ignored for XYZ, which is always text).
enum class Encoding { binary, ascii };

inline constexpr std::array<EnumName<Encoding>, 2> kEncodingNames{{
    {Encoding::binary, "binary"},
    {Encoding::ascii, "ascii"},
}};
constexpr const auto& enum_names(Encoding) {
  return kEncodingNames;
}
constexpr std::string_view enum_noun(Encoding) {
  return "encoding";
}

/// Writes x y z of every point as PLY, PCD or XYZ (chosen from the extension unless given), and
/// in PLY and PCD each point's time as a float field `time` (seconds) when the cloud has times.
/// Binary PLY is little endian, binary PCD is uncompressed "binary". Throws IoError.
void write_point_cloud(const std::filesystem::path& path, const PointCloud& cloud,
                       FileFormat format = FileFormat::automatic,
                       Encoding encoding = Encoding::binary);

}  // namespace sgdicp
