#include "sgdicp/registration/deskew.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "sgdicp/core/error.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"

namespace sgdicp {
namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return s;
}

// The times' middle, and whether they span any time at all.
std::pair<double, bool> mid_time(std::span<const float> times_s) {
  const auto [lo, hi] = std::minmax_element(times_s.begin(), times_s.end());
  return {0.5 * (static_cast<double>(*lo) + static_cast<double>(*hi)), *hi > *lo};
}

void check_inputs(const PointCloud& source, std::span<const float> times_s,
                  const ReferenceIndex& reference) {
  if (times_s.size() != source.size()) {
    throw InvalidInputError("deskewing: " + std::to_string(times_s.size()) + " times for " +
                            std::to_string(source.size()) + " points");
  }
  if (!std::all_of(times_s.begin(), times_s.end(), [](float t) { return std::isfinite(t); })) {
    throw InvalidInputError("deskewing: a point's time is not finite");
  }
  if (!reference.cloud().has_normals()) {
    throw InvalidInputError(
        "deskewing: the reference carries no normals (give it them with "
        "prepare_reference and a plane cost)");
  }
}

// A seeded random subset of the finite points (all of them when fewer), in index order.
std::vector<std::size_t> sample_of(const PointCloud& source, const DeskewSettings& s) {
  std::vector<std::size_t> finite;
  for (std::size_t i = 0; i < source.size(); ++i) {
    if (source.points[i].allFinite()) finite.push_back(i);
  }
  if (finite.size() < 6) throw InvalidInputError("deskewing: fewer than 6 finite source points");
  if (finite.size() <= s.sample_points) return finite;
  std::mt19937_64 rng(s.seed);
  std::shuffle(finite.begin(), finite.end(), rng);
  finite.resize(s.sample_points);
  std::sort(finite.begin(), finite.end());
  return finite;
}

// The point-to-plane system of one iteration over the pose (right perturbation at T) and the
// velocity: q = T Exp(tau xi) p, dq/d(pose) = R [I | -[p']x] with p' = Exp(tau xi) p, and to
// first order dq/d(xi) = tau R R_tau [I | -[p]x]. Cauchy weights at a third of d_max.
struct System {
  Eigen::Matrix<double, 12, 12> H = Eigen::Matrix<double, 12, 12>::Zero();
  Eigen::Matrix<double, 12, 1> g = Eigen::Matrix<double, 12, 1>::Zero();
  std::vector<double> distances_m;
  double sum_squares = 0.0;
  std::size_t pairs = 0;
};

System build_system(const PointCloud& source, std::span<const float> times_s,
                    const std::vector<std::size_t>& sample, const ReferenceIndex& reference,
                    const DeskewedRegistration& r, double d_max_m) {
  System sys;
  const Eigen::Matrix3d R = r.T_reference_source.topLeftCorner<3, 3>();
  const Eigen::Vector3d t = r.T_reference_source.topRightCorner<3, 1>();
  const PointCloud& ref = reference.cloud();
  const auto max_sq = static_cast<float>(d_max_m * d_max_m);
  const double c = d_max_m / 3.0;
  for (const std::size_t i : sample) {
    const double tau = static_cast<double>(times_s[i]) - r.mid_time_s;
    const Eigen::Matrix4d motion = exp_twist(tau * r.velocity);
    const Eigen::Vector3d p = source.origin_m + source.points[i].cast<double>();
    const Eigen::Vector3d p_mid = motion.topLeftCorner<3, 3>() * p + motion.topRightCorner<3, 1>();
    const Eigen::Vector3d q = R * p_mid + t;
    const auto n = reference.nearest((q - ref.origin_m).cast<float>(), max_sq);
    if (!n) continue;
    const Eigen::Vector3d y = ref.origin_m + ref.points[n->index].cast<double>();
    const Eigen::Vector3d normal = ref.normals[n->index].cast<double>();
    const double e = normal.dot(q - y);
    const double w = 1.0 / (1.0 + (e / c) * (e / c));
    Eigen::Matrix<double, 1, 12> J;
    const Eigen::RowVector3d nR = normal.transpose() * R;
    J.segment<3>(0) = nR;
    J.segment<3>(3) = -nR * skew(p_mid);
    const Eigen::RowVector3d nRR = tau * nR * motion.topLeftCorner<3, 3>();
    J.segment<3>(6) = nRR;
    J.segment<3>(9) = -nRR * skew(p);
    sys.H.noalias() += w * J.transpose() * J;
    sys.g.noalias() += w * e * J.transpose();
    sys.distances_m.push_back(std::sqrt(static_cast<double>(n->squared_distance)));
    sys.sum_squares += e * e;
    ++sys.pairs;
  }
  return sys;
}

double median_of(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

Eigen::Matrix4d exp_twist(const Twist& xi) {
  const Eigen::Vector3d v = xi.head<3>();
  const Eigen::Vector3d w = xi.tail<3>();
  const double theta = w.norm();
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  if (theta < 1e-9) {
    T.topRightCorner<3, 1>() = v;
    return T;
  }
  const Eigen::Matrix3d W = skew(w);
  T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(theta, w / theta).toRotationMatrix();
  const Eigen::Matrix3d V = Eigen::Matrix3d::Identity() +
                            (1.0 - std::cos(theta)) / (theta * theta) * W +
                            (theta - std::sin(theta)) / (theta * theta * theta) * W * W;
  T.topRightCorner<3, 1>() = V * v;
  return T;
}

Twist log_twist(const Eigen::Matrix4d& T) {
  const Eigen::AngleAxisd turn(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
  const double theta = turn.angle();
  const Eigen::Vector3d w = theta * turn.axis();
  Eigen::Matrix3d V_inverse = Eigen::Matrix3d::Identity();
  if (theta > 1e-9) {
    const Eigen::Matrix3d W = skew(w);
    V_inverse += -0.5 * W + (1.0 - theta * std::sin(theta) / (2.0 * (1.0 - std::cos(theta)))) /
                                (theta * theta) * W * W;
  }
  Twist xi;
  xi.head<3>() = V_inverse * T.topRightCorner<3, 1>();
  xi.tail<3>() = w;
  return xi;
}

PointCloud deskewed_by_motion(const PointCloud& frame, const Eigen::Matrix4d& sweep_motion) {
  if (!frame.has_times()) return frame;
  const auto [lo, hi] = std::minmax_element(frame.times_s.begin(), frame.times_s.end());
  if (!(*hi > *lo)) return frame;
  const double span = static_cast<double>(*hi) - static_cast<double>(*lo);
  const Twist xi = log_twist(sweep_motion);
  PointCloud out = frame;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double s = (static_cast<double>(frame.times_s[i]) - static_cast<double>(*lo)) / span;
    const Eigen::Matrix4d T = exp_twist((s - 0.5) * xi);
    const Eigen::Vector3d p = frame.origin_m + frame.points[i].cast<double>();
    const Eigen::Vector3d moved = T.topLeftCorner<3, 3>() * p + T.topRightCorner<3, 1>();
    out.points[i] = (moved - frame.origin_m).cast<float>();
  }
  return out;
}

std::vector<float> azimuth_times_s(const PointCloud& frame, double sweep_s) {
  std::vector<float> out;
  out.reserve(frame.size());
  for (const Eigen::Vector3f& point : frame.points) {
    const Eigen::Vector3d p = frame.origin_m + point.cast<double>();
    const double s = 0.5 * (1.0 - std::atan2(p.y(), p.x()) / std::numbers::pi);
    out.push_back(static_cast<float>(s * sweep_s));
  }
  return out;
}

Eigen::Matrix4d pose_at(const DeskewedRegistration& r, double t_s) {
  return r.T_reference_source * exp_twist((t_s - r.mid_time_s) * r.velocity);
}

DeskewedRegistration align_deskewed(const PointCloud& source, std::span<const float> times_s,
                                    const ReferenceIndex& reference, const Eigen::Matrix4d& T_init,
                                    const DeskewSettings& settings) {
  check_inputs(source, times_s, reference);
  DeskewedRegistration r;
  r.T_reference_source = T_init;
  const auto [mid, spans] = mid_time(times_s);
  r.mid_time_s = mid;
  if (!spans) {
    r.converged = true;
    r.message = "the sweep's times are all equal: a rigid sweep, nothing to deskew";
    return r;
  }
  const std::vector<std::size_t> sample = sample_of(source, settings);
  double d_max = settings.max_correspondence_distance_m;
  for (r.iterations = 1; r.iterations <= settings.max_iterations; ++r.iterations) {
    const System sys = build_system(source, times_s, sample, reference, r, d_max);
    if (sys.pairs < 12) {
      r.message = "deskewing: fewer than 12 pairs within " + std::to_string(d_max) + " m";
      return r;
    }
    r.inlier_rmse_m = std::sqrt(sys.sum_squares / static_cast<double>(sys.pairs));
    // Levenberg-Marquardt's scaled damping keeps a direction the sweep leaves free in place.
    Eigen::Matrix<double, 12, 12> A = sys.H;
    A.diagonal() += 1e-3 * sys.H.diagonal() + Eigen::Matrix<double, 12, 1>::Constant(1e-9);
    const Eigen::Matrix<double, 12, 1> step = A.ldlt().solve(-sys.g);
    if (!step.allFinite()) {
      r.message = "deskewing: the system has no solution";
      return r;
    }
    r.T_reference_source = r.T_reference_source * exp_twist(step.head<6>());
    r.velocity += step.tail<6>();
    d_max = std::min(d_max, std::max(3.0 * median_of(sys.distances_m), 1e-3));
    const double sweep_s =
        2.0 *
        (static_cast<double>(*std::max_element(times_s.begin(), times_s.end())) - r.mid_time_s);
    // Converged when the step moves no point of the sweep by more than 0.1 mm (at 100 m).
    const double moved = step.head<3>().norm() + 100.0 * step.segment<3>(3).norm() +
                         sweep_s * (step.segment<3>(6).norm() + 100.0 * step.tail<3>().norm());
    if (moved < 1e-4) {
      r.converged = true;
      r.message = "converged";
      return r;
    }
  }
  r.iterations = settings.max_iterations;
  r.message =
      "deskewing: not converged within " + std::to_string(settings.max_iterations) + " iterations";
  return r;
}

DeskewedRegistration align_deskewed(const PointCloud& source, std::span<const float> times_s,
                                    const PointCloud& reference, const Eigen::Matrix4d& T_init,
                                    const DeskewSettings& settings) {
  ReferenceIndex index = reference_index_for(reference, SgdSettings{});
  prepare_reference(index, CostType::point_to_plane);
  return align_deskewed(source, times_s, index, T_init, settings);
}

PointCloud deskewed_in_reference(const PointCloud& source, std::span<const float> times_s,
                                 const DeskewedRegistration& r) {
  if (times_s.size() != source.size()) {
    throw InvalidInputError("deskewing: " + std::to_string(times_s.size()) + " times for " +
                            std::to_string(source.size()) + " points");
  }
  PointCloud out;
  out.points.reserve(source.size());
  for (std::size_t i = 0; i < source.size(); ++i) {
    const Eigen::Matrix4d T = pose_at(r, static_cast<double>(times_s[i]));
    const Eigen::Vector3d p = source.origin_m + source.points[i].cast<double>();
    out.points.push_back((T.topLeftCorner<3, 3>() * p + T.topRightCorner<3, 1>()).cast<float>());
  }
  return out;
}

}  // namespace sgdicp
