#pragma once
// Options shared by `sgdicp register` and `sgdicp bench`: one per setting of the library's table
// (settings.hpp), with its unit, range and default taken from the library, so --help and
// behaviour never disagree; the method table (methods.hpp); and the runner of one method. The
// commands' other tables (the odometry's, the global registration's) become options the same
// way (add_table_options, settings_from_options).
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/result.hpp"
#include "sgdicp/global/global_registration.hpp"
#include "sgdicp/registration/methods.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp::cli {

/// Setting name (a table's) -> the text given for its option.
using OptionValues = std::map<std::string, std::string, std::less<>>;

/// The options as given on the command line (text, parsed and range-checked by make_method).
struct SettingsOptions {
  std::string preset = "default";
  std::string method = "sgd";
  std::string max_distance_unit = "scaled";
  std::optional<std::string> random_ratio;
  /// Setting name (settings.hpp's table) -> the text given for it.
  OptionValues values;
};

/// --method (one, or with `several` a comma-separated list) and --random-ratio (the voxel grid
/// is a setting of the table: --voxel-size, --downsample-to).
void add_method_options(CLI::App& app, SettingsOptions& o, bool several);
/// --preset, --max-distance-unit and one option per setting of the table
/// (without --voxel-size and --downsample-to unless with_voxel_grid: odometry thins its frames
/// and map itself).
void add_settings_options(CLI::App& app, SettingsOptions& o, bool with_voxel_grid = true);

namespace detail {
/// The help of a setting's option without its default: the table's help, then its choices, or
/// its unit and valid range.
[[nodiscard]] std::string option_help(const SettingDescription& s);
/// The value's type in the usage line: UINT, FLOAT, BOOL or {the,choices}.
[[nodiscard]] std::string option_type(const SettingDescription& s);
/// The text of an option as the value of its setting (a distance in `unit`); throws
/// InvalidSettingsError naming the option for text that is not of the setting's kind.
[[nodiscard]] SettingValue option_value(const SettingDescription& s, const std::string& text,
                                        Distance::Unit unit = Distance::Unit::scaled);
/// Range-checks and sets one setting, with the option's name in any error.
template <typename S>
void apply_option(S& settings, const Setting<S>& s, const SettingValue& value) {
  check_range(s, value, SettingNames::cli);
  try {
    s.set(settings, value);
  } catch (const InvalidSettingsError& e) {
    throw InvalidSettingsError(s.spelled(SettingNames::cli) + ": " + e.what());
  }
}
}  // namespace detail

/// One option --NAME per setting of `table` (OdometrySettings', GlobalSettings'), its help from
/// the table with the default read from `defaults`; the text given goes to values[NAME]. With a
/// `group`, --help lists them under that heading.
template <typename S>
void add_table_options(CLI::App& app, const std::vector<Setting<S>>& table, const S& defaults,
                       OptionValues& values, const std::string& group = "") {
  for (const auto& s : table) {
    const std::string name(s.name);
    CLI::Option* option = app.add_option_function<std::string>(
        "--" + name, [&values, name](const std::string& text) { values[name] = text; },
        detail::option_help(s) + " [default: " + format_value(s.get(defaults)) + "]");
    option->type_name(detail::option_type(s));
    if (!group.empty()) option->group(group);
  }
}

/// `base` with the options of `values` (add_table_options) parsed and set in table order, then
/// validated; throws InvalidSettingsError naming the option, as spelled on the command line.
template <typename S>
[[nodiscard]] S settings_from_options(S base, const std::vector<Setting<S>>& table,
                                      const OptionValues& values) {
  for (const auto& s : table) {
    const auto given = values.find(s.name);
    if (given != values.end()) {
      detail::apply_option(base, s, detail::option_value(s, given->second));
    }
  }
  base.validate(SettingNames::cli);
  return base;
}

/// One method of --method with all its settings resolved.
struct MethodSpec {
  std::string name;
  bool stochastic = true;
  SgdSettings sgd;
  BatchSettings batch;
  std::optional<double> random_ratio;
};

/// Resolves a --method name with the shared options. Throws InvalidSettingsError naming the
/// option as spelled on the command line, with its valid range.
[[nodiscard]] MethodSpec make_method(const std::string& name, const SettingsOptions& o);

struct MethodRun {
  RegistrationResult result;
  /// Random thinning + the reference's voxel grid + KD-tree build + batch methods' reference
  /// normals/covariances (the source's grid is inside the registration's time_ms).
  double prepare_ms = 0.0;
  std::size_t source_points = 0;
  std::size_t reference_points = 0;
};

/// Runs one method: downsampling (if asked), KD-tree, reference normals or covariances,
/// registration; all but file I/O is timed.
[[nodiscard]] MethodRun run_method(const MethodSpec& m, const PointCloud& source,
                                   const PointCloud& reference, const Eigen::Matrix4d& T_init,
                                   bool record_trace = false);

/// run_method without an initial guess (--init global): align_global on the same index, with
/// `global`. Only for the SGD methods; throws InvalidSettingsError for a batch method.
[[nodiscard]] MethodRun run_method_global(const MethodSpec& m, const PointCloud& source,
                                          const PointCloud& reference,
                                          const GlobalSettings& global);

}  // namespace sgdicp::cli
