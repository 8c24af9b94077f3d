// The odometry's whole map (WholeMap): one centroid per voxel in the map frame, bounded by the
// space covered and not by the frames added, regridding, hostile points; Odometry::keep_whole_map
// on a synthetic sequence with exact ground truth.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "odometry_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/odometry/odometry.hpp"
#include "sgdicp/odometry/whole_map.hpp"

namespace sgdicp {
namespace {

using test::make_transform;

PointCloud cloud_of(std::initializer_list<Eigen::Vector3f> points) {
  PointCloud c;
  c.points = points;
  return c;
}

Eigen::Vector3d stored(const PointCloud& c, std::size_t i) {
  return c.origin_m + c.points[i].cast<double>();
}

TEST(WholeMap, OneCentroidPerVoxelOfTheMovedPoints) {
  WholeMap map(1.0);
  // Moved by +10 m in x: (0.2, 0.5, 0.5) and (0.6, 0.5, 0.5) land in voxel (10, 0, 0), (2.5, ...)
  // in (12, 0, 0).
  const Eigen::Matrix4d T = make_transform(0.0, 0.0, 0.0, {10.0, 0.0, 0.0});
  map.add(cloud_of({{0.2F, 0.5F, 0.5F}, {0.6F, 0.5F, 0.5F}, {2.5F, 0.5F, 0.5F}}), T);
  ASSERT_EQ(map.size(), 2U);
  const PointCloud c = map.cloud();
  EXPECT_NEAR((stored(c, 0) - Eigen::Vector3d(10.4, 0.5, 0.5)).norm(), 0.0, 1e-6);
  EXPECT_NEAR((stored(c, 1) - Eigen::Vector3d(12.5, 0.5, 0.5)).norm(), 0.0, 1e-6);
}

// Its memory follows the space covered: a place seen a thousand times, from poses that move
// within it, holds the voxels of one visit.
TEST(WholeMap, APlaceSeenAgainAddsNoVoxel) {
  std::mt19937_64 rng(5);
  PointCloud frame;
  for (int i = 0; i < 2000; ++i) {
    frame.points.emplace_back(Eigen::Vector3d(test::uniform(rng, -5, 5), test::uniform(rng, -5, 5),
                                              test::uniform(rng, 0, 0.01))
                                  .cast<float>());
  }
  WholeMap map(0.5);
  map.add(frame, Eigen::Matrix4d::Identity());
  const std::size_t voxels = map.size();
  for (int k = 0; k < 1000; ++k) {
    map.add(frame, make_transform(0.0, 0.0, 0.0, {1e-4 * (k % 7), 0.0, 0.0}));
  }
  EXPECT_LE(map.size(), voxels + 40);  // points within 0.6 mm of a boundary may cross it
  EXPECT_LT(map.memory_bytes(), 200 * map.size() + 100000);
}

TEST(WholeMap, RegridMergesCentroidsByTheirWeight) {
  WholeMap map(0.5);
  // Three points in voxel (0, 0, 0) at x 0.1, one in (1, 0, 0) at x 0.7 (0.5 m voxels).
  map.add(
      cloud_of({{0.1F, 0.1F, 0.1F}, {0.1F, 0.1F, 0.1F}, {0.1F, 0.1F, 0.1F}, {0.7F, 0.1F, 0.1F}}),
      Eigen::Matrix4d::Identity());
  ASSERT_EQ(map.size(), 2U);
  EXPECT_THROW(map.regrid(0.25), InvalidSettingsError);
  map.regrid(1.0);
  ASSERT_EQ(map.size(), 1U);
  EXPECT_DOUBLE_EQ(map.voxel_size_m(), 1.0);
  EXPECT_NEAR(stored(map.cloud(), 0).x(), (3 * 0.1 + 0.7) / 4, 1e-6);  // not (0.1 + 0.7) / 2
}

TEST(WholeMap, NonFiniteAndFarPointsAreSkippedAndGeoreferencedOnesKeepMillimetres) {
  EXPECT_THROW(WholeMap(0.0), InvalidSettingsError);
  EXPECT_THROW(WholeMap(std::nan("")), InvalidSettingsError);
  WholeMap map(0.1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  map.add(cloud_of({{nan, 0.0F, 0.0F}, {inf, 0.0F, 0.0F}, {3e38F, 0.0F, 0.0F}}),
          Eigen::Matrix4d::Identity());
  EXPECT_TRUE(map.empty());
  // A frame 5,000 km from the map's origin (UTM-like): its centroid keeps the millimetre.
  PointCloud frame = cloud_of({{0.0123F, 0.0F, 0.0F}});
  frame.origin_m = {5'000'000.0, 2'000'000.0, 100.0};
  map.add(frame, Eigen::Matrix4d::Identity());
  ASSERT_EQ(map.size(), 1U);
  EXPECT_NEAR(stored(map.cloud(), 0).x(), 5'000'000.0123, 1e-4);
}

// The whole map of a run keeps what the local map forgets (the frames beyond max_range of the
// last pose), holds only the registered frames, and lies on the scene: each point within a voxel
// of the true scene in the first frame's coordinates.
TEST(Odometry, TheWholeMapKeepsEveryRegisteredFrameAndNoLostOne) {
  const auto seq = test::synthetic_sequence(10, 0.4, 1.0, 4, 6000);
  OdometrySettings settings;
  settings.max_range_m = 6.0;  // the sensor moves 3.6 m: the first frames' far side is dropped
  Odometry odometry(settings);
  EXPECT_THROW(odometry.keep_whole_map(-1.0), InvalidSettingsError);
  odometry.keep_whole_map();
  PointCloud stranger;  // a ball of points 2 m wide: nothing like the room, lost
  std::mt19937_64 rng(3);
  for (int i = 0; i < 6000; ++i) {
    stranger.points.emplace_back(Eigen::Vector3d(test::uniform(rng, -1, 1),
                                                 test::uniform(rng, -1, 1),
                                                 test::uniform(rng, -1, 1))
                                     .normalized()
                                     .cast<float>());
  }
  for (std::size_t f = 0; f < seq.frames.size(); ++f) {
    if (f == 5) {
      const std::size_t before = odometry.whole_map()->size();
      odometry.register_frame(stranger);
      ASSERT_TRUE(odometry.reports().back().failed);
      EXPECT_EQ(odometry.whole_map()->size(), before);
    }
    odometry.register_frame(seq.frames[f]);
  }
  ASSERT_EQ(odometry.lost_frames(), 1U);
  const WholeMap& map = *odometry.whole_map();
  EXPECT_DOUBLE_EQ(map.voxel_size_m(), odometry.voxel_size_m());
  EXPECT_GT(map.size(), odometry.map_cloud(map.voxel_size_m()).size());

  // The scene in the first frame's coordinates, from the true poses (frame 0 is the identity).
  PointCloud scene;
  for (std::size_t f = 0; f < seq.frames.size(); ++f) {
    const PointCloud seen = transformed(crop_range(seq.frames[f], 0.0, 6.0), seq.T_world_frame[f]);
    scene.points.insert(scene.points.end(), seen.points.begin(), seen.points.end());
  }
  const ReferenceIndex index(scene);
  const PointCloud cloud = map.cloud();
  const auto voxel_sq = static_cast<float>(map.voxel_size_m() * map.voxel_size_m());
  std::size_t off = 0;
  for (const Eigen::Vector3f& p : cloud.points) off += index.nearest(p, voxel_sq) ? 0 : 1;
  EXPECT_EQ(off, 0U) << "of " << cloud.size();
}

}  // namespace
}  // namespace sgdicp
