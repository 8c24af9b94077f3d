#include "sgdicp/io/trajectory_io.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <Eigen/Geometry>

#include "io/parse_number.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/core/pose.hpp"
#include "sgdicp/io/transform_io.hpp"

namespace sgdicp {
namespace {

constexpr std::uintmax_t kMaxTrajectoryFileBytes = std::uintmax_t{1} << 28;

std::vector<std::string> read_lines(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw IoError(path.string() + ": a directory, not a trajectory file");
  }
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec)) {
    throw IoError(path.string() + ": not a regular file");
  }
  if (std::filesystem::file_size(path, ec) > kMaxTrajectoryFileBytes && !ec) {
    throw IoError(path.string() + ": larger than 256 MiB, not a trajectory file");
  }
  std::ifstream in(path);
  if (!in) throw IoError(path.string() + ": cannot open: " + std::strerror(errno));
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  if (in.bad()) throw IoError(path.string() + ": read error");
  return lines;
}

// The numbers of a line (separated by blanks or commas); empty for a blank or '#' line.
std::vector<double> numbers_of(const std::string& line, const std::filesystem::path& path,
                               std::size_t line_number) {
  std::vector<double> out;
  const auto first = line.find_first_not_of(" \t\r");
  if (first == std::string::npos || line[first] == '#') return out;
  std::string token;
  std::string text = line;
  std::replace(text.begin(), text.end(), ',', ' ');
  std::istringstream words(text);
  while (words >> token) {
    double v = 0.0;
    if (!parse_number(token, v) || !std::isfinite(v)) {
      throw FormatError(path.string() + ": line " + std::to_string(line_number) + ": '" + token +
                        "' is not a finite number");
    }
    out.push_back(v);
  }
  return out;
}

[[noreturn]] void bad_count(const std::filesystem::path& path, std::size_t line, std::size_t got,
                            std::string_view expected) {
  throw FormatError(path.string() + ": line " + std::to_string(line) + ": " + std::to_string(got) +
                    " numbers, expected " + std::string(expected));
}

Eigen::Matrix4d checked_rigid(const Eigen::Matrix4d& T, const std::filesystem::path& path,
                              std::size_t line) {
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-2 ||
      R.determinant() < 0.5 ||
      (T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6) {
    throw FormatError(
        path.string() + ": line " + std::to_string(line) +
        ": not a rigid transform (rotation orthonormal within 1e-2, last row 0 0 0 1)");
  }
  return orthonormalized(T);
}

}  // namespace

Trajectory read_kitti_poses(const std::filesystem::path& path) {
  Trajectory out;
  out.format = "kitti";
  const auto lines = read_lines(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto v = numbers_of(lines[i], path, i + 1);
    if (v.empty()) continue;
    if (v.size() != 12) bad_count(path, i + 1, v.size(), "12 (a 3x4 row-major pose)");
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) T(r, c) = v[static_cast<std::size_t>(4 * r + c)];
    }
    out.poses.push_back(checked_rigid(T, path, i + 1));
  }
  if (out.poses.empty()) throw FormatError(path.string() + ": no pose in the file");
  return out;
}

Trajectory read_tum_trajectory(const std::filesystem::path& path) {
  Trajectory out;
  out.format = "tum";
  const auto lines = read_lines(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto v = numbers_of(lines[i], path, i + 1);
    if (v.empty()) continue;
    if (v.size() != 8) bad_count(path, i + 1, v.size(), "8 (timestamp tx ty tz qx qy qz qw)");
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (q.norm() < 1e-6) {
      throw FormatError(path.string() + ": line " + std::to_string(i + 1) + ": zero quaternion");
    }
    q.normalize();
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.topLeftCorner<3, 3>() = q.toRotationMatrix();
    T.topRightCorner<3, 1>() = Eigen::Vector3d(v[1], v[2], v[3]);
    out.poses.push_back(T);
    out.timestamps_s.push_back(v[0]);
  }
  if (out.poses.empty()) throw FormatError(path.string() + ": no pose in the file");
  return out;
}

Trajectory read_sevenscenes_poses(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("frame-") && name.ends_with(".pose.txt")) files.push_back(entry.path());
  }
  if (ec) throw IoError(folder.string() + ": cannot list: " + ec.message());
  if (files.empty()) throw FormatError(folder.string() + ": no frame-*.pose.txt file");
  std::sort(files.begin(), files.end());
  Trajectory out;
  out.format = "7scenes";
  for (const auto& f : files) {
    const auto lines = read_lines(f);
    std::vector<double> v;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const auto row = numbers_of(lines[i], f, i + 1);
      v.insert(v.end(), row.begin(), row.end());
    }
    if (v.size() != 16) bad_count(f, 1, v.size(), "16 (a 4x4 camera-to-world matrix)");
    Eigen::Matrix4d T;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) T(r, c) = v[static_cast<std::size_t>(4 * r + c)];
    }
    out.poses.push_back(checked_rigid(T, f, 1));
  }
  return out;
}

Trajectory read_trajectory(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return read_sevenscenes_poses(path);
  const auto lines = read_lines(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto v = numbers_of(lines[i], path, i + 1);
    if (v.empty()) continue;
    if (v.size() == 12) return read_kitti_poses(path);
    if (v.size() == 8) return read_tum_trajectory(path);
    bad_count(path, i + 1, v.size(), "12 (KITTI poses) or 8 (TUM: timestamp tx ty tz qx qy qz qw)");
  }
  throw FormatError(path.string() + ": no pose in the file");
}

void write_kitti_pose(std::ostream& out, const Eigen::Matrix4d& T) {
  const std::streamsize precision = out.precision(9);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) out << (r || c ? " " : "") << T(r, c) + 0.0;  // -0 prints as 0
  }
  out << '\n';
  out.precision(precision);
}

void write_tum_pose(std::ostream& out, double timestamp_s, const Eigen::Matrix4d& T) {
  const std::streamsize precision = out.precision();
  const Eigen::Quaterniond q(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
  out << std::fixed << std::setprecision(6) << timestamp_s << std::defaultfloat
      << std::setprecision(9) << ' ' << T(0, 3) << ' ' << T(1, 3) << ' ' << T(2, 3) << ' ' << q.x()
      << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  out.precision(precision);
}

void write_kitti_poses(const std::filesystem::path& path,
                       const std::vector<Eigen::Matrix4d>& poses) {
  std::ofstream out(path);
  if (!out) throw IoError(path.string() + ": cannot open for writing: " + std::strerror(errno));
  for (const auto& T : poses) write_kitti_pose(out, T);
  if (!out) throw IoError(path.string() + ": write error");
}

void write_tum_trajectory(const std::filesystem::path& path,
                          const std::vector<Eigen::Matrix4d>& poses,
                          const std::vector<double>& timestamps_s) {
  if (timestamps_s.size() != poses.size()) {
    throw InvalidInputError(path.string() + ": " + std::to_string(timestamps_s.size()) +
                            " timestamps for " + std::to_string(poses.size()) + " poses");
  }
  std::ofstream out(path);
  if (!out) throw IoError(path.string() + ": cannot open for writing: " + std::strerror(errno));
  out << kTumHeader;
  for (std::size_t i = 0; i < poses.size(); ++i) write_tum_pose(out, timestamps_s[i], poses[i]);
  if (!out) throw IoError(path.string() + ": write error");
}

Eigen::Matrix4d read_kitti_calibration_tr(const std::filesystem::path& path) {
  const auto lines = read_lines(path);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (!lines[i].starts_with("Tr:")) continue;
    return parse_transform(lines[i].substr(3), path.string() + " (Tr:)");
  }
  throw FormatError(path.string() + ": no 'Tr:' line (a KITTI calib.txt)");
}

}  // namespace sgdicp
