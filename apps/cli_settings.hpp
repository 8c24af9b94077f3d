#pragma once
// Options shared by `sgdicp register` and `sgdicp bench`: one per setting of the library's table
// (settings.hpp), with its unit, range and default taken from the library, so --help and
// behaviour never disagree; the method table (methods.hpp); and the runner of one method.
#include <map>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/result.hpp"
#include "sgdicp/registration/methods.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp::cli {

/// The options as given on the command line (text, parsed and range-checked by make_method).
struct SettingsOptions {
  std::string preset = "default";
  std::string method = "sgd";
  std::string max_distance_unit = "scaled";
  std::optional<std::string> preconditioner;
  std::optional<std::string> random_ratio;
  /// Setting name (settings.hpp's table) -> the text given for it.
  std::map<std::string, std::string, std::less<>> values;
};

/// --method (one, or with `several` a comma-separated list) and --random-ratio (the voxel grid
/// is a setting of the table: --voxel-size, --downsample-to).
void add_method_options(CLI::App& app, SettingsOptions& o, bool several);
/// --preset, --max-distance-unit, --preconditioner and one option per setting of the table
/// (without --voxel-size and --downsample-to unless with_voxel_grid: odometry thins its frames
/// and map itself).
void add_settings_options(CLI::App& app, SettingsOptions& o, bool with_voxel_grid = true);

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

/// run_method without an initial guess (--init global): align_global on the same index. Only
/// for the SGD methods; throws InvalidSettingsError for a batch method.
[[nodiscard]] MethodRun run_method_global(const MethodSpec& m, const PointCloud& source,
                                          const PointCloud& reference);

}  // namespace sgdicp::cli
