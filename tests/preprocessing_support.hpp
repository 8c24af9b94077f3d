#pragma once
// What the tests of the surfaces (test_preprocessing.cpp) and of the downsampling
// (test_downsampling.cpp) share: uniformly random points in a box.
#include <cstddef>
#include <random>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "test_support.hpp"

namespace sgdicp::test {

/// n points uniformly random in the box [lo, hi).
inline PointCloud random_box(std::mt19937_64& rng, std::size_t n, const Eigen::Vector3d& lo,
                             const Eigen::Vector3d& hi) {
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    c.points.emplace_back(static_cast<float>(uniform(rng, lo.x(), hi.x())),
                          static_cast<float>(uniform(rng, lo.y(), hi.y())),
                          static_cast<float>(uniform(rng, lo.z(), hi.z())));
  }
  return c;
}

}  // namespace sgdicp::test
