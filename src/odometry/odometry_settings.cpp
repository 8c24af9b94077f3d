// The odometry's settings table (odometry_settings_table), which the CLI and Python read, and
// their validation.
#include <algorithm>
#include <cmath>
#include <string>

#include "sgdicp/core/error.hpp"
#include "sgdicp/odometry/odometry.hpp"

namespace sgdicp {

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
       "A registered motion between consecutive frames beyond this is rejected and retried",
       [](const S& s) { return s.max_translation_per_frame_m; },
       [](S& s, double v) { s.max_translation_per_frame_m = v; }},
      {"max-rotation-per-frame",
       false,
       {0.0, 180.0, true},
       "deg",
       "A registered rotation between consecutive frames beyond this is rejected and retried; 180 "
       "= "
       "no bound (a wrong registration is caught by its overlap with the map)",
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

}  // namespace sgdicp
