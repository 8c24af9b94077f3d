#pragma once
// Helpers of the nearest-neighbour tests: random clouds and the brute-force answers the indexes
// are checked against.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp::test {

inline float uniformf(std::mt19937_64& rng, double lo, double hi) {
  return static_cast<float>(lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53);
}

inline PointCloud random_cloud(std::mt19937_64& rng, std::size_t n, double half_width) {
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    c.points.emplace_back(uniformf(rng, -half_width, half_width),
                          uniformf(rng, -half_width, half_width),
                          uniformf(rng, -half_width, half_width));
  }
  return c;
}

// The squared distance evaluated exactly as the kd-tree does (float, x then y then z), so that
// distances can be compared for equality.
inline float squared_distance(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  float sum = 0.0F;
  for (int k = 0; k < 3; ++k) {
    const float d = a[k] - b[k];
    sum += d * d;
  }
  return sum;
}

struct Brute {
  std::uint32_t index = 0;
  float squared_distance = std::numeric_limits<float>::infinity();
  int ties = 0;  // other points at exactly the same distance
};

inline Brute brute_force(const PointCloud& cloud, const Eigen::Vector3f& q) {
  Brute best;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const float d = squared_distance(cloud.points[i], q);
    if (d < best.squared_distance) {
      best = {static_cast<std::uint32_t>(i), d, 0};
    } else if (d == best.squared_distance) {
      ++best.ties;
    }
  }
  return best;
}

}  // namespace sgdicp::test
