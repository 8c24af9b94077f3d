#include "sgdicp/metrics/trajectory_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numbers>
#include <string>

#include <Eigen/LU>
#include <Eigen/SVD>

#include "sgdicp/core/error.hpp"

namespace sgdicp {
namespace {

Eigen::Matrix4d inverse(const Eigen::Matrix4d& T) {
  Eigen::Matrix4d out = Eigen::Matrix4d::Identity();
  out.topLeftCorner<3, 3>() = T.topLeftCorner<3, 3>().transpose();
  out.topRightCorner<3, 1>() = -out.topLeftCorner<3, 3>() * T.topRightCorner<3, 1>();
  return out;
}

double angle_deg(const Eigen::Matrix4d& T) {
  const double c = std::clamp((T.topLeftCorner<3, 3>().trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / std::numbers::pi;
}

// E = (G_i^-1 G_j)^-1 (P_i^-1 P_j).
Eigen::Matrix4d relative_error(const std::vector<Eigen::Matrix4d>& estimate,
                               const std::vector<Eigen::Matrix4d>& truth, std::size_t i,
                               std::size_t j) {
  return inverse(inverse(truth[i]) * truth[j]) * (inverse(estimate[i]) * estimate[j]);
}

void check_same_size(const std::vector<Eigen::Matrix4d>& estimate,
                     const std::vector<Eigen::Matrix4d>& truth, std::size_t at_least) {
  if (estimate.size() != truth.size()) {
    throw InvalidInputError("trajectory metrics: " + std::to_string(estimate.size()) +
                            " estimated poses against " + std::to_string(truth.size()) +
                            " ground-truth poses");
  }
  if (estimate.size() < at_least) {
    throw InvalidInputError("trajectory metrics: " + std::to_string(estimate.size()) +
                            " poses, need at least " + std::to_string(at_least));
  }
}

Eigen::Vector3d position(const Eigen::Matrix4d& T) {
  return T.topRightCorner<3, 1>();
}

}  // namespace

ErrorStatistics ErrorStatistics::of(std::vector<double> values) {
  ErrorStatistics s;
  s.count = values.size();
  if (values.empty()) return s;
  double sum = 0.0, squares = 0.0;
  for (const double v : values) {
    sum += v;
    squares += v * v;
    s.max = std::max(s.max, v);
  }
  const auto n = static_cast<double>(values.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(squares / n);
  std::sort(values.begin(), values.end());
  const std::size_t h = values.size() / 2;
  s.median = values.size() % 2 ? values[h] : 0.5 * (values[h - 1] + values[h]);
  return s;
}

RelativePoseErrors relative_pose_errors(const std::vector<Eigen::Matrix4d>& estimate,
                                        const std::vector<Eigen::Matrix4d>& truth,
                                        std::size_t delta) {
  if (delta == 0) throw InvalidInputError("relative pose error: delta must be at least 1 frame");
  check_same_size(estimate, truth, delta + 1);
  RelativePoseErrors out;
  out.delta = delta;
  for (std::size_t i = 0; i + delta < estimate.size(); ++i) {
    const Eigen::Matrix4d E = relative_error(estimate, truth, i, i + delta);
    out.translation_m.push_back(position(E).norm());
    out.rotation_deg.push_back(angle_deg(E));
  }
  out.translation = ErrorStatistics::of(out.translation_m);
  out.rotation = ErrorStatistics::of(out.rotation_deg);
  return out;
}

double path_length_m(const std::vector<Eigen::Matrix4d>& poses) {
  double length = 0.0;
  for (std::size_t i = 1; i < poses.size(); ++i) {
    length += (position(poses[i]) - position(poses[i - 1])).norm();
  }
  return length;
}

std::optional<KittiDrift> kitti_drift(const std::vector<Eigen::Matrix4d>& estimate,
                                      const std::vector<Eigen::Matrix4d>& truth) {
  check_same_size(estimate, truth, 2);
  std::vector<double> distance(truth.size(), 0.0);  // along the ground truth, from frame 0
  for (std::size_t i = 1; i < truth.size(); ++i) {
    distance[i] = distance[i - 1] + (position(truth[i]) - position(truth[i - 1])).norm();
  }
  if (distance.back() < kKittiSegmentLengths_m.front()) return std::nullopt;
  constexpr std::size_t kStepFrames = 10;  // the devkit's step_size
  double t_sum = 0.0, r_sum = 0.0;
  std::size_t segments = 0;
  for (std::size_t first = 0; first < truth.size(); first += kStepFrames) {
    for (const double length : kKittiSegmentLengths_m) {
      // The devkit's lastFrameFromSegmentLength: the first frame beyond first + length.
      const auto it = std::upper_bound(distance.begin() + static_cast<std::ptrdiff_t>(first),
                                       distance.end(), distance[first] + length);
      if (it == distance.end()) continue;
      const auto last = static_cast<std::size_t>(it - distance.begin());
      const Eigen::Matrix4d E = relative_error(estimate, truth, first, last);
      t_sum += position(E).norm() / length;
      r_sum += angle_deg(E) / length;
      ++segments;
    }
  }
  if (segments == 0) return std::nullopt;
  const auto n = static_cast<double>(segments);
  return KittiDrift{100.0 * t_sum / n, r_sum / n, segments};
}

Eigen::Matrix4d rigid_alignment(const std::vector<Eigen::Vector3d>& from,
                                const std::vector<Eigen::Vector3d>& to) {
  if (from.empty() || from.size() != to.size()) {
    throw InvalidInputError("rigid alignment: needs the same number (at least 1) of points");
  }
  Eigen::Vector3d mean_from = Eigen::Vector3d::Zero(), mean_to = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < from.size(); ++i) {
    mean_from += from[i];
    mean_to += to[i];
  }
  mean_from /= static_cast<double>(from.size());
  mean_to /= static_cast<double>(to.size());
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();  // Umeyama's Sigma_xy (up to 1/n)
  for (std::size_t i = 0; i < from.size(); ++i) {
    cross += (to[i] - mean_to) * (from[i] - mean_from).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) S(2, 2) = -1.0;
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = svd.matrixU() * S * svd.matrixV().transpose();
  T.topRightCorner<3, 1>() = mean_to - T.topLeftCorner<3, 3>() * mean_from;
  return T;
}

AbsoluteTrajectoryError absolute_trajectory_error(const std::vector<Eigen::Matrix4d>& estimate,
                                                  const std::vector<Eigen::Matrix4d>& truth) {
  check_same_size(estimate, truth, 1);
  std::vector<Eigen::Vector3d> p, q;
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    p.push_back(position(estimate[i]));
    q.push_back(position(truth[i]));
  }
  AbsoluteTrajectoryError out;
  out.T_truth_estimate = rigid_alignment(p, q);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector3d moved = out.T_truth_estimate.topLeftCorner<3, 3>() * p[i] +
                                  out.T_truth_estimate.topRightCorner<3, 1>();
    out.position_error_m.push_back((moved - q[i]).norm());
  }
  out.error = ErrorStatistics::of(out.position_error_m);
  return out;
}

EndDrift end_drift(const std::vector<Eigen::Matrix4d>& estimate,
                   const std::vector<Eigen::Matrix4d>& truth) {
  check_same_size(estimate, truth, 1);
  const Eigen::Matrix4d E = relative_error(estimate, truth, 0, estimate.size() - 1);
  EndDrift out;
  out.translation_m = position(E).norm();
  out.rotation_deg = angle_deg(E);
  out.path_length_m = path_length_m(truth);
  out.translation_percent =
      out.path_length_m > 0.0 ? 100.0 * out.translation_m / out.path_length_m : 0.0;
  return out;
}

std::vector<Eigen::Matrix4d> relative_to_first(const std::vector<Eigen::Matrix4d>& poses) {
  std::vector<Eigen::Matrix4d> out;
  if (poses.empty()) return out;
  const Eigen::Matrix4d first_inverse = inverse(poses.front());
  for (const auto& T : poses) out.push_back(first_inverse * T);
  return out;
}

std::vector<std::optional<std::size_t>> associate_timestamps(const std::vector<double>& frames_s,
                                                             const std::vector<double>& truth_s,
                                                             double max_difference_s) {
  if (!std::isfinite(max_difference_s) || max_difference_s < 0.0) {
    throw InvalidInputError(
        "timestamp association: the largest difference must be finite and "
        ">= 0 s");
  }
  for (std::size_t k = 0; k < truth_s.size(); ++k) {
    if (!std::isfinite(truth_s[k]) || (k > 0 && truth_s[k] < truth_s[k - 1])) {
      throw InvalidInputError("timestamp association: ground-truth time " + std::to_string(k) +
                              " is not finite or not in ascending order");
    }
  }
  std::vector<std::optional<std::size_t>> out;
  out.reserve(frames_s.size());
  for (const double t : frames_s) {
    if (!std::isfinite(t))
      throw InvalidInputError("timestamp association: a frame time is not finite");
    const auto after = std::lower_bound(truth_s.begin(), truth_s.end(), t);
    std::optional<std::size_t> best;
    double best_difference = max_difference_s;
    for (auto it = after == truth_s.begin() ? after : std::prev(after);
         it != truth_s.end() && it <= after; ++it) {
      if (std::abs(*it - t) <= best_difference) {
        best = static_cast<std::size_t>(it - truth_s.begin());
        best_difference = std::abs(*it - t);
      }
    }
    out.push_back(best);
  }
  return out;
}

}  // namespace sgdicp
