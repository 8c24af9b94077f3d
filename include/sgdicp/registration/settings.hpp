#pragma once
// The settings of both solvers (SGD-ICP and the batch baselines) and one table that describes
// every setting a user can name: its name (the CLI's option without "--"; Python's keyword with
// '_' for '-'), its C++ member, its kind, its valid range and unit, and its help. validate()
// checks the ranges of this table, the CLI builds its options from it, the Python keyword
// overrides apply through it, and the settings table of docs/registration.md is tested against
// it. Defaults are never written in the table: they are read from SgdSettings{},
// SgdSettings::paper() and BatchSettings{}. The odometry's and the global registration's settings
// have tables of the same Setting rows (odometry.hpp, global_registration.hpp), read the same way.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "sgdicp/core/distance.hpp"
#include "sgdicp/core/format_number.hpp"
#include "sgdicp/costs/cost.hpp"
#include "sgdicp/costs/robust_kernel.hpp"
#include "sgdicp/points/scaling.hpp"
#include "sgdicp/registration/evaluation.hpp"
#include "sgdicp/solver/convergence.hpp"
#include "sgdicp/solver/optimizer.hpp"
#include "sgdicp/solver/refinement.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "sgdicp/uncertainty/uncertainty.hpp"

namespace sgdicp {

/// How validate() names a setting in its messages: the C++ member (convergence.window), the CLI
/// option (--window) or the Python keyword (window=).
enum class SettingNames { field, cli, python };

/// The mini-batches (read by the run's sampler and batch loop, and by batch_size_for,
/// is_small_source and min_source_points): how many source points each draws, and from which seed.
struct SamplingSettings {
  /// m of the paper: source points per mini-batch.
  std::size_t batch_size = 160;
  /// Seed of the mini-batch sampler; same inputs and seed give the same result.
  std::uint64_t seed = 2019;

  bool operator==(const SamplingSettings&) const = default;
};

/// Which pairs count and how much (read by the pairing of either solver): d_max, the robust
/// kernel and the trimming. The defaults are SGD's; BatchSettings has its own d_max.
struct PairingSettings {
  /// d_max: pairs farther apart are rejected (SGD: the paper's 0.5 in scaled units).
  Distance max_correspondence_distance = Distance::scaled(0.5);
  /// Robust kernel on each pair's residual (robust_kernel.hpp) ...
  KernelType kernel = KernelType::none;
  /// ... and its scale: the residual size where it starts to down-weight.
  Distance kernel_scale = Distance::scaled(0.01);
  /// Keep only this fraction of the pairs (SGD: of each mini-batch's; batch methods: of each
  /// iteration's), the closest ones (trimmed ICP, Chetverikov et al. 2002), for partial overlap;
  /// 1 keeps all.
  double trim_ratio = 1.0;

  bool operator==(const PairingSettings&) const = default;
};

/// The scaled space of an SGD run (read by its scaling, UnitCubeScaling).
struct ScalingSettings {
  /// Origin of the scaled space = pivot of roll, pitch, yaw. The paper's lower corner couples
  /// rotation and translation strongly (a small rotation about a far corner is a large
  /// translation of the points); the box centre decouples them (docs/design.md).
  ScalingOrigin origin = ScalingOrigin::center;
  /// Scale from the bulk of each cloud (bulk_bounding_box in scaling.hpp), so that a few far
  /// points (spurious returns) do not shrink the scene; false = the paper's bounding box of
  /// every point. The far points left out are counted in RegistrationResult::far_points.
  bool robust = true;

  bool operator==(const ScalingSettings&) const = default;
};

/// Voxel-grid downsampling of both clouds before registering (read where the reference's index
/// is built, reference_index_for, and where the source is thinned, align()). The default is
/// SGD's; BatchSettings downsamples only when asked.
struct DownsamplingSettings {
  /// The voxel side, metres (points/voxel_grid.hpp); 0 = the grid downsample_to chooses.
  double voxel_size_m = 0.0;
  /// Without voxel_size_m: the grid that keeps about this many points of the reference
  /// (voxel_size_for_count), applied to both clouds where the library builds the reference's
  /// index (reference_index_for, align() on two clouds, the CLI, Python arrays); 0 = none. An
  /// index built from a cloud as given keeps both clouds as given. One voxel grid evens out the
  /// density of near and far returns and indexes ~20k points instead of 100k-300k: on every
  /// pairs file and the 7-Scenes pairs it is both faster and more precise than full resolution
  /// (KITTI 33 -> 25 ms, 7-Scenes 58 -> 36 ms with point-to-point, errors equal or lower).
  /// 20,000 is what small_gicp's recommended voxels (0.25 m outdoor, 2 cm Kinect) leave of a
  /// KITTI scan or a 7-Scenes frame. Clouds of at most this many points, or that carry normals
  /// or covariances, are used as they are.
  std::size_t downsample_to = 20000;

  bool operator==(const DownsamplingSettings&) const = default;
};

/// The settings of SGD-ICP, grouped by the part of the run that reads them (docs/registration.md,
/// *Settings*): sampling, the step rule (optimizer), pairing, convergence, refinement, the
/// surfaces (neighborhood), scaling, downsampling, the final statistics (evaluation) and the
/// uncertainty; at the top level what the run as a whole reads.
struct SgdSettings {
  SamplingSettings sampling{};
  /// Small sources (fewer than batch_size x window / 2 points, 1,600 by default; is_small_source)
  /// get two rules the paper lacks. Their mini-batch is capped at 2 x source points / window (at
  /// least kMinCappedBatch), so that one window still sees every point about twice
  /// (batch_size_for): iterations are set by how far the coarse stage travels, not by m, so the
  /// 361-point bunny takes the same ~220 iterations and errors at m = 36 as at 160, at half the
  /// time. And their coarse stage takes Gauss-Newton steps while `optimizer` is the default Adam
  /// (optimizer_for): on the bunny moved 30-90 deg as robust as Adam or more, 1.5x more precise
  /// in rotation, 120 instead of 180-700 mini-batches (docs/design.md, *Small sources*). Not a
  /// user setting: paper() turns both off, every other run keeps them.
  bool adapt_small_sources = true;
  /// Default: Adam with a step of 0.01 scaled units, measured best over the real pairs
  /// (docs/design.md): it keeps the paper's wide basin (KITTI copies moved by 30 m), which the
  /// greedier Gauss-Newton step loses, and reaches cm accuracy with the refinement stages.
  OptimizerSettings optimizer{OptimizerType::adam, default_learning_rate(OptimizerType::adam)};
  PairingSettings pairing{};
  ConvergenceSettings convergence{};
  RefinementSettings refinement{};
  /// Cost of a pair (cost.hpp): the paper's point-to-point, point-to-plane, or plane-to-plane
  /// (GICP). The plane costs need normals / covariances (estimated with `neighborhood` for the
  /// points the run pairs, when the clouds lack them). Default point-to-plane: on the voxel grid
  /// it is 1.5-2x more precise in rotation than point-to-point where the ground truth can tell
  /// (7-Scenes 0.29 -> 0.17 deg, moved copies, car) and keeps the wide basin (coarse_cost).
  CostType cost = CostType::point_to_plane;
  /// Cost of the first (coarse) stage when refinement stages follow; the refinement stages and
  /// the result use `cost`. Point-to-point keeps the paper's wide basin, which point-to-plane
  /// loses: KITTI pairs started 30 m / 30 deg off, 100 % solved against 70-75 % with
  /// point-to-plane throughout (40 starts); and it needs no normals.
  CostType coarse_cost = CostType::point_to_point;
  /// Neighbourhoods for normals and covariances when a plane cost needs them: 10 neighbours
  /// where those lie flat, else 20. Against 20 everywhere: the PCL bunny (a sparse scan of a
  /// small object) 0.34 -> 0.20 deg, KITTI scans cut to 1 % of their points 26 instead of 16 of
  /// 40 registrations within 5 cm and 1 deg, the other pairs as before (18 sets of real and
  /// thinned pairs, 5 seeds each).
  NeighborhoodSettings neighborhood{.flat_k = 10};
  ScalingSettings scaling{};
  /// Hard limit on iterations (mini-batches); reaching it means "not converged".
  std::size_t max_iterations = 4000;
  /// Return the mean of the iterates of the final stage's stationary window (the last
  /// `window` iterations) instead of the last iterate.
  bool average_iterates = true;
  /// Record a per-iteration trace in the result.
  bool record_trace = false;
  /// The final statistics (evaluate_alignment, on the run's num_threads): source points
  /// evaluated (0 = all). The check for degenerate geometry (a plane, a line, a corridor) always
  /// runs.
  EvaluationSettings evaluation{};
  /// Threads of one registration: where the library builds the index (reference_index_for:
  /// align() on clouds, the CLI, Python) the voxel grid's passes over the raw points (the size
  /// search's counting, the moments), the grid's block surfaces alongside its KD-tree (or the
  /// KD-tree build, KdTreeSettings::num_threads, and the normals or covariances estimated all
  /// at once off the grid); the source's thinning in align(); and with two or more, each
  /// mini-batch's nearest-neighbour queries and plane-cost terms in two halves, one on the
  /// calling thread's helper (the sums stay in batch order on the caller; the rest of the SGD
  /// loop runs on one), and the final statistics' queries: two threads 1.5-1.66x faster than one
  /// on KITTI scans and Kinect frames (on an idle second core). 0 = every core. The result is
  /// identical for any count.
  std::size_t num_threads = 1;
  DownsamplingSettings downsampling{};
  /// Pose uncertainty of the result (uncertainty.hpp, docs/uncertainty.md): none, laplace or
  /// sgld, with the sampler's and the calibration's settings.
  UncertaintySettings uncertainty{};

  /// The paper's settings: m = 160, d_max = 0.5 scaled, the step rule's step size
  /// (default_learning_rate: the paper's fixed step alpha = 2, Adam 0.01), no refinement, the
  /// last iterate returned, the paper's scaling origin (lower corner), its point-to-point cost,
  /// every point used.
  static SgdSettings paper(OptimizerType optimizer = OptimizerType::sgd);

  /// Throws InvalidSettingsError naming the first setting outside its range (settings_table())
  /// or contradicting another, spelled as `names` says.
  void validate(SettingNames names = SettingNames::field) const;

  bool operator==(const SgdSettings&) const = default;
};

/// The smallest mini-batch adapt_small_sources leaves (a smaller source is an error).
inline constexpr std::size_t kMinCappedBatch = 32;

/// The mini-batch size m of a run on a source of `source_points` points: batch_size, capped for
/// small sources when adapt_small_sources says so.
[[nodiscard]] std::size_t batch_size_for(const SgdSettings& settings, std::size_t source_points);

/// Whether a source of `source_points` points is small: fewer than batch_size x window / 2, so
/// that m covers it about twice per convergence window.
[[nodiscard]] bool is_small_source(const SgdSettings& settings, std::size_t source_points);
/// Whether `optimizer` is the step rule nobody chose: the default's type at its own learning
/// rate. Its damping may differ: it shapes the Gauss-Newton steps that then replace it (a small
/// source's coarse stage, optimizer_for; the odometry's tracking).
[[nodiscard]] bool is_default_step_rule(const OptimizerSettings& optimizer);
/// The coarse stage's step rule on a source of `source_points` points: Gauss-Newton at its own
/// step for a small source when adapt_small_sources says so and `optimizer` is the
/// default step rule (is_default_step_rule), else `optimizer`.
[[nodiscard]] OptimizerSettings optimizer_for(const SgdSettings& settings,
                                              std::size_t source_points);
/// The fewest source points a run with these settings accepts: batch_size, or with the cap the
/// smaller of batch_size and kMinCappedBatch.
[[nodiscard]] std::size_t min_source_points(const SgdSettings& settings);

struct BatchSettings {
  /// point-to-point (icp), point-to-plane (icp-plane) or plane-to-plane (gicp).
  CostType cost = CostType::point_to_point;
  /// d_max: pairs farther apart are rejected. Scaled units are a fraction of the largest side
  /// of the joint bounding box (e.g. 0.05 = 6 m on a 120 m LiDAR scan, 10 cm on a 2 m Kinect
  /// view). The kernel and the trimming as SgdSettings's, the trimming per iteration.
  PairingSettings pairing{.max_correspondence_distance = Distance::scaled(0.05)};
  std::size_t max_iterations = 100;
  /// Converged when an iteration moves the translation less than this (scaled units: 0.1 mm on
  /// a 10 m room, 1.5 mm on a 150 m LiDAR scene) ...
  double translation_tolerance = 1e-5;
  /// ... and the rotation less than this (rad).
  double rotation_tolerance = 1e-5;
  /// Initial Levenberg-Marquardt damping, relative to the mean diagonal of J^T J; 0 = plain
  /// Gauss-Newton. Unused by point-to-point (closed form).
  double initial_damping = 1e-6;
  /// Neighbourhoods for the normals / covariances of the plane costs (estimated when missing).
  NeighborhoodSettings neighborhood{};
  EvaluationSettings evaluation{};  ///< see SgdSettings
  /// See ScalingSettings::robust (the scale of scaled distances; the batch methods' origin is
  /// the lower corner, which does not change the scale).
  bool robust_scaling = true;
  std::size_t num_threads = 1;  ///< see SgdSettings
  /// See SgdSettings; downsample_to 0 here: the batch methods register every point unless asked.
  DownsamplingSettings downsampling{.downsample_to = 0};
  /// Record a per-iteration trace in the result: the pose after each iteration, every source
  /// point processed per iteration, step size 1, d_max, the pairs kept and, as the cost, their
  /// mean squared distance before the step (scaled units^2).
  bool record_trace = false;

  static BatchSettings icp();        ///< point-to-point
  static BatchSettings icp_plane();  ///< point-to-plane
  static BatchSettings gicp();       ///< plane-to-plane

  /// Throws InvalidSettingsError naming the first setting outside its range, spelled as `names`
  /// says.
  void validate(SettingNames names = SettingNames::field) const;

  bool operator==(const BatchSettings&) const = default;
};

// ---- the table of settings

enum class SettingKind {
  count,     ///< a non-negative integer
  real,      ///< a finite floating-point number
  flag,      ///< true or false
  distance,  ///< a Distance; its range depends on its unit
  choice,    ///< one of the names of an enum (enum_names.hpp)
};

/// An interval of valid values; each end closed or open.
struct ValueRange {
  double min = 0.0;
  double max = 0.0;
  bool min_open = false;
  bool max_open = false;

  [[nodiscard]] bool contains(double v) const {
    return (min_open ? v > min : v >= min) && (max_open ? v < max : v <= max);
  }
  /// "[8, 100000]", "(0, 1]", "[0, 2^64-1]".
  [[nodiscard]] std::string to_string() const;
};

/// The value of one setting, whatever its kind (a choice by its canonical name).
using SettingValue = std::variant<std::uint64_t, double, bool, Distance, std::string>;

/// What a table says of one setting, whatever the settings struct: names, kind, range, unit,
/// help. Read by validate(), the CLI's options, Python's keywords and the docs tests.
struct SettingDescription {
  std::string_view name;   ///< the CLI option without "--"; Python: '-' replaced by '_'
  std::string_view field;  ///< the C++ member, e.g. "optimizer.learning_rate"
  SettingKind kind = SettingKind::real;
  ValueRange range;         ///< count and real; a distance in scaled units
  ValueRange metres_range;  ///< a distance in metres
  std::string_view unit;    ///< of a count or real, for help, docs and messages ("rad"; "" = none)
  std::string_view help;    ///< one sentence, no default (read from the settings)
  std::vector<std::string_view> (*choices)() = nullptr;  ///< the names of a choice
  /// Not a CLI option (the CLI chooses the cost with --method and records a trace with --trace).
  bool keyword_only = false;
  /// One of the few a user of the command sets: Python's signatures and help list these first
  /// (the CLI's --help shows them, with the command's own options).
  bool common = false;

  /// `name` as the user spells it: --learning-rate, learning_rate=, optimizer.learning_rate.
  [[nodiscard]] std::string spelled(SettingNames names) const;
};

/// One row of the table of a settings struct S (SgdSettings, BatchSettings, OdometrySettings,
/// GlobalSettings): its description and the access to its member.
template <typename S>
struct Setting : SettingDescription {
  SettingValue (*get)(const S&) = nullptr;
  /// Sets the value (a choice by any accepted name); throws InvalidSettingsError for an unknown
  /// name. Setting "optimizer" also sets the learning rate to default_learning_rate().
  void (*set)(S&, const SettingValue&) = nullptr;
};

/// Every setting of SgdSettings a user can name, in the order in which they are applied
/// ("optimizer" first: it sets the learning rate, which a later "learning-rate" overrides).
[[nodiscard]] const std::vector<Setting<SgdSettings>>& sgd_settings_table();
/// The members of SgdSettings that no user names: fixed rules of the default that C++ code (the
/// tests) may switch: convergence.max_path_efficiency, refinement.gauss_newton and
/// settle_tolerance, and the samplers' uncertainty.burn_in, step, svgd_step and block_size (each
/// member says why its value holds). validate() checks their ranges with their C++ names. The
/// other members outside sgd_settings_table() are set by paper() alone (adapt_small_sources,
/// scaling.robust) or are the surfaces' own (NeighborhoodSettings::validate).
[[nodiscard]] const std::vector<Setting<SgdSettings>>& sgd_fixed_rules_table();
/// Every setting of BatchSettings a user can name (those shared with SGD have the same name).
[[nodiscard]] const std::vector<Setting<BatchSettings>>& batch_settings_table();

/// The part of the run that reads the setting whose C++ member is `field` ("Step rule" for
/// "optimizer.learning_rate"), the heading under which --help-all and Python's help group it.
[[nodiscard]] std::string_view setting_part(std::string_view field);

/// Whether `name` ('_' may stand for '-') was a setting of an earlier release that is none now: a
/// rule's constant, a fixed rule or a paper()-only member (docs/registration.md, *What is no
/// longer a setting*), so that the CLI and Python can say so instead of "unknown".
[[nodiscard]] bool is_retired_setting(std::string_view name);

/// The setting called `name` ('_' may stand for '-'), or nullptr.
[[nodiscard]] const Setting<SgdSettings>* find_sgd_setting(std::string_view name);
[[nodiscard]] const Setting<BatchSettings>* find_batch_setting(std::string_view name);

/// A value as the docs and --help print it: 160, 0.01, 1e-06, true, 0.5 scaled, 2 m, adam.
[[nodiscard]] std::string format_value(const SettingValue& value);

/// Throws InvalidSettingsError "SPELLED VALUE: must be in RANGE UNIT" unless `value` lies in the
/// setting's range (a distance: the range of its unit).
void check_range(const SettingDescription& setting, const SettingValue& value, SettingNames names);

}  // namespace sgdicp
