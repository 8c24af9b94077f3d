#include "cli_common.hpp"

#include <filesystem>
#include <iostream>

#include "sgdicp/error.hpp"
#include "sgdicp/transform_io.hpp"

namespace sgdicp::cli {

PointCloud load_cloud(const std::string& path, const std::string& role, bool verbose) {
  ReadResult read = read_point_cloud(path);
  if (read.non_finite_dropped > 0 && verbose) {
    std::cerr << "note: " << path << ": dropped " << read.non_finite_dropped
              << " points with non-finite coordinates\n";
  }
  if (read.cloud.empty()) {
    throw InvalidInputError(path + ": the " + role + " cloud has no finite points");
  }
  return std::move(read.cloud);
}

Eigen::Matrix4d parse_init(const std::string& text) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(text, ec)) return read_transform(text);
  // Inline matrices hold only numbers and separators; anything else was meant as a file name.
  if (text.find_first_not_of("0123456789+-.eE \t\r\n,;[]") != std::string::npos ||
      text.find_first_of("0123456789") == std::string::npos) {
    throw IoError(text + ": no such transform file");
  }
  return parse_transform(text, "--init");
}

nlohmann::json matrix_to_json(const Eigen::Matrix4d& T) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) {
    rows.push_back({T(r, 0), T(r, 1), T(r, 2), T(r, 3)});
  }
  return rows;
}

nlohmann::json result_to_json(const RegistrationResult& r) {
  return {{"transform", matrix_to_json(r.T_reference_source)},
          {"converged", r.converged},
          {"stop_reason", std::string(to_string(r.stop_reason))},
          {"message", r.message},
          {"iterations", r.iterations},
          {"points_processed", r.points_processed},
          {"stages", r.stages},
          {"time_ms", r.time_ms},
          {"evaluated_points", r.evaluated_points},
          {"inliers", r.inliers},
          {"inlier_ratio", r.inlier_ratio},
          {"inlier_rmse_m", r.inlier_rmse_m},
          {"final_max_distance_m", r.final_max_distance_m},
          {"scale_m", r.scale_m},
          {"constraint_ratio", r.constraint_ratio},
          {"degenerate", r.degenerate}};
}

}  // namespace sgdicp::cli
