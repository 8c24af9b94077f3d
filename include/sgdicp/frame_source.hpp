#pragma once
// The frames of a sequence, for odometry: a list of frame files, a reader of frame i, and the
// frames' timestamps when the layout gives them. Layouts:
//   - a folder of point-cloud files of one readable format (io.hpp), in name order;
//   - a KITTI sequence folder: its velodyne/ subfolder of .bin scans, and its times.txt (one
//     timestamp per line, line k for scan 0000k) when present.
// Depth-image layouts (7-Scenes, TUM RGB-D) plug in here as more layouts.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "sgdicp/point_cloud.hpp"

namespace sgdicp {

struct FrameSource {
  std::filesystem::path folder;  ///< where the frames are
  std::string layout;            ///< "clouds" or "kitti"
  std::vector<std::filesystem::path> frames;
  std::vector<double> timestamps_s;  ///< one per frame, or empty when unknown

  [[nodiscard]] std::size_t size() const noexcept { return frames.size(); }
  /// Frame i in its sensor frame. Throws IoError or FormatError (naming the file).
  [[nodiscard]] PointCloud read(std::size_t i) const;
};

/// The frames of a folder. Throws IoError for a missing folder, FormatError for a folder with no
/// readable frame or with frames of several formats (naming two of them).
[[nodiscard]] FrameSource open_frame_source(const std::filesystem::path& input);

}  // namespace sgdicp
