#pragma once
// Errors of an estimated trajectory against a ground truth with the same frames (pose k of both
// = frame k; poses T_world_frame, any world frame per trajectory). docs/odometry.md says which
// convention each number follows:
//   - relative pose error (RPE) between frames k and k + delta: E = (G_k^-1 G_{k+d})^-1
//     (P_k^-1 P_{k+d}), its translation |t_E| (m) and rotation angle (deg), as evo_rpe / the TUM
//     benchmark's evaluate_rpe.py with delta in frames;
//   - KITTI drift: the same E over segments of 100, 200, ..., 800 m of ground-truth path,
//     started every 10 frames, |t_E| / length (%) and angle / length (deg/m), averaged over all
//     segments, as the KITTI odometry devkit (evaluate_odometry.cpp);
//   - absolute trajectory error (ATE): RMSE of the positions after the rigid (rotation and
//     translation, no scale) least-squares alignment of the estimated positions onto the ground
//     truth (Horn 1987 / Umeyama 1991), as evo_ape without --correct_scale;
//   - end drift: E between the first and the last frame, in m, deg and % of the path length.
#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace sgdicp {

struct ErrorStatistics {
  double rmse = 0.0, mean = 0.0, median = 0.0, max = 0.0;
  std::size_t count = 0;
  [[nodiscard]] static ErrorStatistics of(std::vector<double> values);
};

struct RelativePoseErrors {
  std::size_t delta = 1;
  std::vector<double> translation_m;  ///< per pair (k, k + delta)
  std::vector<double> rotation_deg;
  ErrorStatistics translation, rotation;
};

struct KittiDrift {
  double translation_percent = 0.0;  ///< mean over segments of |t_E| / length * 100
  double rotation_deg_per_m = 0.0;   ///< mean over segments of angle(E) / length
  std::size_t segments = 0;
};

struct AbsoluteTrajectoryError {
  Eigen::Matrix4d T_truth_estimate = Eigen::Matrix4d::Identity();  ///< the alignment
  std::vector<double> position_error_m;  ///< per frame, after the alignment
  ErrorStatistics error;
};

struct EndDrift {
  double translation_m = 0.0;
  double rotation_deg = 0.0;
  double path_length_m = 0.0;        ///< of the ground truth
  double translation_percent = 0.0;  ///< translation_m / path_length_m * 100 (0 for no path)
};

/// Throws InvalidInputError unless both have the same number of poses (at least delta + 1).
[[nodiscard]] RelativePoseErrors relative_pose_errors(const std::vector<Eigen::Matrix4d>& estimate,
                                                      const std::vector<Eigen::Matrix4d>& truth,
                                                      std::size_t delta = 1);

/// The devkit's segment lengths, metres.
inline constexpr std::array<double, 8> kKittiSegmentLengths_m{100, 200, 300, 400,
                                                              500, 600, 700, 800};

/// Empty when the ground-truth path is shorter than the shortest segment (100 m).
[[nodiscard]] std::optional<KittiDrift> kitti_drift(const std::vector<Eigen::Matrix4d>& estimate,
                                                    const std::vector<Eigen::Matrix4d>& truth);

/// The rigid T minimising sum |q_k - T p_k|^2 (Umeyama 1991 without scale, with the reflection
/// guard). Needs at least one pair; fewer than 3 non-collinear pairs leave rotation about the
/// line free (any minimiser is returned).
[[nodiscard]] Eigen::Matrix4d rigid_alignment(const std::vector<Eigen::Vector3d>& from,
                                              const std::vector<Eigen::Vector3d>& to);

[[nodiscard]] AbsoluteTrajectoryError absolute_trajectory_error(
    const std::vector<Eigen::Matrix4d>& estimate, const std::vector<Eigen::Matrix4d>& truth);

[[nodiscard]] EndDrift end_drift(const std::vector<Eigen::Matrix4d>& estimate,
                                 const std::vector<Eigen::Matrix4d>& truth);

/// Ground-truth path length: the sum of the distances between consecutive positions, metres.
[[nodiscard]] double path_length_m(const std::vector<Eigen::Matrix4d>& poses);

/// For each frame timestamp, the index of the ground-truth pose nearest in time, if one lies
/// within max_difference_s (the TUM benchmark's associate.py matches within 0.02 s), else
/// nullopt. Seconds; truth_s must be sorted ascending (InvalidInputError otherwise, and for a
/// non-finite time or a negative or non-finite max_difference_s).
[[nodiscard]] std::vector<std::optional<std::size_t>> associate_timestamps(
    const std::vector<double>& frames_s, const std::vector<double>& truth_s,
    double max_difference_s = 0.02);

/// The poses re-expressed from the first one: T_0^-1 T_k (the first becomes the identity).
[[nodiscard]] std::vector<Eigen::Matrix4d> relative_to_first(
    const std::vector<Eigen::Matrix4d>& poses);

}  // namespace sgdicp
