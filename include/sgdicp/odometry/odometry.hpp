#pragma once
// Odometry over a sequence of scans: each frame (a cloud in its sensor's frame) is registered to
// a local map of the frames before it, giving its pose T_first_frame (maps the frame's points
// into the first frame's coordinates). The parts, after KISS-ICP (Vizzo et al., RA-L 2023):
//   - a local VoxelMap (voxel_map.hpp), bounded in points per voxel and in radius around the
//     sensor, updated incrementally;
//   - a prediction from the last frame-to-frame motion, with the share of its rotation and of
//     its translation that carried over between the registered frames (MotionModel);
//   - a correspondence threshold adapted to the observed deviation of the registrations from
//     the prediction (AdaptiveThreshold), measured at the frame's own range;
//   - any method of methods.hpp (SGD-ICP by default) as the registration step.
// A registration is judged before its pose is taken (converged, within the bounds per frame,
// an overlap with the map like the frames before); one that fails is retried from the last
// good pose, with no guess (the global registration) and with SGD-ICP's wide basin (confirmed by
// the global answer), and one whose overlap is doubtful (below 0.8 of the recent frames', or
// half the frame before any is known) is compared with theirs: the highest overlap is the
// pose. A frame no start registers is lost: it gets the predicted pose and touches
// neither the map nor the motion model.
// docs/odometry.md.
#include <array>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/core/enum_names.hpp"
#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/odometry/voxel_map.hpp"
#include "sgdicp/odometry/whole_map.hpp"
#include "sgdicp/registration/methods.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp {

class ReferenceIndex;       // nearest_neighbor.hpp
struct RegistrationResult;  // result.hpp

/// Motion compensation of each frame (OdometrySettings::deskew).
enum class DeskewMode {
  automatic,  ///< when the frame carries times (PointCloud::times_s)
  none,       ///< never
  azimuth,    ///< times from each point's azimuth (azimuth_times_s: KITTI's sweeps)
};
inline constexpr std::array<EnumName<DeskewMode>, 3> kDeskewModeNames{{
    {DeskewMode::automatic, "auto"},
    {DeskewMode::none, "none"},
    {DeskewMode::azimuth, "azimuth"},
}};
constexpr const auto& enum_names(DeskewMode) {
  return kDeskewModeNames;
}
constexpr std::string_view enum_noun(DeskewMode) {
  return "deskew mode";
}

/// The settings of the odometry pipeline (the registration step has its own: SgdSettings or
/// BatchSettings). Lengths with a 0 default are derived from the first frame's extent (auto).
struct OdometrySettings {
  /// Points farther from the sensor are dropped; the map keeps voxels within this radius of the
  /// current pose.
  double max_range_m = 100.0;
  /// Points closer to the sensor are dropped (the vehicle, the operator's hand).
  double min_range_m = 0.0;
  /// Side of the map's voxels; 0 = 1 % of the first frame's range (its 99th percentile point
  /// distance from the sensor, at most max_range_m): 0.5-0.8 m on KITTI, 3-4 cm on a Kinect;
  /// grown (the map regridded) when the second frame or half the last 5 see twice as far.
  /// Frames are thinned to one point per 0.75 voxel for the map and per 1.5 voxels for the
  /// registration.
  double voxel_size_m = 0.0;
  /// Points kept per voxel of the map, at most; no two of a voxel closer than
  /// voxel_size_m / sqrt(max_points_per_voxel), so a place seen again adds nothing once covered.
  std::size_t max_points_per_voxel = 20;
  /// Correspondence threshold sigma before any motion has been observed; 0 = 2 voxels. The
  /// registration's d_max is 3 sigma.
  double initial_threshold_m = 0.0;
  /// Deviations from the prediction smaller than this are not samples of the threshold (a
  /// standing sensor would shrink it to nothing); 0 = voxel / 10.
  double min_motion_m = 0.0;
  /// Physical bounds of the motion between consecutive frames: a registration beyond either is
  /// rejected (and retried). Translation: 0 = the frame's own range (the distance within which
  /// 99 % of its points lie): a sensor does not move farther than it sees between two frames,
  /// whatever the frame rate. A bound in metres assumes one: 5 m (180 km/h at 10 Hz) rejected
  /// the correct 5.2-5.9 m steps of a hand-held LiDAR read every seventh scan and lost those
  /// frames. No bound on rotation by default: a hand-held sensor turns 54 deg between scans at
  /// 1 Hz and 62 deg at 0.67 Hz (../shared/data/balm_handheld_lidar), and a 45 deg bound rejected
  /// those correct registrations and lost the track; a wrong one is caught by its overlap with
  /// the map.
  double max_translation_per_frame_m = 0.0;
  double max_rotation_per_frame_deg = 180.0;
  /// Derive d_max from the observed deviations (true), or keep the registration settings' own
  /// max_correspondence_distance (false; the CLI and Python set it when --max-distance is given).
  bool adaptive_threshold = true;
  /// Adam and RMSProp step a length per iteration (their learning rate, in scaled units): cap it
  /// at a quarter of each frame's d_max, so the first steps cannot jump past every
  /// correspondence (false: the settings' learning rate as is; the CLI and Python set it when
  /// --learning-rate is given). docs/odometry.md.
  bool step_within_threshold = true;
  /// The registrations that track (from the prediction or the last registered pose) take
  /// Gauss-Newton steps in their coarse stage while the step rule is the default (Adam at its
  /// own step; the other optimizer parameters kept, as with_gauss_newton_steps does), as the
  /// refinement stages do: their start lies within the point-to-point basin, where a Newton step
  /// converges in a few mini-batches and Adam's steps of one length took 80-260 (the coarse stage
  /// was half of a hand-held LiDAR run's time; docs/design.md, *Tracking with Gauss-Newton
  /// steps*). The wide-basin retry keeps the optimizer (false: the settings' optimizer for every
  /// start; the CLI sets it when --optimizer or --learning-rate is given,
  /// Python when optimizer= or learning_rate= is).
  bool tracking_gauss_newton = true;
  /// Each frame with times is deskewed before it is registered and enters the map: moved to its
  /// sweep's middle by the predicted motion over the sweep (constant velocity, the sweep taken to
  /// last from one frame to the next: deskewed_by_motion), once a motion is known
  /// (docs/deskewing.md). A frame without times is registered as it is.
  DeskewMode deskew = DeskewMode::automatic;

  /// Throws InvalidSettingsError naming the first setting out of range (odometry_settings_table),
  /// spelled as `names` says.
  void validate(SettingNames names = SettingNames::field) const;
  bool operator==(const OdometrySettings&) const = default;
};

/// Every numeric setting of OdometrySettings a user can name (settings.hpp's Setting rows): the
/// CLI's `sgdicp odometry` options and Odometry's Python keywords, with range, unit and help.
[[nodiscard]] const std::vector<Setting<OdometrySettings>>& odometry_settings_table();
/// The setting called `name` ('_' may stand for '-'), or nullptr.
[[nodiscard]] const Setting<OdometrySettings>* find_odometry_setting(std::string_view name);

/// The correspondence threshold sigma of KISS-ICP's eq. (4)-(5): the RMS, over the frames so far,
/// of the deviation of each registration from its prediction, measured as the largest
/// displacement it causes to a point of the frame: |dt| + 2 r sin(|dtheta| / 2), r the range
/// within which the frame's points lie (KISS-ICP takes its max_range setting, 100 m: on a 20 m
/// scene a 2 deg deviation then counts 3.5 m and d_max reached 70-120 m, docs/odometry.md).
/// Deviations below min_motion are not counted; before the first counted one sigma is initial.
class AdaptiveThreshold {
 public:
  AdaptiveThreshold(double initial_m, double min_motion_m);
  /// Adds the deviation T_prediction^-1 T_estimate of one registered frame whose points lie
  /// within range_m of the sensor.
  void update(const Eigen::Matrix4d& deviation, double range_m);
  [[nodiscard]] double sigma_m() const;
  [[nodiscard]] std::size_t samples() const noexcept { return samples_; }
  /// The point displacement bound of a transform on points within range_m (metres), as used by
  /// update().
  [[nodiscard]] static double displacement_m(const Eigen::Matrix4d& T, double range_m);

 private:
  double initial_m_, min_motion_m_;
  double sum_squares_ = 0.0;
  std::size_t samples_ = 0;
};

/// The laplace covariance's softening (RegistrationResult::softening) over a sequence: measured by
/// its secant (6 passes over the frame, the bulk of the covariance's cost) on the first
/// kWarmUp frames and then on every kEvery-th, and between those the last measurement. The
/// softening drifts as the map fills (0.83 to 0.38 over the built hand-held sequence, 0.63 to
/// 0.2 over 7-Scenes): a mean over earlier measurements lags behind it and made the covariance
/// up to 2x too narrow (docs/odometry.md, *Covariance*).
class SofteningMemory {
 public:
  static constexpr std::size_t kWarmUp = 3;
  static constexpr std::size_t kEvery = 8;
  /// The softening the next frame's registration is to use: 0 = measure it.
  [[nodiscard]] double next() const;
  /// A frame was registered with the softening `used`, as next() asked.
  void record(double used);

 private:
  double last_measured_ = 0.0;      // 0 = none yet
  std::size_t measured_ = 0;        // measurements so far
  std::size_t since_measured_ = 0;  // frames since the last measurement
};

/// The motion expected of the next frame, T_{k-1}^-1 T_k: the last registered frame's motion with
/// its rotation and its translation each scaled by how much of a frame's motion has carried over
/// to the next one so far: the least-squares c of b = c a over the consecutive motions a, b of the
/// registered frames (rotation vectors; translations in the frame), in [0, 1]. 1 is KISS-ICP's
/// constant velocity, which a vehicle or a steadily carried camera fits (7-Scenes: 0.9 and 1); a
/// hand-held sensor swung about turns unpredictably and fits near 0 for the rotation (the
/// hand-held LiDAR: median prediction error 11 -> 7.7 deg at 2 Hz, 22 -> 15 deg at 0.67 Hz).
/// Until kMinPairs pairs of motions are known, constant velocity.
class MotionModel {
 public:
  static constexpr std::size_t kMinPairs = 5;
  /// A registered frame moved by `motion` since the registered frame just before it.
  void update(const Eigen::Matrix4d& motion);
  /// The motion since the last registered frame is unknown (frames were lost in between): the
  /// next prediction is no motion; the fits are kept.
  void forget_last() noexcept { last_.reset(); }
  /// The expected motion of the next frame (the identity before any motion is known).
  [[nodiscard]] Eigen::Matrix4d predicted() const;
  [[nodiscard]] double rotation_carry() const noexcept;
  [[nodiscard]] double translation_carry() const noexcept;

 private:
  struct Motion {
    Eigen::Vector3d rotation;  // rotation vector, rad
    Eigen::Vector3d translation_m;
  };
  std::optional<Motion> last_;
  double rotation_ab_ = 0.0, rotation_aa_ = 0.0;
  double translation_ab_ = 0.0, translation_aa_ = 0.0;
  std::size_t pairs_ = 0;
};

/// Where a frame's registration started.
enum class FrameStart {
  prediction,  ///< the motion model's prediction (MotionModel)
  last_pose,   ///< the last registered pose, without the velocity (a retry)
  wide_basin,  ///< the last registered pose, with SGD-ICP's own wide basin (the last retry)
  global,      ///< no guess: the global registration against the map (a retry, before the wide
               ///< basin, whose answer it confirms)
};
inline constexpr std::array<EnumName<FrameStart>, 4> kFrameStartNames{{
    {FrameStart::prediction, "prediction"},
    {FrameStart::last_pose, "last pose"},
    {FrameStart::wide_basin, "wide basin"},
    {FrameStart::global, "global"},
}};
constexpr const auto& enum_names(FrameStart) {
  return kFrameStartNames;
}
constexpr std::string_view enum_noun(FrameStart) {
  return "frame start";
}

/// How a frame's message starts when an internal error (a bug) failed it.
inline constexpr std::string_view kInternalError =
    "internal error (a bug in sgd-icp: please report this message with the command, or the "
    "calls, and the frame that caused it): ";

/// What happened to one frame.
struct FrameReport {
  std::size_t index = 0;
  Eigen::Matrix4d T_first_frame = Eigen::Matrix4d::Identity();
  /// Lost: no start registered the frame; the pose is the prediction (see message) and neither
  /// the map nor the motion model took the frame in.
  bool failed = false;
  /// Registered by a retry, after the registration from the prediction was rejected (message
  /// says why); start says which.
  bool recovered = false;
  FrameStart start = FrameStart::prediction;
  /// Of the registered frame: the fraction of its registered points with a map point within one
  /// map voxel. A frame is rejected below half the median of the last frames' (the frame has
  /// slid off the map), 0 when not registered.
  double overlap = 0.0;
  bool converged = false;  ///< the registration's convergence test passed
  /// Registered, but the pose may be off (message says why after "doubtful: "): the scene leaves
  /// some motion unconstrained (the registration's constraint_ratio below 0.05: a floor and little
  /// else) while the prediction was uncertain by more than two voxels, or no start gave an overlap
  /// like the last frames' and the best one was taken. The pose is kept (rejecting such frames
  /// lost 59-75 of 76 cropped hand-held scans and left the map behind); trust it less.
  bool doubtful = false;
  /// Of the registration: its smallest over largest eigenvalue of the point-to-plane information
  /// (result.hpp), 0 when not registered.
  double constraint_ratio = 0.0;
  /// The frame is identical to the previous one (a sensor delivering a frame twice, as 59 of the
  /// 600 7-Scenes frames): it gets the previous pose and the motion model is kept, since the
  /// data's answer (no motion) would stop the prediction.
  bool repeated = false;
  std::string message;  ///< why it failed, or the registration's stop message
  std::size_t iterations = 0;
  std::size_t source_points = 0;  ///< frame points registered (after cropping and thinning)
  std::size_t map_points = 0;     ///< map points it was registered to
  double inlier_ratio = 0.0;      ///< of the registration (result.hpp)
  double inlier_rmse_m = 0.0;
  double threshold_m = 0.0;     ///< adaptive d_max given (3 sigma), metres; 0 when fixed
  double index_build_ms = 0.0;  ///< KD-tree over the map (plus normals / covariances)
  double time_ms = 0.0;         ///< the whole frame: thinning, index, registration, map update
  /// With an uncertainty (SgdSettings::uncertainty, an SGD method): the covariance of the frame's
  /// pose relative to the map it was registered against, the covariance_se3 of the registration
  /// that gave the pose (result.hpp): translation first, right perturbation T_first_frame =
  /// T_hat * Exp(xi), xi in the frame's own tangent space, metres and radians. The map's own error
  /// (the drift of the frames before) is not in it. The frame that starts the map (the first):
  /// zeros, it defines the coordinates. A repeated frame: the previous frame's. A frame without
  /// one (lost, unreadable, no point; every frame without an uncertainty): every entry NaN.
  Eigen::Matrix<double, 6, 6> covariance =
      Eigen::Matrix<double, 6, 6>::Constant(std::numeric_limits<double>::quiet_NaN());
};

class Odometry {
 public:
  /// The registration step is `method` (methods.hpp) with `sgd` or `batch` as its settings.
  /// Without the settings of the method's solver (`sgd` for the SGD methods, `batch` for the
  /// batch ones), the defaults with the method's cost (apply_method_cost); given, they are
  /// used as they are (their grid aside: the pipeline has its own), so apply the method's cost to
  /// them before changing what you want (e.g. a coarse cost). An uncertainty in `sgd`
  /// (SgdSettings::uncertainty) gives every frame its covariance (FrameReport::covariance); none,
  /// nothing is computed for it. Throws InvalidSettingsError for invalid settings or method,
  /// settings whose cost is not the method's, or an uncertainty with a batch method
  /// (check_method_uncertainty).
  explicit Odometry(const OdometrySettings& settings = {}, std::string_view method = "sgd",
                    std::optional<SgdSettings> sgd = std::nullopt,
                    std::optional<BatchSettings> batch = std::nullopt);
  /// The settings of the registration step, as used.
  [[nodiscard]] const SgdSettings& sgd_settings() const noexcept { return sgd_; }
  [[nodiscard]] const BatchSettings& batch_settings() const noexcept { return batch_; }

  /// Registers the next frame (points in its sensor frame) and returns its pose T_first_frame.
  /// The first frame is the identity. A failed frame is reported (reports().back().failed, with
  /// the reason in its message) and gets the predicted pose; whatever goes wrong with one frame
  /// is that frame's failure, and the next frame goes on from the last registered one. An
  /// internal error (a bug) is reported as such (the message starts with kInternalError). Throws
  /// only std::bad_alloc (out of memory).
  Eigen::Matrix4d register_frame(const PointCloud& frame);

  /// Records a frame that could not be read (a bad file): predicted pose, failed, `message`.
  Eigen::Matrix4d skip_frame(const std::string& message);

  [[nodiscard]] const std::vector<Eigen::Matrix4d>& poses() const noexcept { return poses_; }
  [[nodiscard]] const std::vector<FrameReport>& reports() const noexcept { return reports_; }
  [[nodiscard]] const VoxelMap* map() const noexcept { return map_ ? &*map_ : nullptr; }
  /// The map's points (the first frame's coordinates, metres), thinned to one centroid per voxel
  /// of voxel_size_m when it is above 0; empty before the first frame with points.
  [[nodiscard]] PointCloud map_cloud(double voxel_size_m = 0.0) const;
  /// From the next frame on, keeps the whole map: every registered frame's points (cropped to the
  /// range limits) in the first frame's coordinates, one centroid per voxel of voxel_size_m (0 =
  /// the odometry's voxel, regridded with it when it grows; whole_map.hpp). On a voxel no finer
  /// than 3/4 of the odometry's, the frame enters as thinned for the local map (the centroids of
  /// its 3/4-voxel grid); on a finer one, at full resolution.
  /// Lost frames do not enter it. Throws InvalidSettingsError for a negative or non-finite size.
  void keep_whole_map(double voxel_size_m = 0.0);
  /// The whole map kept since keep_whole_map (nullptr before it was asked for or before the first
  /// frame with points).
  [[nodiscard]] const WholeMap* whole_map() const noexcept {
    return whole_map_ ? &*whole_map_ : nullptr;
  }
  /// Frames lost (no start registered them, or unreadable) and recovered (registered by a retry).
  [[nodiscard]] std::size_t lost_frames() const noexcept;
  [[nodiscard]] std::size_t recovered_frames() const noexcept;
  /// Frames registered but doubtful (FrameReport::doubtful).
  [[nodiscard]] std::size_t doubtful_frames() const noexcept;
  [[nodiscard]] const OdometrySettings& settings() const noexcept { return settings_; }
  /// The voxel size in use (the derived one once the first frame is in), metres.
  [[nodiscard]] double voxel_size_m() const noexcept { return voxel_size_m_; }
  [[nodiscard]] std::string_view method() const noexcept { return method_->name; }

 protected:
  /// Localization (Localizer, localizer.hpp): the map is `map` (its own coordinates), built into
  /// the map's voxels at the first frame and never changed; the first frame starts from
  /// T_map_first_frame, or from the global registration without one; a frame whose best
  /// registration overlaps the map doubtfully is lost, not placed. Before the first frame only.
  void fix_map(PointCloud map, std::optional<Eigen::Matrix4d> T_map_first_frame);
  /// The time it took to build the fixed map into its voxels, with its surfaces (0 before).
  [[nodiscard]] double fixed_map_build_ms() const noexcept { return fixed_map_build_ms_; }

 private:
  /// Builds the fixed map into map_ (fix_map), timing it.
  void build_fixed_map();
  /// The starts of a frame's registration, in the order they are tried.
  [[nodiscard]] std::vector<FrameStart> starts() const;
  /// The map and the threshold for the first frame with points, whose range is range_m.
  void start(double range_m);
  /// The adaptive threshold anew, its derived lengths from the voxel in use.
  void start_threshold();
  /// What a voxel growth replaced: taken back when the frame that asked for it is lost.
  struct VoxelBefore {
    double voxel_size_m;
    VoxelMap map;
    AdaptiveThreshold threshold;
  };
  /// A derived voxel grows (the map regridded) when the last frames' range asks for twice it;
  /// returns what it replaced (nothing when it did not grow).
  std::optional<VoxelBefore> grow_voxel(double range_m);
  [[nodiscard]] Eigen::Matrix4d predicted() const;
  /// register_frame without its guard: may throw.
  Eigen::Matrix4d register_frame_unguarded(const PointCloud& frame, double started_ms);
  /// The frame (cropped, its range range_m) thinned on the map's grid and registered to the map
  /// (the first frame with points starts it); `grown`: what a growth of the grid replaced.
  Eigen::Matrix4d register_on_grid(const PointCloud& cropped, double range_m,
                                   std::optional<VoxelBefore>& grown, FrameReport& report,
                                   double started_ms);
  /// Records the next frame as lost: the predicted pose, `message`.
  Eigen::Matrix4d fail_frame(const std::string& message, double started_ms);
  /// Restores what a voxel growth replaced (nothing when it did not grow).
  void take_back(std::optional<VoxelBefore>& grown);
  /// std::logic_error when the map lacks what the cost reads of it (a bug).
  void check_map_surfaces(const ReferenceIndex& index) const;
  /// A frame identical to the previous one: the previous pose, the motion model kept.
  Eigen::Matrix4d repeat_previous_pose(double started_ms);
  /// The registration step of a frame to the map (d_max 3 sigma when adaptive).
  [[nodiscard]] RegistrationResult align_to_map(const PointCloud& source,
                                                const ReferenceIndex& index, double sigma_m,
                                                const Eigen::Matrix4d& T_guess,
                                                FrameStart start) const;
  /// Registers the frame from each start in turn until one is accepted (judge) with an overlap
  /// that is not doubtful, filling the report; else the doubtful one with the highest overlap;
  /// lost when none is accepted.
  void register_to_map(const PointCloud& source, const ReferenceIndex& index, double range_m,
                       FrameReport& report);
  /// Why a registration cannot be the frame's pose ("" = accepted): not converged, a motion
  /// beyond the bounds per frame since the last registered frame, or an overlap below half the
  /// recent frames'.
  [[nodiscard]] std::string judge(const RegistrationResult& r, double overlap,
                                  double range_m) const;
  /// The overlap below which an accepted registration is doubtful: 0.8 of the recent frames'
  /// median, or half the frame before any is known.
  [[nodiscard]] double doubtful_below() const;
  /// One registration of the frame from `start`, judged ("" = accepted).
  struct Attempt {
    RegistrationResult result;
    double overlap = 0.0;
    std::string why;
  };
  [[nodiscard]] Attempt attempt(const PointCloud& source, const ReferenceIndex& index,
                                double sigma_m, double range_m, const Eigen::Matrix4d& T_guess,
                                FrameStart start) const;
  /// The frame's pose is the registration `a` from `start` (its report filled in); `rejected`
  /// says why the starts before it were not taken.
  void accept(const Attempt& a, FrameStart start, const Eigen::Matrix4d& T_prediction,
              double range_m, const std::string& rejected, FrameReport& report);
  /// Why a registration taken as the frame's pose may be off ("" = none): FrameReport::doubtful.
  [[nodiscard]] std::string doubt_of(const Attempt& a) const;
  /// Why the global registration does not confirm a wide-basin one ("" = confirmed).
  [[nodiscard]] std::string unconfirmed(const Attempt& wide, const Attempt& global) const;
  Eigen::Matrix4d finish(FrameReport report, const PointCloud& map_frame, double started_ms);
  /// The frame with the times the deskew mode gives it, cropped to the range limits, and
  /// deskewed when it has times and a motion is known.
  [[nodiscard]] PointCloud prepared_frame(const PointCloud& frame) const;
  /// After the second frame with times: the map made anew of the first two, deskewed by the
  /// motion between them.
  void deskew_first_frames(const PointCloud& map_frame);
  /// Adds the registered frame (cropped, or its map_frame thinning) at pose T to the whole map,
  /// when one is kept.
  void add_to_whole_map(const PointCloud& cropped, const PointCloud& map_frame,
                        const Eigen::Matrix4d& T);
  /// Adds the frame's points at pose T, with the normals or covariances the cost needs.
  void add_to_map(const PointCloud& frame, const Eigen::Matrix4d& T);
  [[nodiscard]] CostType cost() const;
  [[nodiscard]] const NeighborhoodSettings& neighborhood() const;
  // The registration's thread count: every step of a frame runs on it (--threads).
  [[nodiscard]] std::size_t threads() const;
  // The registrations estimate a pose uncertainty (an SGD method with SgdSettings::uncertainty).
  [[nodiscard]] bool with_uncertainty() const;

  OdometrySettings settings_;
  const Method* method_;
  SgdSettings sgd_;
  BatchSettings batch_;
  double voxel_size_m_ = 0.0;
  std::vector<double> ranges_m_;  ///< of the first and the last registered frames (grow_voxel)
  std::optional<VoxelMap> map_;
  std::optional<double> whole_map_voxel_m_;  ///< keep_whole_map's size (0 = the odometry's voxel)
  std::optional<WholeMap> whole_map_;
  std::optional<PointCloud> first_map_frame_;  ///< with times, until deskew_first_frames
  std::optional<PointCloud> fixed_map_;        ///< fix_map's cloud, until build_fixed_map takes it
  bool localizing_ = false;                    ///< the map is fixed (fix_map)
  std::optional<Eigen::Matrix4d> T_map_first_frame_;
  double fixed_map_build_ms_ = 0.0;
  bool registered_any_ = false;  ///< a frame has been registered (T_last_good_ is a pose)
  std::optional<AdaptiveThreshold> threshold_;
  MotionModel motion_;
  SofteningMemory softening_;
  Eigen::Matrix4d T_last_good_ = Eigen::Matrix4d::Identity();  ///< last registered frame's pose
  std::size_t lost_since_good_ = 0;  ///< frames lost since the last registered one
  std::vector<double> overlaps_;     ///< of the registered frames, the last kOverlapFrames
  std::vector<Eigen::Vector3f> previous_points_;  ///< of the last frame, to spot a repeat
  std::vector<Eigen::Matrix4d> poses_;
  std::vector<FrameReport> reports_;
};

/// The points of `cloud` at a distance from the origin in [min_range_m, max_range_m].
[[nodiscard]] PointCloud crop_range(const PointCloud& cloud, double min_range_m,
                                    double max_range_m);

}  // namespace sgdicp
