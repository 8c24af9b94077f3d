#pragma once
// Depth images as point clouds: a 16-bit depth PNG (or a depth array already in memory) with
// pinhole intrinsics, back-projected into the camera frame (docs/depth.md).
//
// Camera frame: x right, y down, z forward (along the optical axis), metres. Pixel (u, v) =
// (column, row), with (0, 0) the centre of the top-left pixel, and depth z along the optical
// axis (not the ray length) give
//     x = (u - cx) z / fx,   y = (v - cy) z / fy,   z = d / depth_units_per_m.
//
// Pixels without a usable depth are dropped and counted, never returned: 0 (the sensors' "no
// reading"), NaN or infinite (float images), or a depth outside [min_depth_m, max_depth_m]
// (this also drops 65535, the "saturated / no reading" value of some 16-bit sensors, at the
// default scale). Points are emitted row by row, left to right.
//
// The same limits as every other reader (io.hpp): a file over kMaxFileBytes is refused, and an
// image of more than kMaxCloudPoints pixels is refused from its header, before it is decoded.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>

#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp {

/// Pinhole intrinsics of the depth camera, in pixels: focal lengths fx, fy and principal point
/// (cx, cy). No skew, no lens distortion (depth images are delivered undistorted).
struct PinholeIntrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;

  /// Throws InvalidSettingsError unless fx, fy are finite and > 0 and cx, cy finite.
  void validate() const;
  bool operator==(const PinholeIntrinsics&) const = default;
};

/// Depth units per metre of 16-bit depth images: millimetres (7-Scenes, Kinect and RealSense
/// tools), and the TUM RGB-D benchmark's 1/5000 m.
inline constexpr double kDefaultDepthUnitsPerMetre = 1000.0;
inline constexpr double kTumDepthUnitsPerMetre = 5000.0;

struct DepthImageSettings {
  /// Stored depth units per metre of a 16-bit image: 1000 (millimetres: 7-Scenes, most Kinect
  /// and RealSense tools), 5000 (TUM RGB-D). 0 = the data's own: kTumDepthUnitsPerMetre for the
  /// frames of a TUM RGB-D sequence (frame_source.hpp), else kDefaultDepthUnitsPerMetre. Float
  /// images are in metres and ignore it.
  double depth_units_per_m = 0.0;
  /// Deeper pixels are dropped (invalid_range). 10 m is beyond the working range of consumer
  /// depth cameras (Kinect v1 0.8-4 m, RealSense D4xx <= 10 m), whose depth error grows with
  /// the square of the range; it also drops the 65535 sentinel (65.5 m in millimetres).
  double max_depth_m = 10.0;
  /// Shallower pixels are dropped (invalid_range); 0 keeps every nonzero depth (0 itself is
  /// always dropped, as invalid_zero).
  double min_depth_m = 0.0;
  /// Take every n-th pixel in x and y (1 = all): thins the cloud n^2-fold before anything else.
  int pixel_stride = 1;
  /// Pixels dropped along each edge of the image (a band this wide at the left, right, top and
  /// bottom), before the stride. A Kinect v1's depth is off by up to ~1 cm toward its left and
  /// right edges (docs/depth.md, *Distorted edges*); 0 keeps every pixel. An image narrower or
  /// lower than two borders is refused when read (InvalidSettingsError).
  int border_px = 0;

  /// Throws InvalidSettingsError naming the field unless depth_units_per_m is 0 or in (0, 1e9],
  /// 0 <= min_depth_m < max_depth_m <= 1e6 (all finite), pixel_stride in [1, 65536] and
  /// border_px in [0, 65536].
  void validate() const;
  bool operator==(const DepthImageSettings&) const = default;
};

/// What happened to the pixels: pixels = valid + invalid_zero + invalid_range + nonfinite,
/// counting only the pixels the stride visits within the border.
struct DepthImageReport {
  std::size_t pixels = 0;         ///< pixels visited: within the border, every stride-th
  std::size_t valid = 0;          ///< back-projected: the points of the cloud
  std::size_t invalid_zero = 0;   ///< depth 0: no reading
  std::size_t invalid_range = 0;  ///< depth outside [min_depth_m, max_depth_m] (or negative)
  std::size_t nonfinite = 0;      ///< NaN or infinite depth (float images only)
  int width = 0;                  ///< of the image, pixels
  int height = 0;
};

/// Reads a 3x3 camera matrix K (three lines of three numbers, spaces, tabs or commas: the
/// 7-Scenes camera-intrinsics.txt layout `fx 0 cx / 0 fy cy / 0 0 1`). Throws IoError when the
/// file cannot be read, FormatError naming the file when it is not such a matrix (nonzero skew
/// or a last row other than 0 0 1 included), InvalidSettingsError when fx or fy <= 0.
[[nodiscard]] PinholeIntrinsics read_intrinsics(const std::filesystem::path& path);

/// Parses "fx,fy,cx,cy" (four numbers separated by commas and/or spaces). Throws FormatError or
/// InvalidSettingsError (the values, as validate()).
[[nodiscard]] PinholeIntrinsics parse_intrinsics(std::string_view text);

/// Reads a 16-bit single-channel PNG depth image and back-projects it. Throws IoError (cannot
/// read), FormatError naming the file (not a PNG, not 16-bit greyscale, truncated, too many
/// pixels) or InvalidSettingsError (intrinsics or settings). `report`, when given, is filled.
[[nodiscard]] PointCloud read_depth_image(const std::filesystem::path& path,
                                          const PinholeIntrinsics& intrinsics,
                                          const DepthImageSettings& settings = {},
                                          DepthImageReport* report = nullptr);

/// The same decoder on a whole file's bytes held in memory (`name` stands for the file in
/// messages): the entry point of the fuzz target.
[[nodiscard]] PointCloud read_depth_image_from_memory(std::span<const std::byte> bytes,
                                                      const PinholeIntrinsics& intrinsics,
                                                      const DepthImageSettings& settings = {},
                                                      DepthImageReport* report = nullptr,
                                                      std::string_view name = "<memory>");

/// Back-projects a row-major depth image of stored units (depth_units_per_m per metre).
/// Throws InvalidSettingsError (intrinsics, settings) or InvalidInputError (size).
[[nodiscard]] PointCloud depth_image_to_cloud(const std::uint16_t* depth, int width, int height,
                                              const PinholeIntrinsics& intrinsics,
                                              const DepthImageSettings& settings,
                                              DepthImageReport* report);

/// Back-projects a row-major depth image in metres (depth_units_per_m is not used).
[[nodiscard]] PointCloud depth_image_to_cloud(const float* depth_m, int width, int height,
                                              const PinholeIntrinsics& intrinsics,
                                              const DepthImageSettings& settings,
                                              DepthImageReport* report);

}  // namespace sgdicp
