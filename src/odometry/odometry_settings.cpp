// The odometry's settings table (odometry_settings_table), which the CLI and Python read, and
// their validation.
#include <string>

#include "registration/setting_rows.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/odometry/odometry.hpp"

namespace sgdicp {
namespace {

using detail::common;
using detail::setting;
using S = OdometrySettings;

// A length in metres up to a thousand kilometres; 0 where 0 means "derived" (auto).
constexpr ValueRange kLength{0.0, 1e6};
constexpr ValueRange kPositiveLength{0.0, 1e6, true};

std::vector<Setting<S>> make_table() {
  return {
      common(setting<S, &S::max_range_m>(
          {"max-range", "max_range_m", kPositiveLength, "m",
           "Points farther from the sensor are dropped; the map keeps voxels within this radius"})),
      setting<S, &S::min_range_m>(
          {"min-range", "min_range_m", kLength, "m", "Points closer to the sensor are dropped"}),
      common(setting<S, &S::voxel_size_m>(
          {"voxel-size", "voxel_size_m", kLength, "m",
           "Map voxel side (frames thinned to 0.75 of it for the map, 1.5 times it for the "
           "registration); 0 = 1 % of the first frame's 99th-percentile range, grown when the "
           "second frame or half the last 5 see twice as far"})),
      setting<S, &S::max_points_per_voxel>(
          {"max-points-per-voxel",
           "max_points_per_voxel",
           {1.0, 10000.0},
           "",
           "Points a map voxel keeps, at most, no two closer than voxel / sqrt(count)"}),
      setting<S, &S::initial_threshold_m>(
          {"initial-threshold", "initial_threshold_m", kLength, "m",
           "Correspondence threshold sigma before any motion is observed (d_max = 3 sigma); 0 = "
           "2 voxels"}),
      setting<S, &S::min_motion_m>(
          {"min-motion", "min_motion_m", kLength, "m",
           "Deviations from the prediction below this do not adapt the threshold; 0 = voxel / "
           "10"}),
      setting<S, &S::max_translation_per_frame_m>(
          {"max-translation-per-frame", "max_translation_per_frame_m", kLength, "m",
           "A registered motion between consecutive frames beyond this is rejected and "
           "retried; 0 = the frame's own range (99 % of its points lie within it)"}),
      setting<S, &S::max_rotation_per_frame_deg>(
          {"max-rotation-per-frame",
           "max_rotation_per_frame_deg",
           {0.0, 180.0, true},
           "deg",
           "A registered rotation between consecutive frames beyond this is rejected and "
           "retried; 180 = no bound (a wrong registration is caught by its overlap with the "
           "map)"}),
  };
}

}  // namespace

const std::vector<Setting<OdometrySettings>>& odometry_settings_table() {
  static const std::vector<Setting<OdometrySettings>> table = make_table();
  return table;
}

const Setting<OdometrySettings>* find_odometry_setting(std::string_view name) {
  return detail::find_in(odometry_settings_table(), name);
}

void OdometrySettings::validate(SettingNames names) const {
  detail::check_table(*this, odometry_settings_table(), names);
  if (min_range_m >= max_range_m) {
    throw InvalidSettingsError(find_odometry_setting("min-range")->spelled(names) + " " +
                               format_number(min_range_m) + ": must be below " +
                               find_odometry_setting("max-range")->spelled(names) + " " +
                               format_number(max_range_m));
  }
}

}  // namespace sgdicp
