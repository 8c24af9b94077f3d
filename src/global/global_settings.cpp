// The global registration's settings table (global_settings_table), which the CLI, Python and
// docs/global.md read, and their validation.
#include <string>

#include "registration/setting_rows.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/global/global_registration.hpp"

namespace sgdicp {
namespace {

using detail::setting;
using S = GlobalSettings;

// Ranges: wide enough for any scene (lengths are in feature voxels, so they do not depend on
// its size), narrow enough that no value allocates absurdly or runs without end.
constexpr ValueRange kPoints{10.0, 1e7};
constexpr ValueRange kVoxels{0.0, 1000.0, true};  // (0, 1000]
constexpr ValueRange kFraction{0.0, 1.0};
constexpr ValueRange kPoses{1.0, 1000.0};

std::vector<Setting<S>> make_table() {
  return {
      setting<S, &S::feature_points>(
          {"global-feature-points", "feature_points", kPoints, "points",
           "Both clouds are thinned on one voxel grid (the feature grid) that keeps about this "
           "many reference points; the features, the consensus and the scores work on it, and "
           "every length of the global settings is in its voxels"}),
      setting<S, &S::normal_neighbors>({"global-normal-neighbors",
                                        "normal_neighbors",
                                        {3.0, 1000.0},
                                        "",
                                        "Neighbours of a point's normal on the feature grid"}),
      setting<S, &S::feature_radius_voxels>({"global-feature-radius", "feature_radius_voxels",
                                             kVoxels, "voxels", "FPFH neighbourhood radius"}),
      setting<S, &S::inlier_distance_voxels>(
          {"global-inlier-distance", "inlier_distance_voxels", kVoxels, "voxels",
           "A feature match agrees with a pose, and a source point overlaps the reference in "
           "the coarse score, within this distance"}),
      setting<S, &S::max_iterations>(
          {"global-max-iterations", "max_iterations", {1.0, 1e8}, "", "RANSAC samples at most"}),
      setting<S, &S::confidence>(
          {"global-confidence",
           "confidence",
           {0.0, 1.0, true, true},
           "",
           "RANSAC stops once a sample of matches all agreeing with the best pose would have "
           "been drawn with this probability"}),
      setting<S, &S::hypotheses>({"global-hypotheses", "hypotheses", kPoses, "",
                                  "Distinct poses RANSAC keeps and scores by their overlap"}),
      setting<S, &S::distinct_rotation_deg>(
          {"global-distinct-rotation",
           "distinct_rotation_deg",
           {0.0, 180.0},
           "deg",
           "Two poses closer than this in rotation and than --global-distinct-translation in "
           "translation are the same hypothesis"}),
      setting<S, &S::distinct_translation_voxels>(
          {"global-distinct-translation",
           "distinct_translation_voxels",
           {0.0, 1000.0},
           "voxels",
           "Two poses closer than this in translation and than --global-distinct-rotation in "
           "rotation are the same hypothesis"}),
      setting<S, &S::refined_hypotheses>(
          {"global-refined-hypotheses", "refined_hypotheses", kPoses, "",
           "SGD-ICP refines up to this many hypotheses (best coarse overlap first, those with at "
           "least half the best's) and scores them again at --global-fine-distance: the winner "
           "and the runner-up are decided there"}),
      setting<S, &S::fine_distance_voxels>(
          {"global-fine-distance", "fine_distance_voxels", kVoxels, "voxels",
           "A source point overlaps the reference after the refinement within this distance"}),
      setting<S, &S::ambiguity_ratio>(
          {"global-ambiguity-ratio",
           "ambiguity_ratio",
           {0.0, 1.0, true, false},
           "",
           "A runner-up scoring at least this fraction of the winner's overlap makes the scene "
           "ambiguous (a symmetric object, a repetitive scene): no reliable solution"}),
      setting<S, &S::min_score>(
          {"global-min-score", "min_score", kFraction, "",
           "A winner overlapping less than this fraction of the source is no reliable solution"}),
      setting<S, &S::min_points>({"global-min-points",
                                  "min_points",
                                  {3.0, 1e7},
                                  "points",
                                  "Fewer feature-grid points than this in either cloud: no "
                                  "solution is attempted"}),
  };
}

}  // namespace

const std::vector<Setting<GlobalSettings>>& global_settings_table() {
  static const std::vector<Setting<GlobalSettings>> table = make_table();
  return table;
}

const Setting<GlobalSettings>* find_global_setting(std::string_view name) {
  return detail::find_in(global_settings_table(), name);
}

void GlobalSettings::validate(SettingNames names) const {
  try {
    detail::check_table(*this, global_settings_table(), names);
  } catch (const InvalidSettingsError& e) {
    // SgdSettings has members of the same names (max_iterations): say whose.
    if (names != SettingNames::field) throw;
    throw InvalidSettingsError("GlobalSettings." + std::string(e.what()));
  }
}

}  // namespace sgdicp
