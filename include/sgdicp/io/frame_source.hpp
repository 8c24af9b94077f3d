#pragma once
// The frames of a sequence, for odometry: a list of frame files, a reader of frame i, and the
// frames' timestamps when the layout gives them. Layouts:
//   - a folder of point-cloud files of one readable format (io.hpp), in name order;
//   - a KITTI sequence folder: its velodyne/ subfolder of .bin scans, and its times.txt (one
//     timestamp per line, line k for scan 0000k) when present;
//   - a 7-Scenes sequence folder: frame-NNNNNN.depth.png depth images (depth_image.hpp) with the
//     folder's camera-intrinsics.txt (or the intrinsics given), 30 Hz;
//   - a TUM RGB-D sequence folder: depth.txt ("timestamp path" per frame, paths relative to the
//     folder, '#' comments; timestamps from it) listing 16-bit depth PNGs of 5000 units per metre
//     (unless DepthImageSettings says otherwise), 30 Hz; intrinsics must be given (TUM ships none).
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <optional>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/io/depth_image.hpp"

namespace sgdicp {

struct FrameSource {
  std::filesystem::path folder;  ///< where the frames are
  std::string layout;            ///< "clouds", "kitti", "7scenes" or "tum"
  std::vector<std::filesystem::path> frames;
  std::vector<double> timestamps_s;  ///< one per frame, or empty when unknown
  double nominal_rate_hz = 0.0;      ///< the layout's frame rate, 0 when unknown
  /// Depth-image frames: their intrinsics and back-projection settings.
  std::optional<PinholeIntrinsics> intrinsics;
  DepthImageSettings depth;

  [[nodiscard]] std::size_t size() const noexcept { return frames.size(); }
  /// Frame i in its sensor frame. Throws IoError or FormatError (naming the file).
  [[nodiscard]] PointCloud read(std::size_t i) const;
};

/// The frames of a folder. Throws IoError for a missing folder, FormatError for a folder with no
/// readable frame or with frames of several formats (naming two of them).
/// Depth images use `intrinsics` when given, else the folder's camera-intrinsics.txt (IoError /
/// FormatError naming it when missing or malformed; a TUM sequence, which has none,
/// InvalidSettingsError), with `depth` (depth_units_per_m 0: TUM 5000, 7-Scenes 1000).
/// A malformed depth.txt raises FormatError naming its line.
[[nodiscard]] FrameSource open_frame_source(
    const std::filesystem::path& input,
    const std::optional<PinholeIntrinsics>& intrinsics = std::nullopt,
    const DepthImageSettings& depth = {});

}  // namespace sgdicp
