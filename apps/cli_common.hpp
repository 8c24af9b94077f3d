#pragma once
// Helpers shared by the subcommands of the sgdicp tool.
#include <string>

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "sgdicp/io.hpp"
#include "sgdicp/registration.hpp"

namespace sgdicp::cli {

/// Reads a cloud; rejects an empty one with a message naming the file. Reports dropped points
/// on stderr when verbose.
PointCloud load_cloud(const std::string& path, const std::string& role, bool verbose);

/// Parses a transform option (--init, --ground-truth): a file holding 12/16 numbers, or the
/// 12/16 numbers inline. Errors name the option.
Eigen::Matrix4d parse_transform_option(const std::string& text, const std::string& option);

nlohmann::json matrix_to_json(const Eigen::Matrix4d& T);

/// Every field of a result (but the trace) as JSON.
nlohmann::json result_to_json(const RegistrationResult& r);

void add_register_command(CLI::App& app);
void add_bench_command(CLI::App& app);
void add_odometry_command(CLI::App& app);

}  // namespace sgdicp::cli
