#pragma once
// Helpers shared by the unit tests: seeded uniform numbers, random rigid transforms and
// temporary directories.
#include <atomic>
#include <filesystem>
#include <random>
#include <string>
#include <system_error>

#include <unistd.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sgdicp::test {

/// Uniform double in [lo, hi) from the generator's raw bits (the same on every standard library).
inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

/// A uniformly random rotation (normalised random quaternion).
inline Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  Eigen::Quaterniond q;
  do {
    q = Eigen::Quaterniond(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1),
                           uniform(rng, -1, 1));
  } while (q.norm() < 1e-3 || q.norm() > 1.0);
  return q.normalized().toRotationMatrix();
}

/// A random rigid transform with each translation component in [-max_translation, max_translation).
inline Eigen::Matrix4d random_rigid(std::mt19937_64& rng, double max_translation) {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t.topLeftCorner<3, 3>() = random_rotation(rng);
  t.topRightCorner<3, 1>() =
      Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)) *
      max_translation;
  return t;
}

/// A fresh directory under the system temp dir, removed with everything in it at the end.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "sgdicp_test") {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            (prefix + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace sgdicp::test
