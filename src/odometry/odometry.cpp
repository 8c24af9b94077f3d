#include "sgdicp/odometry/odometry.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <new>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "odometry/rigid_motion.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/global/global_registration.hpp"
#include "sgdicp/metrics/metrics.hpp"
#include "sgdicp/points/voxel_grid.hpp"
#include "sgdicp/registration/batch_icp.hpp"
#include "sgdicp/registration/evaluation.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"

namespace sgdicp {

using detail::rigid_inverse;
using detail::rotation_angle_rad;

namespace {

double now_ms() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// What enters the map is the frame thinned to one centroid per this many map voxels; what is
// registered, per kSourceThinning. KISS-ICP thins the map's frame to half a voxel; a point here
// carries its own normal, and three quarters measured as precise or more at 10-15 % less time
// on every shared sequence and rate (a centroid of more points is a less noisy one; docs/design.md,
// *The map's frame at three quarters of a voxel*).
constexpr double kMapThinning = 0.75;
constexpr double kSourceThinning = 1.5;
// The derived voxel is this share of the frames' range (their 99th-percentile point distance),
// taken over the last kRangeFrames frames, and grows once theirs asks for kVoxelGrowth times it.
constexpr double kVoxelShare = 0.01;
constexpr std::size_t kRangeFrames = 5;
constexpr double kVoxelGrowth = 2.0;

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
  const double d_max = s.pairing.max_correspondence_distance.unit == Distance::Unit::metres
                           ? s.pairing.max_correspondence_distance.value / scale_m
                           : s.pairing.max_correspondence_distance.value;
  s.optimizer.learning_rate = std::min(s.optimizer.learning_rate, 0.25 * d_max);
}

}  // namespace

// ---- the pipeline

PointCloud crop_range(const PointCloud& cloud, double min_range_m, double max_range_m) {
  PointCloud out;
  out.origin_m = cloud.origin_m;
  out.points.reserve(cloud.size());
  const bool times = cloud.has_times();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const double r = (cloud.origin_m + cloud.points[i].cast<double>()).norm();
    if (!(std::isfinite(r) && r >= min_range_m && r <= max_range_m)) continue;
    out.points.push_back(cloud.points[i]);
    if (times) out.times_s.push_back(cloud.times_s[i]);
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
  // A batch method has no uncertainty to give (the CLI's --method refuses it the same way).
  check_method_uncertainty(*method_, sgd_);
  // The settings of the method's own solver decide: given, they are checked; not given, the
  // defaults get the method's cost.
  if (method_->solver == Solver::sgd ? sgd.has_value() : batch.has_value()) {
    check_method_cost(*method_, sgd_, batch_);
  } else {
    apply_method_cost(*method_, sgd_, batch_);
  }
  // The pipeline thins frames and map on its own voxel grid (settings_.voxel_size_m): the
  // registration step uses them as they are.
  sgd_.downsampling.voxel_size_m = batch_.downsampling.voxel_size_m = 0.0;
  sgd_.downsampling.downsample_to = batch_.downsampling.downsample_to = 0;
  sgd_.validate();
  batch_.validate();
}

void Odometry::start(double range_m) {
  ranges_m_.assign(1, range_m);
  voxel_size_m_ =
      settings_.voxel_size_m > 0.0 ? settings_.voxel_size_m : std::max(kVoxelShare * range_m, 1e-3);
  map_.emplace(voxel_size_m_, settings_.max_points_per_voxel);
  if (localizing_) build_fixed_map();
  start_threshold();
}

void Odometry::start_threshold() {
  const double initial =
      settings_.initial_threshold_m > 0.0 ? settings_.initial_threshold_m : 2.0 * voxel_size_m_;
  const double min_motion =
      settings_.min_motion_m > 0.0 ? settings_.min_motion_m : 0.1 * voxel_size_m_;
  threshold_.emplace(initial, min_motion);
}

Eigen::Matrix4d Odometry::predicted() const {
  if (poses_.empty()) return T_map_first_frame_.value_or(Eigen::Matrix4d::Identity());
  return poses_.back() * motion_.predicted();
}

PointCloud Odometry::map_cloud(double voxel_size_m) const {
  if (!map_ || map_->empty()) return {};
  const PointCloud& cloud = map_->points();
  return voxel_size_m > 0.0 ? voxel_downsample(cloud, voxel_size_m) : cloud;
}

void Odometry::keep_whole_map(double voxel_size_m) {
  if (!(voxel_size_m >= 0.0 && std::isfinite(voxel_size_m))) {
    throw InvalidSettingsError(
        "whole map: voxel size must be 0 (the odometry's) or positive, got " +
        format_number(voxel_size_m) + " m");
  }
  whole_map_voxel_m_ = voxel_size_m;
  whole_map_.reset();
}

// Made at the first registered frame after keep_whole_map, when the odometry's voxel is known; a
// map on the odometry's voxel follows it when it grows. A map whose voxel is no finer than the
// map frame's grid takes the map frame's centroids (a voxel's point is then the mean of its
// sub-voxels' centroids, not of their points): the full frame cost 6.5 ms more per 7-Scenes
// frame (24 -> 30 ms), the map frame nothing measurable.
void Odometry::add_to_whole_map(const PointCloud& cropped, const PointCloud& map_frame,
                                const Eigen::Matrix4d& T) {
  if (!whole_map_voxel_m_) return;
  const bool follows = *whole_map_voxel_m_ == 0.0;
  if (!whole_map_) whole_map_.emplace(follows ? voxel_size_m_ : *whole_map_voxel_m_);
  if (follows && voxel_size_m_ > whole_map_->voxel_size_m()) whole_map_->regrid(voxel_size_m_);
  const bool thinned_enough = whole_map_->voxel_size_m() >= kMapThinning * voxel_size_m_;
  whole_map_->add(thinned_enough ? map_frame : cropped, T);
}

std::size_t Odometry::lost_frames() const noexcept {
  return static_cast<std::size_t>(
      std::count_if(reports_.begin(), reports_.end(), [](const auto& r) { return r.failed; }));
}

std::size_t Odometry::doubtful_frames() const noexcept {
  return static_cast<std::size_t>(
      std::count_if(reports_.begin(), reports_.end(), [](const auto& r) { return r.doubtful; }));
}

std::size_t Odometry::recovered_frames() const noexcept {
  return static_cast<std::size_t>(
      std::count_if(reports_.begin(), reports_.end(), [](const auto& r) { return r.recovered; }));
}

Eigen::Matrix4d Odometry::skip_frame(const std::string& message) {
  return fail_frame(message, now_ms());
}

Eigen::Matrix4d Odometry::fail_frame(const std::string& message, double started_ms) {
  FrameReport report;
  report.failed = true;
  report.message = message;
  report.T_first_frame = predicted();
  previous_points_.clear();
  return finish(report, PointCloud{}, started_ms);
}

// Whatever goes wrong while one frame is registered is that frame's failure: a long run loses the
// frame, never the run (issue 54). The library's own errors say what was wrong with the frame;
// anything else is a bug and says so. Out of memory alone ends the run.
Eigen::Matrix4d Odometry::register_frame(const PointCloud& frame) {
  const double started = now_ms();
  try {
    return register_frame_unguarded(frame, started);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const Error& e) {
    return fail_frame(std::string("registration failed: ") + e.what(), started);
  } catch (const std::exception& e) {
    return fail_frame(std::string(kInternalError) + e.what(), started);
  }
}

Eigen::Matrix4d Odometry::register_frame_unguarded(const PointCloud& frame, double started) {
  if (!poses_.empty() && !frame.empty() && frame.points == previous_points_) {
    return repeat_previous_pose(started);
  }
  previous_points_ = frame.points;
  const PointCloud cropped = prepared_frame(frame);
  // The frame's range, which a derived voxel follows (start, grow_voxel); a set one needs none.
  const double range_m = settings_.voxel_size_m > 0.0 ? 0.0 : range_percentile_m(cropped);
  if (!map_ && !cropped.empty()) start(range_m);
  FrameReport report;
  report.T_first_frame = predicted();
  if (cropped.empty()) {
    report.failed = true;
    report.message = "no point within the range limits";
    return finish(report, PointCloud{}, started);
  }
  std::optional<VoxelBefore> grown;
  if (!map_->empty()) grown = grow_voxel(range_m);
  try {
    return register_on_grid(cropped, range_m, grown, report, started);
  } catch (...) {
    take_back(grown);  // the frame fails: a growth it asked for goes with it
    throw;
  }
}

Eigen::Matrix4d Odometry::register_on_grid(const PointCloud& cropped, double range_m,
                                           std::optional<VoxelBefore>& grown, FrameReport& report,
                                           double started) {
  const PointCloud map_frame = voxel_downsample(cropped, kMapThinning * voxel_size_m_, threads());
  if (map_->empty() && localizing_) {
    throw InvalidInputError("the map to localize in has no finite point");
  }
  if (map_->empty()) {  // the first frame with points: it defines the map
    report.converged = true;
    if (with_uncertainty()) report.covariance.setZero();  // exact: it defines the coordinates
    report.message = poses_.empty() ? "first frame" : "map restarted (no map before)";
    if (map_frame.has_times()) first_map_frame_ = map_frame;
    add_to_whole_map(cropped, map_frame, report.T_first_frame);
    return finish(report, map_frame, started);
  }
  const PointCloud source = voxel_downsample(map_frame, kSourceThinning * voxel_size_m_, threads());
  report.source_points = source.size();

  const double build_start = now_ms();
  // The map is its own index, with its surfaces: nothing is copied or built (docs/design.md).
  const ReferenceIndex index = map_->index();
  report.index_build_ms = now_ms() - build_start;
  report.map_points = index.size();
  check_map_surfaces(index);

  register_to_map(source, index, range_percentile_m(map_frame), report);
  if (report.failed) {
    // A lost frame says nothing of the scene (a scan of another sensor, say): a growth it asked
    // for is taken back (the frame does not enter the map), and its range is not kept.
    take_back(grown);
  } else {
    if (grown) {
      report.message += "; voxel " + format_number(grown->voxel_size_m) + " -> " +
                        format_number(voxel_size_m_) + " m (the frames' range grew)";
    }
    add_to_whole_map(cropped, map_frame, report.T_first_frame);
  }
  const Eigen::Matrix4d T = finish(report, map_frame, started);
  if (!report.failed) deskew_first_frames(map_frame);
  if (!report.failed) {
    ranges_m_.push_back(range_m);  // the next frame's range joins these
    if (ranges_m_.size() >= kRangeFrames) ranges_m_.erase(ranges_m_.begin());
  }
  return T;
}

void Odometry::take_back(std::optional<VoxelBefore>& grown) {
  if (!grown) return;
  map_ = std::move(grown->map);
  voxel_size_m_ = grown->voxel_size_m;
  threshold_ = grown->threshold;
  grown.reset();
}

// The map carries what the cost reads of it by construction (add_to_map): a map without it is a
// bug of ours, not the caller's (ReferenceIndex's own check names an API call the caller never
// made).
void Odometry::check_map_surfaces(const ReferenceIndex& index) const {
  try {
    check_reference_prepared(index, cost());
  } catch (const InvalidInputError&) {
    throw std::logic_error("the odometry map has lost its " +
                           std::string(needs_covariances(cost()) ? "covariances" : "normals") +
                           " (" + std::to_string(index.size()) + " points, voxel " +
                           format_number(voxel_size_m_) + " m)");
  }
}

// A repeat of a lost frame is lost as well: its pose is the prediction it was given.
Eigen::Matrix4d Odometry::repeat_previous_pose(double started_ms) {
  FrameReport report;
  report.repeated = true;
  report.failed = reports_.back().failed;
  report.converged = !report.failed;
  report.message = report.failed
                       ? "repeated frame (identical to the previous one, which was lost)"
                       : "repeated frame (identical to the previous one): the previous pose";
  report.T_first_frame = poses_.back();
  report.covariance = reports_.back().covariance;
  const MotionModel motion = motion_;
  const Eigen::Matrix4d T = finish(report, PointCloud{}, started_ms);
  motion_ = motion;  // the motion goes on; the frame says nothing about it
  return T;
}

RegistrationResult Odometry::align_to_map(const PointCloud& source, const ReferenceIndex& index,
                                          double sigma_m, const Eigen::Matrix4d& T_guess,
                                          FrameStart start) const {
  if (start == FrameStart::wide_basin || start == FrameStart::global) {
    // SGD-ICP as `sgdicp register` runs it: d_max 0.5 scaled and the point-to-point coarse
    // stage, the basin that registers scans moved 30 m / 30 deg (docs/design.md), whatever the
    // method; the map's surfaces serve the plane costs. The global start needs no guess: its
    // features propose, the same registration refines (docs/global.md).
    SgdSettings s = method_->solver == Solver::sgd ? sgd_ : SgdSettings{};
    if (method_->solver != Solver::sgd) s.cost = batch_.cost;
    s.pairing.max_correspondence_distance = SgdSettings{}.pairing.max_correspondence_distance;
    s.downsampling.voxel_size_m = 0.0;
    s.downsampling.downsample_to = 0;
    return start == FrameStart::global ? align_global(source, index, s)
                                       : align(source, index, s, T_guess);
  }
  if (method_->solver == Solver::sgd) {
    SgdSettings s = sgd_;
    if (settings_.adaptive_threshold)
      s.pairing.max_correspondence_distance = Distance::metres(3 * sigma_m);
    if (settings_.tracking_gauss_newton && is_default_step_rule(s.optimizer)) {
      s.optimizer = with_gauss_newton_steps(s.optimizer);
    }
    if (settings_.step_within_threshold) cap_step(s, index);
    // A softening the user gave is kept; otherwise the sequence's (SofteningMemory).
    if (s.uncertainty.softening == 0.0) s.uncertainty.softening = softening_.next();
    return align(source, index, s, T_guess);
  }
  BatchSettings b = batch_;
  if (settings_.adaptive_threshold)
    b.pairing.max_correspondence_distance = Distance::metres(3 * sigma_m);
  return align_batch(source, index, b, T_guess);
}

namespace {

constexpr std::size_t kOverlapFrames = 10;  // recent registered frames whose overlap is the norm
constexpr double kOverlapDrop = 0.5;        // a frame below this fraction of their median is off
// A registration below this fraction of their median is doubtful: the other starts are tried too,
// and the one with the highest overlap is the frame's pose. Registered frames score 0.91-1.0 of
// the median on every shared sequence, at every rate and reversed; a hand-held LiDAR scan 55 deg
// and 2.8 m on, registered 26 deg off, scored 0.57 (docs/odometry.md, step 7).
constexpr double kOverlapDoubt = 0.8;
constexpr std::size_t kOverlapPoints = 1000;  // frame points (evenly spread) its overlap looks at
// A wide-basin registration and the global one are the same pose within these.
constexpr double kConfirmDeg = 5.0;
constexpr double kConfirmVoxels = 2.0;
// A registration leaves some motion unconstrained below this constraint ratio (result.hpp): the
// wrong frames of the hand-held LiDAR cropped to 4-12 m (a floor and little else) scored
// 0.002-0.045, every frame of the uncropped hand-held LiDAR and 7-Scenes 0.13-0.37. It matters
// when the prediction is uncertain by more than kUnsureVoxels (the adaptive threshold's sigma:
// 13-25 voxels on the hand-held LiDAR, at most 1.2 on 7-Scenes at 30 Hz): along that motion the
// cost has no pull back to the truth and the frame keeps what its start gave it, at an overlap
// as high as the right pose's (docs/long-runs.md, *Doubtful frames*).
constexpr double kUnconstrainedBelow = 0.05;
constexpr double kUnsureVoxels = 2.0;

double median_of(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

std::string Odometry::judge(const RegistrationResult& r, double overlap, double range_m) const {
  if (r.global_init && !r.global_reliable) return r.message;  // "no reliable global solution"
  if (!r.converged) return "not converged: " + r.message;
  // The bounds hold per frame since the last registered one (lost frames in between).
  const auto frames = static_cast<double>(lost_since_good_ + 1);
  const double bound_m =
      settings_.max_translation_per_frame_m > 0.0 ? settings_.max_translation_per_frame_m : range_m;
  const Eigen::Matrix4d motion = rigid_inverse(T_last_good_) * r.T_reference_source;
  const double step_m = motion.topRightCorner<3, 1>().norm();
  const double turn_deg = rotation_angle_rad(motion) * 180.0 / std::numbers::pi;
  // Before a frame is registered in a fixed map there is no motion to bound.
  const bool bounded = registered_any_;
  if (!r.T_reference_source.allFinite() ||
      (bounded && (step_m > frames * bound_m ||
                   turn_deg > std::min(180.0, frames * settings_.max_rotation_per_frame_deg)))) {
    return "motion beyond the bounds per frame: " + format_number(step_m) + " m, " +
           format_number(turn_deg) + " deg";
  }
  if (!overlaps_.empty() && overlap < kOverlapDrop * median_of(overlaps_)) {
    return "overlap with the map " + format_number(overlap) + ", below half the last frames' " +
           format_number(median_of(overlaps_));
  }
  return "";
}

Odometry::Attempt Odometry::attempt(const PointCloud& source, const ReferenceIndex& index,
                                    double sigma_m, double range_m, const Eigen::Matrix4d& T_guess,
                                    FrameStart start) const {
  Attempt a;
  try {
    a.result = align_to_map(source, index, sigma_m, T_guess, start);
  } catch (const InvalidInputError& e) {
    a.why = std::string("registration refused the frame: ") + e.what();
    return a;
  }
  a.overlap =
      overlap_fraction(source, index, a.result.T_reference_source, voxel_size_m_, kOverlapPoints);
  a.why = judge(a.result, a.overlap, range_m);
  return a;
}

// Before any frame's overlap is known (the second frame), a registration with less than half
// of the frame on the map is doubtful: the hand-held LiDAR played backwards every 6th-8th scan
// slid its second frame 3 m along the corridor with 0.20-0.26, and every frame after it 2-3 m
// off against that map; registered right it overlaps 0.57-0.61, and the second frames of every
// shared sequence, rate and direction score 0.64-0.98 from the prediction.
double Odometry::doubtful_below() const {
  return overlaps_.empty() ? kOverlapDrop : kOverlapDoubt * median_of(overlaps_);
}

// Whether the global registration's answer confirms the wide basin's: the same pose within a
// few degrees and two map voxels ("" = confirmed). A global answer that is itself doubtful and
// overlaps the map less than the wide basin's disproves nothing: the wide basin's then stands on
// its own overlap (judged as any start's). The hand-held LiDAR played backwards every 7th-8th
// scan: in a corridor the global answer slid 2.3 m along it with 0.57 of the frame on the map, and
// the right wide-basin pose was thrown out for it.
std::string Odometry::unconfirmed(const Attempt& wide, const Attempt& global) const {
  // The global start's own reason follows in the frame's message ("global: ..."): not twice.
  if (!global.why.empty()) return "not confirmed by the global registration";
  const Eigen::Matrix4d& T_global = global.result.T_reference_source;
  const Eigen::Matrix4d& T_wide = wide.result.T_reference_source;
  const double turn_deg = rotation_error_geodesic(T_wide, T_global) * 180.0 / std::numbers::pi;
  const double shift_m = translation_error(T_wide, T_global);
  if (turn_deg <= kConfirmDeg && shift_m <= kConfirmVoxels * voxel_size_m_) return "";
  if (global.overlap < doubtful_below() && global.overlap < wide.overlap) return "";
  return "the global registration ends " + format_number(turn_deg) + " deg and " +
         format_number(shift_m) + " m from it";
}

// A derived voxel follows the frames' range upwards: taken from a first frame facing a wall or in
// a small room, it stays a share of a range the sensor soon exceeds. The hand-held LiDAR's first
// scan cropped to 5 m left 5 cm voxels for a 20 m scene: 4x the time and the memory, and the
// second scan, tracked with a threshold of 2 such voxels, 0.7 m off (docs/design.md, *A voxel
// that grows with the frames' range*). Before a frame is registered, its range joins those of the
// last registered frames (ranges_m_); the voxel grows when their median (the larger of two: a frame
// may see less than the sensor can, never farther than the scene; later at least half of the last
// 5) asks for twice the voxel or more. It never shrinks (a voxel too large costs precision, not
// time; shrinking and growing back would rebuild the map at every doorway), nor changes when the
// user set it. A frame that is then lost takes the growth back, and its range is not kept
// (register_frame): with two frames the second alone decides, and a KITTI scan as the second of
// 7-Scenes frames grew the voxel to 0.57 m and lost all the frames after it. Returns what it
// replaced (nothing when the voxel did not grow).
std::optional<Odometry::VoxelBefore> Odometry::grow_voxel(double range_m) {
  if (settings_.voxel_size_m > 0.0 || localizing_) return std::nullopt;  // a fixed map stays
  std::vector<double> ranges = ranges_m_;
  ranges.push_back(range_m);
  const double voxel_m = kVoxelShare * median_of(std::move(ranges));
  if (voxel_m < kVoxelGrowth * voxel_size_m_) return std::nullopt;
  VoxelBefore before{voxel_size_m_, std::move(*map_), *threshold_};
  // The map's points, with their surfaces, into the coarser grid (its bound per voxel applies).
  map_.emplace(voxel_m, settings_.max_points_per_voxel);
  map_->add(before.map.points());
  voxel_size_m_ = voxel_m;
  start_threshold();  // the derived threshold lengths are shares of the voxel
  return before;
}

void Odometry::register_to_map(const PointCloud& source, const ReferenceIndex& index,
                               double range_m, FrameReport& report) {
  const Eigen::Matrix4d T_prediction = report.T_first_frame;
  const double sigma = threshold_->sigma_m();
  if (settings_.adaptive_threshold) report.threshold_m = 3.0 * sigma;
  std::string rejected;
  std::optional<Attempt> global;  // the global start's answer, which also checks the wide basin's
  // An accepted registration whose overlap is doubtful, and its start: the pose unless a later
  // start overlaps more.
  std::optional<std::pair<Attempt, FrameStart>> doubtful;
  const auto reject = [&rejected](FrameStart start, const std::string& why) {
    rejected += (rejected.empty() ? "" : "; ") + std::string(enum_name(start)) + ": " + why;
  };
  // The global start comes before the wide basin: it costs less (0.13-0.18 s against 0.2-0.5 s
  // on the hand-held LiDAR) and its answer is what confirms the wide basin's anyway; the wide
  // basin runs when the global answer is not taken as it is.
  for (const FrameStart start : starts()) {
    const Eigen::Matrix4d T_guess = start == FrameStart::prediction ? T_prediction : T_last_good_;
    if (start == FrameStart::last_pose && T_guess.isApprox(T_prediction)) continue;
    Attempt a = attempt(source, index, sigma, range_m, T_guess, start);
    report.iterations += a.result.iterations;
    if (start == FrameStart::global) global = a;
    // The wide basin reaches 30 deg (docs/design.md); in a scene nearly symmetric under a half
    // turn it can also land on the mirror pose with a high overlap. Its answer stands only if
    // the global registration, which scores the competing poses, confirms it.
    if (a.why.empty() && start == FrameStart::wide_basin) a.why = unconfirmed(a, *global);
    if (a.why.empty() && a.overlap < doubtful_below()) {
      const std::string norm = overlaps_.empty()
                                   ? "half the frame, no earlier frame's to compare"
                                   : format_number(kOverlapDoubt) + " of the last frames'";
      reject(start, "overlap with the map " + format_number(a.overlap) + ", doubtful (below " +
                        norm + ")");
      if (!doubtful || a.overlap > doubtful->first.overlap) doubtful.emplace(std::move(a), start);
      continue;
    }
    if (a.why.empty()) {
      accept(a, start, T_prediction, range_m, rejected, report);
      return;
    }
    reject(start, a.why);
  }
  // Odometry takes the best of doubtful registrations (its map is the frames before); a fixed map
  // may not cover what the frame sees, and a frame it does not hold is lost, not placed. Taking
  // the best one with half the frame on the map placed 7-Scenes frames 364-464 (localized in a map
  // of frames 0-299, seeing 29-69 % of it at their reference poses) 0.18-0.95 m off, with
  // overlaps of 0.51-0.67 where the frames around scored 0.73-0.99.
  if (doubtful && !localizing_) {
    accept(doubtful->first, doubtful->second, T_prediction, range_m, rejected, report);
    return;
  }
  report.failed = true;
  report.message = "lost (" + rejected + ")";
}

void Odometry::accept(const Attempt& a, FrameStart start, const Eigen::Matrix4d& T_prediction,
                      double range_m, const std::string& rejected, FrameReport& report) {
  const RegistrationResult& r = a.result;
  report.converged = true;
  report.start = start;
  // The first frame in a fixed map without a pose starts from the global registration by plan.
  report.recovered = start != starts().front();
  report.overlap = a.overlap;
  report.inlier_ratio = r.inlier_ratio;
  report.inlier_rmse_m = r.inlier_rmse_m;
  report.constraint_ratio = r.constraint_ratio;
  if (rejected.empty()) {
    report.message = r.message;
  } else {
    report.message = (report.recovered ? "recovered from the " : "registered from the ") +
                     std::string(enum_name(start)) + " (" + rejected + ")";
  }
  const std::string doubt = doubt_of(a);
  report.doubtful = !doubt.empty();
  if (report.doubtful) report.message += "; doubtful: " + doubt;
  report.T_first_frame = r.T_reference_source;
  // The registration's own: of the pose relative to the map, in the frame's tangent space.
  if (with_uncertainty()) {
    report.covariance = r.covariance_se3;
    softening_.record(r.softening);
  }
  // Only registrations from the prediction sample how far it is off: a retry's start was not the
  // prediction.
  // A first pose given in a fixed map (fix_map) is the user's, not a prediction.
  if (!report.recovered && registered_any_)
    threshold_->update(rigid_inverse(T_prediction) * r.T_reference_source, range_m);
}

// Why a registration taken as the frame's pose may still be off ("" = no reason), from the state
// before the frame (the threshold and the overlaps are updated after).
std::string Odometry::doubt_of(const Attempt& a) const {
  const double sigma_m = threshold_->sigma_m();
  const bool unsure = threshold_->samples() == 0 || sigma_m > kUnsureVoxels * voxel_size_m_;
  if (a.result.constraint_ratio < kUnconstrainedBelow && unsure) {
    return "some motion is unconstrained by the scene (constraint ratio " +
           format_number(a.result.constraint_ratio) + ", below " +
           format_number(kUnconstrainedBelow) + ") while the prediction was uncertain (" +
           (threshold_->samples() == 0
                ? std::string("no motion seen yet")
                : "sigma " + format_number(sigma_m / voxel_size_m_) + " voxels") +
           ")";
  }
  if (a.overlap < doubtful_below()) {
    return "no start overlapped the map like the last frames (" + format_number(a.overlap) +
           "); the best was taken";
  }
  return "";
}

CostType Odometry::cost() const {
  return method_->solver == Solver::sgd ? sgd_.cost : batch_.cost;
}

bool Odometry::with_uncertainty() const {
  return method_->solver == Solver::sgd && sgd_.uncertainty.method != UncertaintyType::none;
}

std::size_t Odometry::threads() const {
  return method_->solver == Solver::sgd ? sgd_.num_threads : batch_.num_threads;
}

const NeighborhoodSettings& Odometry::neighborhood() const {
  return method_->solver == Solver::sgd ? sgd_.neighborhood : batch_.neighborhood;
}

void Odometry::add_to_map(const PointCloud& frame, const Eigen::Matrix4d& T) {
  // What the cost needs of the map, estimated on the frame in its own sensor frame (facing the
  // sensor) and only for the points the map admits: not over the whole map every frame (541 of
  // 581 ms a frame), nor for the points of full voxels (95 % of a Kinect frame's).
  const bool covariances = needs_covariances(cost());
  if (!covariances && !needs_reference_normals(cost())) {
    map_->add(transformed(frame, T));
    return;
  }
  // The frame (voxel_downsample's output) carries no surfaces yet: moving it moves points only.
  const std::vector<std::uint32_t> admitted = map_->admitted(transformed(frame, T));
  // On the registration's threads (--threads), as everything else of a frame: not on every core
  // whatever the setting (NeighborhoodSettings' own default), which made one thread two.
  NeighborhoodSettings surfaces = neighborhood();
  surfaces.num_threads = threads();
  map_->add(transformed(subset_with_surfaces(frame, admitted, surfaces, covariances), T));
}

Eigen::Matrix4d Odometry::finish(FrameReport report, const PointCloud& map_frame,
                                 double started_ms) {
  report.index = poses_.size();
  const Eigen::Matrix4d T = report.T_first_frame;
  // The map first: it is what can throw (register_frame then fails the frame, and nothing of the
  // state below has taken it in).
  if (map_ && !map_frame.empty() && !localizing_) {
    // A lost frame is not added: its pose is a guess, and the map must stay consistent.
    if (!report.failed || map_->empty()) add_to_map(map_frame, T);
    map_->remove_far_from(T.topRightCorner<3, 1>(), settings_.max_range_m);
  }
  if (!report.failed) {
    // The motion model learns only from two registered frames in a row: across lost frames the
    // motion per frame is unknown, so the next prediction is the pose itself.
    if (lost_since_good_ == 0 && registered_any_) {
      motion_.update(rigid_inverse(T_last_good_) * T);
    } else {
      motion_.forget_last();
    }
    T_last_good_ = T;
    registered_any_ = true;
    lost_since_good_ = 0;
    if (report.overlap > 0.0) {
      overlaps_.push_back(report.overlap);
      if (overlaps_.size() > kOverlapFrames) overlaps_.erase(overlaps_.begin());
    }
  } else if (!poses_.empty()) {
    ++lost_since_good_;
  }
  poses_.push_back(T);
  report.time_ms = now_ms() - started_ms;
  reports_.push_back(std::move(report));
  return T;
}

}  // namespace sgdicp
