#pragma once
// Helpers shared by the subcommands of the sgdicp tool.
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "sgdicp/core/error.hpp"
#include "sgdicp/io/depth_image.hpp"
#include "sgdicp/io/io.hpp"
#include "sgdicp/registration/registration.hpp"

namespace sgdicp::cli {

/// A run that finished with an answer that must not be used: main prints the message and exits
/// with the code.
class ExitStatus : public std::runtime_error {
 public:
  ExitStatus(const std::string& message, int code) : std::runtime_error(message), code_(code) {}
  [[nodiscard]] int code() const noexcept { return code_; }

 private:
  int code_;
};

/// register --init global found no reliable global solution (1 is any other error).
inline constexpr int kExitNoGlobalSolution = 3;

/// How a depth image (a .png path) becomes a cloud: --intrinsics, --depth-scale, --max-depth,
/// --min-depth, --pixel-stride, --depth-border (docs/depth.md).
struct DepthOptions {
  std::string intrinsics;  ///< a 3x3 K file or "fx,fy,cx,cy"; empty: camera-intrinsics.txt beside
  DepthImageSettings settings;
};

/// Throws `e` again with the CLI option instead of the DepthImageSettings field it names.
[[noreturn]] void throw_naming_depth_option(const InvalidSettingsError& e);

/// Runs `f`; a bad depth setting it throws (validate(), or a border too wide for the image read)
/// names its CLI option.
template <typename F>
auto naming_depth_options(F&& f) {
  try {
    return f();
  } catch (const InvalidSettingsError& e) {
    throw_naming_depth_option(e);
  }
}

/// The depth-image options, with units and the library's defaults in their help.
void add_depth_options(CLI::App& app, DepthOptions& o);

/// Whether a path is read as a depth image (.png) rather than a point-cloud file.
bool is_depth_image(const std::string& path);

/// Reads a cloud, or back-projects a depth image (.png) with `depth`; rejects an empty one with
/// a message naming the file. Reports dropped points on stderr when verbose.
PointCloud load_cloud(const std::string& path, const std::string& role, bool verbose,
                      const DepthOptions& depth = {});

/// Parses a transform option (--init, --ground-truth): a file holding 12/16 numbers, or the
/// 12/16 numbers inline. Errors name the option.
Eigen::Matrix4d parse_transform_option(const std::string& text, const std::string& option);

/// --picture is always PNG: a name that says otherwise is refused before any work is done.
void check_picture_name(const std::string& path);

nlohmann::json matrix_to_json(const Eigen::Matrix4d& T);

/// Every field of a result (but the trace) as JSON.
nlohmann::json result_to_json(const RegistrationResult& r);

void add_register_command(CLI::App& app);
void add_bench_command(CLI::App& app);
void add_odometry_command(CLI::App& app);
void add_localize_command(CLI::App& app);

}  // namespace sgdicp::cli
