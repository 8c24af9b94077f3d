#pragma once
// Real datasets of the micro-benchmarks: the first pair of a pairs file in ../shared/data/pairs.
// The data folder is $SGDICP_DATA, else the compile-time SGDICP_BENCH_DATA_DIR. A dataset whose
// files are missing is skipped (with a note on stderr), never an error.
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include <sgdicp/core/point_cloud.hpp>
#include <sgdicp/io/io.hpp>
#include <sgdicp/tools/pairs.hpp>

#ifndef SGDICP_BENCH_DATA_DIR
#define SGDICP_BENCH_DATA_DIR "../shared/data"
#endif

namespace sgdicp::bench {

struct Dataset {
  std::string name;        ///< short name used in benchmark names
  std::string pairs_file;  ///< file in DATA/pairs
  std::filesystem::path source, reference;
  Eigen::Matrix4d T_gt = Eigen::Matrix4d::Identity();
};

inline std::filesystem::path data_dir() {
  if (const char* env = std::getenv("SGDICP_DATA"); env && *env) return env;
  return SGDICP_BENCH_DATA_DIR;
}

/// The first pair of each (name, pairs file) whose files exist.
inline std::vector<Dataset> datasets(
    const std::vector<std::pair<std::string, std::string>>& wanted) {
  std::vector<Dataset> out;
  for (const auto& [name, file] : wanted) {
    const auto path = data_dir() / "pairs" / file;
    try {
      const auto pairs = read_pairs_file(path);
      if (pairs.empty()) throw std::runtime_error("no pairs");
      const auto& p = pairs.front();
      if (!std::filesystem::exists(p.source) || !std::filesystem::exists(p.reference)) {
        throw std::runtime_error("missing cloud file");
      }
      out.push_back({name, file, p.source, p.reference, p.T_reference_source_gt});
    } catch (const std::exception& e) {
      std::cerr << "skipping dataset " << name << " (" << path.string() << "): " << e.what()
                << '\n';
    }
  }
  return out;
}

/// KITTI .bin (124k points), Kinect binary_compressed PCD (271k), car CSV (25k), ETH PLY (38k).
inline std::vector<Dataset> available_datasets() {
  return datasets({
      {"kitti", "kitti_seq00.txt"},
      {"kinect", "pcl_kinect_frames.txt"},
      {"car", "libpointmatcher_car.txt"},
      {"eth", "eth_kinect_map_moved_copies.txt"},
  });
}

/// Reads each file once per process.
inline const PointCloud& cloud(const std::filesystem::path& path) {
  static std::map<std::string, PointCloud> cache;
  const std::string key = path.lexically_normal().string();
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, read_point_cloud(path).cloud).first;
  return it->second;
}

}  // namespace sgdicp::bench
