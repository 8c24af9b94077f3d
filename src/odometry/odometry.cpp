#include "sgdicp/odometry/odometry.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "sgdicp/core/error.hpp"
#include "sgdicp/points/voxel_grid.hpp"
#include "sgdicp/registration/batch_icp.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"

namespace sgdicp {
namespace {

double now_ms() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

double rotation_angle_rad(const Eigen::Matrix4d& T) {
  const double c = std::clamp((T.topLeftCorner<3, 3>().trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

Eigen::Matrix4d rigid_inverse(const Eigen::Matrix4d& T) {
  Eigen::Matrix4d out = Eigen::Matrix4d::Identity();
  out.topLeftCorner<3, 3>() = T.topLeftCorner<3, 3>().transpose();
  out.topRightCorner<3, 1>() = -out.topLeftCorner<3, 3>() * T.topRightCorner<3, 1>();
  return out;
}

// The 99th percentile of the point distances from the sensor (at most 20 000 points looked at).
double range_percentile_m(const PointCloud& cloud) {
  if (cloud.empty()) return 0.0;
  const std::size_t stride = std::max<std::size_t>(1, cloud.size() / 20000);
  std::vector<double> ranges;
  for (std::size_t i = 0; i < cloud.size(); i += stride) {
    ranges.push_back((cloud.origin_m + cloud.points[i].cast<double>()).norm());
  }
  const auto k = static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(ranges.size() - 1));
  std::nth_element(ranges.begin(), ranges.begin() + k, ranges.end());
  return ranges[static_cast<std::size_t>(k)];
}

// Caps a length-per-iteration step (Adam, RMSProp) at a quarter of d_max in scaled units, the
// scale taken as the largest side of the map's box (the joint box of a registration is about
// that of the map, which holds the frame).
void cap_step(SgdSettings& s, const ReferenceIndex& map) {
  const auto type = s.optimizer.type;
  if (type != OptimizerType::adam && type != OptimizerType::rmsprop) return;
  const BoundingBox& box = map.bounding_box();
  const double scale_m = (box.max - box.min).maxCoeff();
  if (!(scale_m > 0.0)) return;
  const double d_max = s.max_correspondence_distance.unit == Distance::Unit::metres
                           ? s.max_correspondence_distance.value / scale_m
                           : s.max_correspondence_distance.value;
  s.optimizer.learning_rate = std::min(s.optimizer.learning_rate, 0.25 * d_max);
}

}  // namespace

// ---- settings

const std::vector<OdometrySetting>& odometry_settings_table() {
  using S = OdometrySettings;
  static const std::vector<OdometrySetting> table{
      {"max-range",
       false,
       {0.0, 1e6, true},
       "m",
       "Points farther from the sensor are dropped; the map keeps voxels within this radius",
       [](const S& s) { return s.max_range_m; },
       [](S& s, double v) { s.max_range_m = v; }},
      {"min-range",
       false,
       {0.0, 1e6},
       "m",
       "Points closer to the sensor are dropped",
       [](const S& s) { return s.min_range_m; },
       [](S& s, double v) { s.min_range_m = v; }},
      {"voxel-size",
       false,
       {0.0, 1e6},
       "m",
       "Map voxel side (frames thinned to half of it for the map, 1.5 times it for the "
       "registration); 0 = 1 % of the first frame's 99th-percentile range",
       [](const S& s) { return s.voxel_size_m; },
       [](S& s, double v) { s.voxel_size_m = v; }},
      {"max-points-per-voxel",
       true,
       {1.0, 10000.0},
       "",
       "Points kept per map voxel",
       [](const S& s) { return static_cast<double>(s.max_points_per_voxel); },
       [](S& s, double v) { s.max_points_per_voxel = static_cast<std::size_t>(v); }},
      {"initial-threshold",
       false,
       {0.0, 1e6},
       "m",
       "Correspondence threshold sigma before any motion is observed (d_max = 3 sigma); 0 = 2 "
       "voxels",
       [](const S& s) { return s.initial_threshold_m; },
       [](S& s, double v) { s.initial_threshold_m = v; }},
      {"min-motion",
       false,
       {0.0, 1e6},
       "m",
       "Deviations from the prediction below this do not adapt the threshold; 0 = voxel / 10",
       [](const S& s) { return s.min_motion_m; },
       [](S& s, double v) { s.min_motion_m = v; }},
      {"max-translation-per-frame",
       false,
       {0.0, 1e6, true},
       "m",
       "A registered motion between consecutive frames beyond this is a failed frame",
       [](const S& s) { return s.max_translation_per_frame_m; },
       [](S& s, double v) { s.max_translation_per_frame_m = v; }},
      {"max-rotation-per-frame",
       false,
       {0.0, 180.0, true},
       "deg",
       "A registered rotation between consecutive frames beyond this is a failed frame",
       [](const S& s) { return s.max_rotation_per_frame_deg; },
       [](S& s, double v) { s.max_rotation_per_frame_deg = v; }},
  };
  return table;
}

std::string OdometrySetting::spelled(SettingNames names) const {
  std::string out(name);
  if (names == SettingNames::cli) return "--" + out;
  std::replace(out.begin(), out.end(), '-', '_');
  return names == SettingNames::python ? out + "=" : out;
}

const OdometrySetting* find_odometry_setting(std::string_view name) {
  for (const auto& s : odometry_settings_table()) {
    if (detail::same_name(s.name, name)) return &s;
  }
  return nullptr;
}

void OdometrySettings::validate(SettingNames names) const {
  for (const auto& s : odometry_settings_table()) {
    const double v = s.get(*this);
    if (!std::isfinite(v) || !s.range.contains(v) || (s.integer && v != std::floor(v))) {
      throw InvalidSettingsError(s.spelled(names) + " " + format_number(v) + ": must be in " +
                                 s.range.to_string() + (s.unit.empty() ? "" : " ") +
                                 std::string(s.unit));
    }
  }
  if (min_range_m >= max_range_m) {
    throw InvalidSettingsError(find_odometry_setting("min-range")->spelled(names) + " " +
                               format_number(min_range_m) + ": must be below " +
                               find_odometry_setting("max-range")->spelled(names) + " " +
                               format_number(max_range_m));
  }
}

// ---- adaptive threshold

AdaptiveThreshold::AdaptiveThreshold(double initial_m, double min_motion_m, double max_range_m)
    : initial_m_(initial_m), min_motion_m_(min_motion_m), max_range_m_(max_range_m) {}

double AdaptiveThreshold::displacement_m(const Eigen::Matrix4d& T, double max_range_m) {
  const double theta = rotation_angle_rad(T);
  return T.topRightCorner<3, 1>().norm() + 2.0 * max_range_m * std::sin(theta / 2.0);
}

void AdaptiveThreshold::update(const Eigen::Matrix4d& deviation) {
  const double d = displacement_m(deviation, max_range_m_);
  if (!std::isfinite(d) || d <= min_motion_m_) return;
  sum_squares_ += d * d;
  ++samples_;
}

double AdaptiveThreshold::sigma_m() const {
  return samples_ == 0 ? initial_m_ : std::sqrt(sum_squares_ / static_cast<double>(samples_));
}

// ---- the pipeline

PointCloud crop_range(const PointCloud& cloud, double min_range_m, double max_range_m) {
  PointCloud out;
  out.origin_m = cloud.origin_m;
  out.points.reserve(cloud.size());
  for (const auto& p : cloud.points) {
    const double r = (cloud.origin_m + p.cast<double>()).norm();
    if (std::isfinite(r) && r >= min_range_m && r <= max_range_m) out.points.push_back(p);
  }
  return out;
}

namespace {
// Settings given with a method are used as they are (the CLI and Python apply the method's cost
// before their options, so that a --coarse-cost survives); settings that contradict the
// method's cost are a caller's mistake, not something to overwrite without a word.
void check_method_cost(const Method& method, const SgdSettings& sgd, const BatchSettings& batch) {
  if (!method.cost) return;
  const CostType given = method.solver == Solver::sgd ? sgd.cost : batch.cost;
  if (given == *method.cost) return;
  throw InvalidSettingsError("method '" + std::string(method.name) + "' registers with the " +
                             std::string(to_string(*method.cost)) + " cost but its settings have " +
                             std::string(to_string(given)) +
                             ": call apply_method_cost(method, sgd, batch) on them first");
}
}  // namespace

Odometry::Odometry(const OdometrySettings& settings, std::string_view method,
                   std::optional<SgdSettings> sgd, std::optional<BatchSettings> batch)
    : settings_(settings),
      method_(&method_from_string(method)),
      sgd_(sgd.value_or(SgdSettings{})),
      batch_(batch.value_or(BatchSettings{})) {
  settings_.validate();
  // The settings of the method's own solver decide: given, they are checked; not given, the
  // defaults get the method's cost.
  if (method_->solver == Solver::sgd ? sgd.has_value() : batch.has_value()) {
    check_method_cost(*method_, sgd_, batch_);
  } else {
    apply_method_cost(*method_, sgd_, batch_);
  }
  // The pipeline thins frames and map on its own voxel grid (settings_.voxel_size_m): the
  // registration step uses them as they are.
  sgd_.voxel_size_m = batch_.voxel_size_m = 0.0;
  sgd_.downsample_to = batch_.downsample_to = 0;
  sgd_.validate();
  batch_.validate();
}

void Odometry::start(const PointCloud& cropped) {
  voxel_size_m_ = settings_.voxel_size_m > 0.0 ? settings_.voxel_size_m
                                               : std::max(0.01 * range_percentile_m(cropped), 1e-3);
  const double initial =
      settings_.initial_threshold_m > 0.0 ? settings_.initial_threshold_m : 2.0 * voxel_size_m_;
  const double min_motion =
      settings_.min_motion_m > 0.0 ? settings_.min_motion_m : 0.1 * voxel_size_m_;
  map_.emplace(voxel_size_m_, settings_.max_points_per_voxel);
  threshold_.emplace(initial, min_motion, settings_.max_range_m);
}

Eigen::Matrix4d Odometry::predicted() const {
  return poses_.empty() ? Eigen::Matrix4d::Identity()
                        : Eigen::Matrix4d(poses_.back() * last_motion_);
}

Eigen::Matrix4d Odometry::skip_frame(const std::string& message) {
  FrameReport report;
  report.failed = true;
  report.message = message;
  report.T_first_frame = predicted();
  previous_points_.clear();
  return finish(report, PointCloud{}, now_ms());
}

Eigen::Matrix4d Odometry::register_frame(const PointCloud& frame) {
  const double started = now_ms();
  if (!poses_.empty() && !frame.empty() && frame.points == previous_points_) {
    return repeat_previous_pose(started);
  }
  previous_points_ = frame.points;
  const PointCloud cropped = crop_range(frame, settings_.min_range_m, settings_.max_range_m);
  if (!map_ && !cropped.empty()) start(cropped);
  FrameReport report;
  report.T_first_frame = predicted();
  if (cropped.empty()) {
    report.failed = true;
    report.message = "no point within the range limits";
    return finish(report, PointCloud{}, started);
  }
  PointCloud map_frame = voxel_downsample(cropped, 0.5 * voxel_size_m_);
  // What the cost needs of the map, estimated on this frame alone (a few thousand points, in its
  // own sensor frame, facing the sensor) rather than over the whole map every frame.
  const bool stochastic = method_->solver == Solver::sgd;
  const CostType cost = stochastic ? sgd_.cost : batch_.cost;
  const NeighborhoodSettings& neighborhood = stochastic ? sgd_.neighborhood : batch_.neighborhood;
  if (needs_covariances(cost)) {
    estimate_covariances(map_frame, neighborhood);
  } else if (needs_reference_normals(cost)) {
    estimate_normals(map_frame, neighborhood);
  }
  if (map_->empty()) {  // the first frame with points: it defines the map
    report.converged = true;
    report.message = poses_.empty() ? "first frame" : "map restarted (no map before)";
    return finish(report, map_frame, started);
  }
  const PointCloud source = voxel_downsample(map_frame, 1.5 * voxel_size_m_);
  report.source_points = source.size();
  const double sigma = threshold_->sigma_m();
  if (settings_.adaptive_threshold) report.threshold_m = 3.0 * sigma;

  const double build_start = now_ms();
  ReferenceIndex index(map_->points());
  prepare_reference(index, cost, neighborhood);
  report.index_build_ms = now_ms() - build_start;
  report.map_points = index.size();

  const Eigen::Matrix4d T_guess = report.T_first_frame;
  RegistrationResult r;
  try {
    r = align_to_map(source, index, sigma, T_guess);
  } catch (const InvalidInputError& e) {
    report.failed = true;
    report.message = std::string("registration refused the frame: ") + e.what();
    return finish(report, map_frame, started);
  }
  judge_registration(r, T_guess, report);
  return finish(report, map_frame, started);
}

Eigen::Matrix4d Odometry::repeat_previous_pose(double started_ms) {
  FrameReport report;
  report.repeated = report.converged = true;
  report.message = "repeated frame (identical to the previous one): the previous pose";
  report.T_first_frame = poses_.back();
  const Eigen::Matrix4d motion = last_motion_;
  const Eigen::Matrix4d T = finish(report, PointCloud{}, started_ms);
  last_motion_ = motion;  // the motion goes on; the frame says nothing about it
  return T;
}

RegistrationResult Odometry::align_to_map(const PointCloud& source, const ReferenceIndex& index,
                                          double sigma_m, const Eigen::Matrix4d& T_guess) const {
  if (method_->solver == Solver::sgd) {
    SgdSettings s = sgd_;
    if (settings_.adaptive_threshold) s.max_correspondence_distance = Distance::metres(3 * sigma_m);
    if (settings_.step_within_threshold) cap_step(s, index);
    return align(source, index, s, T_guess);
  }
  BatchSettings b = batch_;
  if (settings_.adaptive_threshold) b.max_correspondence_distance = Distance::metres(3 * sigma_m);
  return align_batch(source, index, b, T_guess);
}

void Odometry::judge_registration(const RegistrationResult& r, const Eigen::Matrix4d& T_guess,
                                  FrameReport& report) {
  report.converged = r.converged;
  report.iterations = r.iterations;
  report.inlier_ratio = r.inlier_ratio;
  report.inlier_rmse_m = r.inlier_rmse_m;
  report.message = r.message;

  const Eigen::Matrix4d motion = rigid_inverse(poses_.back()) * r.T_reference_source;
  const double step_m = motion.topRightCorner<3, 1>().norm();
  const double turn_deg = rotation_angle_rad(motion) * 180.0 / std::numbers::pi;
  if (!r.converged) {
    report.failed = true;
    report.message = "not converged: " + r.message;
  } else if (!r.T_reference_source.allFinite() || step_m > settings_.max_translation_per_frame_m ||
             turn_deg > settings_.max_rotation_per_frame_deg) {
    report.failed = true;
    report.message = "motion beyond the bounds per frame: " + format_number(step_m) + " m, " +
                     format_number(turn_deg) + " deg";
  } else {
    report.T_first_frame = r.T_reference_source;
    threshold_->update(rigid_inverse(T_guess) * r.T_reference_source);
  }
}

Eigen::Matrix4d Odometry::finish(FrameReport report, const PointCloud& map_frame,
                                 double started_ms) {
  report.index = poses_.size();
  const Eigen::Matrix4d T = report.T_first_frame;
  if (!poses_.empty()) last_motion_ = rigid_inverse(poses_.back()) * T;
  if (map_ && !map_frame.empty()) {
    // A failed frame is not added: its pose is a guess, and the map must stay consistent.
    if (!report.failed || map_->empty()) map_->add(transformed(map_frame, T));
    map_->remove_far_from(T.topRightCorner<3, 1>(), settings_.max_range_m);
  }
  poses_.push_back(T);
  report.time_ms = now_ms() - started_ms;
  reports_.push_back(std::move(report));
  return T;
}

}  // namespace sgdicp
