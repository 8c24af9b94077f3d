#pragma once
// Registration without an initial guess (docs/global.md): FPFH descriptors (fpfh.hpp) on one
// voxel grid of both clouds, mutual nearest neighbours in descriptor space, RANSAC with the
// edge-length test keeping the best few distinct hypotheses, each verified by the overlap it
// gives against the reference index; the winner then starts the default SGD-ICP registration.
// Method: Rusu et al., "Fast Point Feature Histograms (FPFH) for 3D registration", ICRA 2009
// (features, and their RANSAC "SAC-IA" pipeline), with the correspondence checks of Zhou, Park and
// Koltun, "Fast Global Registration", ECCV 2016.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/result.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp {

struct GlobalSettings {
  /// Both clouds are thinned on one voxel grid that keeps about this many reference points
  /// (voxel_size_for_count); the features, the consensus and the scores work on it, and every
  /// length below is in its voxels. 3,000 against 5,000: the same success on 6 turns of 7
  /// datasets but the hand-held LiDAR 20 scans apart (50 % against 33 %), 2x faster.
  std::size_t feature_points = 3000;
  std::size_t normal_neighbors = 12;    ///< k of the normals on the feature grid
  double feature_radius_voxels = 5.0;   ///< FPFH neighbourhood radius
  double inlier_distance_voxels = 1.5;  ///< a correspondence, or an overlapping point, within this
  std::size_t max_iterations = 100000;  ///< RANSAC samples at most
  double confidence = 0.999;            ///< RANSAC stops once a better sample is this unlikely
  std::size_t hypotheses = 8;           ///< distinct hypotheses kept and verified
  /// Hypotheses closer than this (rotation, or translation in voxels) are the same one. 3
  /// voxels, not 10: on the hand-held LiDAR 20 scans apart a pose shifted 5-7 m (7-9 voxels)
  /// along the scene merged with the right one and, with more feature support, replaced it
  /// (80 % solved on 20 turns; 95 % at 3 or 5 voxels, the other pairs unchanged).
  double distinct_rotation_deg = 10.0;
  double distinct_translation_voxels = 3.0;
  /// align_global refines with SGD-ICP each of up to this many hypotheses (best coarse overlap
  /// first) whose overlap is at least half the best's, and scores them again at a finer
  /// distance: the winner and the runner-up are decided there.
  std::size_t refined_hypotheses = 3;
  double fine_distance_voxels = 0.5;  ///< an overlapping point after refinement, within this
  /// The runner-up's score at least this fraction of the winner's: the scene is ambiguous (a
  /// symmetric object, a repetitive scene), and the result says so instead of picking one.
  double ambiguity_ratio = 0.9;
  /// A winner overlapping less than this fraction of the source is no solution.
  double min_score = 0.05;
  /// Fewer feature-grid points than this in either cloud: no solution is attempted.
  std::size_t min_points = 30;

  /// Throws InvalidSettingsError naming the first setting out of range (global_settings_table),
  /// spelled as `names` says (field: "GlobalSettings.confidence", as SgdSettings has members of
  /// the same names).
  void validate(SettingNames names = SettingNames::field) const;
};

/// Every setting of GlobalSettings (settings.hpp's Setting rows), named with the prefix "global-"
/// so that they stand beside the registration's: the CLI's options of `register --init global`
/// (--global-feature-points), the Python keywords of register(init="global")
/// (global_feature_points=), docs/global.md's table; with range, unit and help.
[[nodiscard]] const std::vector<Setting<GlobalSettings>>& global_settings_table();
/// The setting called `name` ('_' may stand for '-'), or nullptr.
[[nodiscard]] const Setting<GlobalSettings>* find_global_setting(std::string_view name);

/// One pose explaining the correspondences, with its support.
struct GlobalHypothesis {
  Eigen::Matrix4d T_reference_source = Eigen::Matrix4d::Identity();
  std::size_t consensus = 0;       ///< correspondences it agrees with
  std::size_t consensus_rank = 0;  ///< its rank by consensus (0 = the most supported)
  double score = 0.0;  ///< fraction of the source's feature points overlapping the reference
};

struct GlobalEstimate {
  /// Verified hypotheses, best score first (empty when none was found). estimate_global scores
  /// at inlier_distance_voxels; align_global keeps the refined ones, scored at
  /// fine_distance_voxels.
  std::vector<GlobalHypothesis> hypotheses;
  std::size_t winner_rank = 0;       ///< the winner's rank by consensus (0 = the most supported)
  double score = 0.0;                ///< the winner's
  double runner_up_score = 0.0;      ///< the best distinct other hypothesis's (0 = none)
  bool ambiguous = false;            ///< runner_up_score >= ambiguity_ratio * score
  bool reliable = false;             ///< a winner, not ambiguous, enough points and overlap
  std::string message;               ///< why it is not reliable, or what won
  std::size_t source_points = 0;     ///< on the feature grid
  std::size_t reference_points = 0;  ///< on the feature grid
  std::size_t correspondences = 0;   ///< putative feature matches
  std::size_t iterations = 0;        ///< RANSAC samples drawn
  double feature_voxel_m = 0.0;      ///< the feature grid
  double time_ms = 0.0;
};

/// Pose hypotheses for T_reference_source from no initial guess: source is the raw source cloud,
/// reference an index as align() takes (reference_index_for, or an odometry map's). The same
/// inputs and seed give the same estimate. Throws InvalidSettingsError; clouds too small or
/// without structure give reliable = false with a message, not an error.
[[nodiscard]] GlobalEstimate estimate_global(const PointCloud& source,
                                             const ReferenceIndex& reference,
                                             const GlobalSettings& global = {},
                                             std::uint64_t seed = 2019);

/// estimate_global (seeded with settings.sampling.seed), then align() from its winner with
/// `settings`. The result carries the estimate in its global_* fields; global_reliable false means
/// no reliable global solution (the transform is then the best guess, or the identity when there
/// was none, and should not be used).
[[nodiscard]] RegistrationResult align_global(const PointCloud& source,
                                              const ReferenceIndex& reference,
                                              const SgdSettings& settings = {},
                                              const GlobalSettings& global = {});

/// The same, building the reference's index (reference_index_for).
[[nodiscard]] RegistrationResult align_global(const PointCloud& source, const PointCloud& reference,
                                              const SgdSettings& settings = {},
                                              const GlobalSettings& global = {});

}  // namespace sgdicp
