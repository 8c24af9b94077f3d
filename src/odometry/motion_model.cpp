// The odometry's models of the motion between frames: the adaptive correspondence threshold and
// the motion model, and the covariance's softening over the sequence (odometry.hpp).
#include <cmath>

#include <Eigen/Geometry>

#include "odometry/rigid_motion.hpp"
#include "sgdicp/odometry/odometry.hpp"

namespace sgdicp {

using detail::rotation_angle_rad;

// ---- adaptive threshold

AdaptiveThreshold::AdaptiveThreshold(double initial_m, double min_motion_m)
    : initial_m_(initial_m), min_motion_m_(min_motion_m) {}

double AdaptiveThreshold::displacement_m(const Eigen::Matrix4d& T, double range_m) {
  const double theta = rotation_angle_rad(T);
  return T.topRightCorner<3, 1>().norm() + 2.0 * range_m * std::sin(theta / 2.0);
}

void AdaptiveThreshold::update(const Eigen::Matrix4d& deviation, double range_m) {
  const double d = displacement_m(deviation, range_m);
  if (!std::isfinite(d) || d <= min_motion_m_) return;
  sum_squares_ += d * d;
  ++samples_;
}

double AdaptiveThreshold::sigma_m() const {
  return samples_ == 0 ? initial_m_ : std::sqrt(sum_squares_ / static_cast<double>(samples_));
}

// ---- motion model

namespace {
// The least-squares c of b = c a, in [0, 1] (1 without data).
double carry(double ab, double aa) {
  return aa > 0.0 ? std::clamp(ab / aa, 0.0, 1.0) : 1.0;
}
}  // namespace

void MotionModel::update(const Eigen::Matrix4d& motion) {
  const Eigen::AngleAxisd turn(Eigen::Matrix3d(motion.topLeftCorner<3, 3>()));
  const Motion now{turn.angle() * turn.axis(), motion.topRightCorner<3, 1>()};
  if (!now.rotation.allFinite() || !now.translation_m.allFinite()) return;
  if (last_) {
    rotation_ab_ += last_->rotation.dot(now.rotation);
    rotation_aa_ += last_->rotation.squaredNorm();
    translation_ab_ += last_->translation_m.dot(now.translation_m);
    translation_aa_ += last_->translation_m.squaredNorm();
    ++pairs_;
  }
  last_ = now;
}

double MotionModel::rotation_carry() const noexcept {
  return pairs_ < kMinPairs ? 1.0 : carry(rotation_ab_, rotation_aa_);
}

double MotionModel::translation_carry() const noexcept {
  return pairs_ < kMinPairs ? 1.0 : carry(translation_ab_, translation_aa_);
}

Eigen::Matrix4d MotionModel::predicted() const {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  if (!last_) return T;
  const Eigen::Vector3d r = rotation_carry() * last_->rotation;
  const double angle = r.norm();
  if (angle > 0.0) T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(angle, r / angle).matrix();
  T.topRightCorner<3, 1>() = translation_carry() * last_->translation_m;
  return T;
}

// ---- the covariance's softening over the sequence

double SofteningMemory::next() const {
  if (measured_ < kWarmUp || since_measured_ + 1 >= kEvery) return 0.0;
  return last_measured_;
}

void SofteningMemory::record(double used) {
  if (next() > 0.0) {  // the frame used the memory's value: nothing measured
    ++since_measured_;
    return;
  }
  since_measured_ = 0;
  if (!(used > 0.0 && used <= 1.0)) return;  // no laplace covariance was made
  ++measured_;
  last_measured_ = used;
}

}  // namespace sgdicp
