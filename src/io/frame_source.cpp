#include "sgdicp/io/frame_source.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <optional>

#include "io/parse_number.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

namespace sgdicp {
namespace {

std::optional<FileFormat> cloud_format(const std::filesystem::path& path) {
  try {
    return format_from_extension(path);
  } catch (const FormatError&) {
    return std::nullopt;
  }
}

// KITTI's times.txt: line k is the timestamp of scan k (the number in its name).
std::vector<double> kitti_timestamps(const std::filesystem::path& times,
                                     const std::vector<std::filesystem::path>& frames) {
  std::ifstream in(times);
  if (!in) return {};
  std::vector<double> all;
  for (std::string line; std::getline(in, line);) {
    double v = 0.0;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    const auto last = line.find_last_not_of(" \t\r");
    if (!parse_number(std::string_view(line).substr(first, last - first + 1), v)) {
      throw FormatError(times.string() + ": line " + std::to_string(all.size() + 1) +
                        ": not a timestamp");
    }
    all.push_back(v);
  }
  std::vector<double> out;
  for (const auto& f : frames) {
    const std::string stem = f.stem().string();
    std::size_t k = 0;
    const auto [end, ec] = std::from_chars(stem.data(), stem.data() + stem.size(), k);
    if (ec != std::errc() || end != stem.data() + stem.size() || k >= all.size()) return {};
    out.push_back(all[k]);
  }
  return out;
}

// The frame-*.depth.png files of a 7-Scenes sequence folder, sorted; empty when there are none.
std::vector<std::filesystem::path> sevenscenes_frames(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> out;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("frame-") && name.ends_with(".depth.png")) out.push_back(entry.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// A TUM RGB-D sequence's depth.txt: "timestamp path" per frame, paths relative to the folder,
// '#' comments. Fills the frames and their timestamps; false when the folder has no depth.txt.
bool read_tum_depth_list(const std::filesystem::path& folder, FrameSource& source) {
  const std::filesystem::path list = folder / "depth.txt";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(list, ec)) return false;
  std::ifstream in(list);
  if (!in) throw IoError(list.string() + ": cannot open");
  std::size_t line_number = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const auto gap = line.find_first_of(" \t", first);
    const auto name = gap == std::string::npos ? gap : line.find_first_not_of(" \t", gap);
    const auto last = line.find_last_not_of(" \t\r");
    double t = 0.0;
    if (name == std::string::npos ||
        !parse_number(std::string_view(line).substr(first, gap - first), t) || !std::isfinite(t) ||
        line.find_first_of(" \t", name) < last) {
      throw FormatError(list.string() + ": line " + std::to_string(line_number) +
                        ": expected 'timestamp path' (the TUM RGB-D depth.txt)");
    }
    if (!source.timestamps_s.empty() && t <= source.timestamps_s.back()) {
      throw FormatError(list.string() + ": line " + std::to_string(line_number) +
                        ": timestamps must increase");
    }
    source.timestamps_s.push_back(t);
    source.frames.push_back(folder / line.substr(name, last - name + 1));
  }
  if (source.frames.empty()) throw FormatError(list.string() + ": no frame listed");
  return true;
}

}  // namespace

PointCloud FrameSource::read(std::size_t i) const {
  if (intrinsics) return read_depth_image(frames.at(i), *intrinsics, depth);
  return read_point_cloud(frames.at(i)).cloud;
}

FrameSource open_frame_source(const std::filesystem::path& input,
                              const std::optional<PinholeIntrinsics>& intrinsics,
                              const DepthImageSettings& depth) {
  std::error_code ec;
  if (!std::filesystem::is_directory(input, ec)) {
    throw IoError(input.string() + ": not a folder (odometry reads a folder of frames)");
  }
  FrameSource source;
  if (read_tum_depth_list(input, source)) {
    source.layout = "tum";
    source.folder = input;
    source.nominal_rate_hz = 30.0;
    depth.validate();
    source.depth = depth;
    if (source.depth.depth_units_per_m == 0.0) {
      source.depth.depth_units_per_m = kTumDepthUnitsPerMetre;
    }
    if (!intrinsics) {
      throw InvalidSettingsError(
          input.string() +
          ": a TUM RGB-D sequence has no intrinsics file: give them (--intrinsics fx,fy,cx,cy; "
          "the benchmark's calibration lists e.g. freiburg1 517.3,516.5,318.6,255.3)");
    }
    intrinsics->validate();
    source.intrinsics = intrinsics;
    return source;
  }
  source.frames = sevenscenes_frames(input);
  if (!source.frames.empty()) {
    source.layout = "7scenes";
    source.folder = input;
    source.nominal_rate_hz = 30.0;
    depth.validate();
    source.depth = depth;
    source.intrinsics = intrinsics ? *intrinsics : read_intrinsics(input / "camera-intrinsics.txt");
    source.intrinsics->validate();
    return source;
  }
  source.layout = "clouds";
  source.folder = input;
  if (std::filesystem::is_directory(input / "velodyne", ec)) {
    source.layout = "kitti";
    source.folder = input / "velodyne";
  }
  std::optional<FileFormat> format;
  std::filesystem::path first_of_format;
  for (const auto& entry : std::filesystem::directory_iterator(source.folder, ec)) {
    if (!entry.is_regular_file()) continue;
    const auto f = cloud_format(entry.path());
    if (!f) continue;
    if (format && *f != *format) {
      throw FormatError(source.folder.string() + ": frames of several formats (" +
                        first_of_format.filename().string() + " is " + to_string(*format) + ", " +
                        entry.path().filename().string() + " is " + to_string(*f) +
                        "): keep one format per sequence folder");
    }
    format = f;
    if (first_of_format.empty()) first_of_format = entry.path();
    source.frames.push_back(entry.path());
  }
  if (ec) throw IoError(source.folder.string() + ": cannot list: " + ec.message());
  if (source.frames.empty()) {
    throw FormatError(source.folder.string() +
                      ": no frame file (.pcd .ply .bin .xyz .txt .csv .vtk .f32) in the folder");
  }
  std::sort(source.frames.begin(), source.frames.end());
  if (source.layout == "kitti" && std::filesystem::is_regular_file(input / "times.txt", ec)) {
    source.timestamps_s = kitti_timestamps(input / "times.txt", source.frames);
  }
  return source;
}

}  // namespace sgdicp
