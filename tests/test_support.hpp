#pragma once
// Helpers shared by the unit tests: seeded uniform numbers, random rigid transforms and
// temporary directories.
#include <atomic>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <system_error>

#include <unistd.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/core/pose.hpp"

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

#ifdef SGDICP_SHARED_DATA
// A file or folder of the benchmark data beside the repository (../shared/data).
inline std::filesystem::path shared_data(const std::string& relative) {
  return std::filesystem::path(SGDICP_SHARED_DATA) / relative;
}
#endif

// Skips the test when a file or folder of the data it reads is missing (../shared/data is not
// part of the repository).
#define SKIP_WITHOUT(path) \
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "missing " << (path)

constexpr double kDeg = std::numbers::pi / 180.0;

// Points on the six faces of a 1 x 1.5 x 0.7 m box (about 2 cm apart, far more than the 1 mm
// noise), with their exact normals.
inline PointCloud box_surface(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const Eigen::Vector3d size(1.0, 1.5, 0.7);
  const double areas[3] = {size.y() * size.z(), size.x() * size.z(), size.x() * size.y()};
  const double total = areas[0] + areas[1] + areas[2];
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const double pick = uniform(rng, 0, total);
    const int axis = pick < areas[0] ? 0 : pick < areas[0] + areas[1] ? 1 : 2;
    Eigen::Vector3d p(uniform(rng, 0, 1), uniform(rng, 0, 1), uniform(rng, 0, 1));
    p[axis] = uniform(rng, 0, 1) < 0.5 ? 0.0 : 1.0;
    cloud.points.push_back(p.cwiseProduct(size).cast<float>());
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();
    normal[axis] = 1.0F;
    cloud.normals.push_back(normal);
  }
  return cloud;
}

// A small man-made scene without symmetries: a floor, two walls, a box and a ball, 60k points
// (about 4 cm apart) with 2 mm noise, in metres.
inline PointCloud synthetic_scene(std::uint64_t seed, std::size_t n = 60000) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0.0F, 1.0F);
  std::normal_distribution<float> noise(0.0F, 0.002F);
  PointCloud cloud;
  cloud.points.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float a = u(rng), b = u(rng);
    Eigen::Vector3f p;
    switch (i % 5) {
      case 0:
        p = {6.0F * a, 4.0F * b, 0.0F};
        break;  // floor
      case 1:
        p = {6.0F * a, 0.0F, 2.5F * b};
        break;  // wall along x
      case 2:
        p = {0.0F, 4.0F * a, 2.5F * b};
        break;  // wall along y
      case 3:
        p = {2.0F + 0.8F * a, 1.5F + 0.5F * b, 0.9F};
        break;    // box top
      default: {  // ball
        const float th = 2.0F * std::numbers::pi_v<float> * a, ph = std::acos(2.0F * b - 1.0F);
        p = Eigen::Vector3f(4.2F, 2.8F, 0.6F) + 0.5F * Eigen::Vector3f(std::sin(ph) * std::cos(th),
                                                                       std::sin(ph) * std::sin(th),
                                                                       std::cos(ph));
      }
    }
    cloud.points.push_back(p + Eigen::Vector3f(noise(rng), noise(rng), noise(rng)));
  }
  return cloud;
}

inline Eigen::Matrix4d make_transform(double roll, double pitch, double yaw,
                                      const Eigen::Vector3d& t) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = rotation_from_rpy(roll, pitch, yaw);
  T.topRightCorner<3, 1>() = t;
  return T;
}

// transformed(cloud, T) is the library's (point_cloud.hpp).

}  // namespace sgdicp::test
