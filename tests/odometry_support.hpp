#pragma once
// A synthetic sequence for the odometry tests: a sensor moving through a room with pillars and
// boxes, each frame the world points within range, re-sampled and noised anew per frame, in the
// sensor's frame; the exact poses come with it.
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"
#include "test_support.hpp"

namespace sgdicp::test {

struct SyntheticSequence {
  std::vector<PointCloud> frames;              ///< in the sensor frame
  std::vector<Eigen::Matrix4d> T_world_frame;  ///< ground truth (frame 0 at the identity)
};

/// A point on the surfaces of the world: 40 x 16 x 4 m room, 12 pillars, 8 boxes.
inline Eigen::Vector3d synthetic_world_point(std::mt19937_64& rng) {
  const double a = uniform(rng, 0, 1), b = uniform(rng, 0, 1);
  const int surface = static_cast<int>(uniform(rng, 0, 6));
  switch (surface) {
    case 0:
      return {-10 + 40 * a, -8 + 16 * b, 0.0};  // floor
    case 1:
      return {-10 + 40 * a, (b < 0.5 ? -8.0 : 8.0), 4 * uniform(rng, 0, 1)};  // long walls
    case 2:
      return {(b < 0.5 ? -10.0 : 30.0), -8 + 16 * a, 4 * uniform(rng, 0, 1)};  // end walls
    case 3: {  // pillars, radius 0.3 m, along both sides
      const int k = static_cast<int>(12 * a);
      const Eigen::Vector2d c(-6 + 3.1 * k, (k % 2 ? 3.5 : -4.2) + 0.3 * (k % 3));
      const double th = 2 * std::numbers::pi * b;
      return {c.x() + 0.3 * std::cos(th), c.y() + 0.3 * std::sin(th), 4 * uniform(rng, 0, 1)};
    }
    default: {  // boxes: 1 m cubes' tops and sides
      const int k = static_cast<int>(8 * uniform(rng, 0, 1));
      const Eigen::Vector3d corner(-4 + 4.3 * k, (k % 2 ? -6.5 : 5.0) + 0.2 * k, 0.0);
      const double c = uniform(rng, 0, 1);
      if (c < 0.33) return corner + Eigen::Vector3d(a, b, 1.0);
      if (c < 0.66) return corner + Eigen::Vector3d(a, 0.0, b);
      return corner + Eigen::Vector3d(0.0, a, b);
    }
  }
}

/// One frame per pose T_world_frame: about `points` world points within `range_m` of the sensor,
/// in its frame, noise sigma `noise_m`, sampled anew per frame.
inline std::vector<PointCloud> synthetic_frames(const std::vector<Eigen::Matrix4d>& T_world_frame,
                                                std::uint64_t seed, std::size_t points = 15000,
                                                double range_m = 15.0, double noise_m = 0.005) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m);
  std::vector<PointCloud> frames;
  for (const Eigen::Matrix4d& T : T_world_frame) {
    const Eigen::Matrix4d T_frame_world = T.inverse();
    PointCloud frame;
    while (frame.size() < points) {
      const Eigen::Vector3d p_world = synthetic_world_point(rng);
      const Eigen::Vector3d p = (T_frame_world * p_world.homogeneous()).head<3>();
      if (p.norm() > range_m) continue;
      frame.points.push_back(
          (p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))).cast<float>());
    }
    frames.push_back(std::move(frame));
  }
  return frames;
}

/// The sensor's start: 1.5 m above the floor of the synthetic world.
inline Eigen::Matrix4d synthetic_start() {
  return make_transform(0, 0, 0, Eigen::Vector3d(0, 0, 1.5));
}

/// `frames` frames moving `step_m` forward and turning `yaw_deg` per frame (a gentle bend), each
/// with about `points` points within `range_m`, noise sigma `noise_m`.
inline SyntheticSequence synthetic_sequence(std::size_t frames, double step_m, double yaw_deg,
                                            std::uint64_t seed, std::size_t points = 15000,
                                            double range_m = 15.0, double noise_m = 0.005) {
  SyntheticSequence out;
  Eigen::Matrix4d T = synthetic_start();
  std::vector<Eigen::Matrix4d> T_world;
  for (std::size_t f = 0; f < frames; ++f) {
    T_world.push_back(T);
    out.T_world_frame.push_back(synthetic_start().inverse() * T);
    // Speed varies a little (accelerating), so the constant-velocity prediction is not exact.
    const double step = step_m * (1.0 + 0.2 * std::sin(0.3 * static_cast<double>(f)));
    T = T * make_transform(0, 0, yaw_deg * kDeg, Eigen::Vector3d(step, 0, 0));
  }
  out.frames = synthetic_frames(T_world, seed, points, range_m, noise_m);
  return out;
}

}  // namespace sgdicp::test
