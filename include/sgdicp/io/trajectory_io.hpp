#pragma once
// Trajectories as files: the KITTI odometry poses (one line per frame, 12 numbers, the 3x4
// row-major [R | t] of T_world_frame), the TUM RGB-D format (one line per frame: timestamp tx
// ty tz qx qy qz qw, '#' comments) and a 7-Scenes sequence folder (frame-NNNNNN.pose.txt, a 4x4
// camera-to-world matrix each). Rotations are re-orthonormalised on reading (7-Scenes poses
// come from dense tracking and are not exactly orthonormal; KITTI's carry 6-7 digits).
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace sgdicp {

struct Trajectory {
  std::vector<Eigen::Matrix4d> poses;  ///< T_world_frame, one per frame
  std::vector<double> timestamps_s;    ///< one per pose, or empty (KITTI, 7-Scenes)
  std::string format;                  ///< "kitti", "tum" or "7scenes"
};

/// KITTI poses file. Throws IoError or FormatError (naming the file and line).
[[nodiscard]] Trajectory read_kitti_poses(const std::filesystem::path& path);
/// TUM trajectory file (quaternion x y z w, normalised on reading).
[[nodiscard]] Trajectory read_tum_trajectory(const std::filesystem::path& path);
/// The frame-*.pose.txt files of a folder, sorted by name.
[[nodiscard]] Trajectory read_sevenscenes_poses(const std::filesystem::path& folder);
/// A folder: 7-Scenes; a file: KITTI (12 numbers on its first data line) or TUM (8 numbers).
[[nodiscard]] Trajectory read_trajectory(const std::filesystem::path& path);

/// One pose as a KITTI line: 12 numbers (the 3x4 row-major T) with 9 significant digits.
void write_kitti_pose(std::ostream& out, const Eigen::Matrix4d& T);
/// The TUM format's header line, and one pose as a TUM line: timestamp tx ty tz qx qy qz qw.
inline constexpr std::string_view kTumHeader = "# timestamp tx ty tz qx qy qz qw\n";
void write_tum_pose(std::ostream& out, double timestamp_s, const Eigen::Matrix4d& T);

/// One line per pose, 12 numbers with 9 significant digits (KITTI). Throws IoError.
void write_kitti_poses(const std::filesystem::path& path,
                       const std::vector<Eigen::Matrix4d>& poses);
/// One line per pose: timestamp tx ty tz qx qy qz qw. Throws IoError or InvalidInputError for a
/// different number of timestamps.
void write_tum_trajectory(const std::filesystem::path& path,
                          const std::vector<Eigen::Matrix4d>& poses,
                          const std::vector<double>& timestamps_s);

/// The `Tr:` line of a KITTI calib.txt (the velodyne-to-camera transform). Throws IoError or
/// FormatError.
[[nodiscard]] Eigen::Matrix4d read_kitti_calibration_tr(const std::filesystem::path& path);

}  // namespace sgdicp
