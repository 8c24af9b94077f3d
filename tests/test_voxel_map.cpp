// The odometry's local map (VoxelMap): its admission rule (a bound per voxel and a spacing between
// a voxel's points), admitted() against add(), its surfaces, and its bounds in space over long
// sequences (the map as an index: test_voxel_hash.cpp).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "sgdicp/core/error.hpp"
#include "sgdicp/odometry/voxel_map.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {
PointCloud cloud_of(std::initializer_list<Eigen::Vector3f> points) {
  PointCloud c;
  c.points = points;
  return c;
}

TEST(VoxelMap, KeepsAtMostTheBoundPerVoxel) {
  VoxelMap map(1.0, 3);  // spacing 1 / sqrt(3) = 0.58 m; the 8 points below are 0.9 m apart
  PointCloud c;
  for (unsigned i = 0; i < 8; ++i) {
    c.points.emplace_back((i & 1U) != 0 ? 0.95F : 0.05F, (i & 2U) != 0 ? 0.95F : 0.05F,
                          (i & 4U) != 0 ? 0.95F : 0.05F);
  }
  c.points.emplace_back(5.5F, 0.5F, 0.5F);
  map.add(c);
  EXPECT_EQ(map.voxels(), 2U);
  EXPECT_EQ(map.size(), 4U);                // 3 of the 8 in voxel (0,0,0), 1 in (5,0,0)
  c.points.back() = {5.05F, 0.05F, 0.05F};  // 0.78 m from (5.5, 0.5, 0.5)
  map.add(c);  // the full voxel takes no more, the other one its new point
  EXPECT_EQ(map.size(), 5U);
  EXPECT_EQ(map.points().size(), 5U);
}

// admitted() names exactly the points add() keeps: random points over a few voxels, some full,
// some filled by the same cloud, one non-finite.
TEST(VoxelMap, AdmittedAreThePointsAddKeeps) {
  std::mt19937_64 rng(4);
  VoxelMap map(1.0, 5);
  for (int round = 0; round < 4; ++round) {
    PointCloud c;
    for (int i = 0; i < 60; ++i) {
      c.points.emplace_back(Eigen::Vector3d(test::uniform(rng, -2, 2), test::uniform(rng, -1, 1),
                                            test::uniform(rng, 0, 1))
                                .cast<float>());
    }
    c.points[7] = Eigen::Vector3f(std::nanf(""), 0.0F, 0.0F);
    const std::vector<std::uint32_t> admitted = map.admitted(c);
    PointCloud expected;
    for (const std::uint32_t i : admitted) expected.points.push_back(c.points[i]);
    const std::vector<Eigen::Vector3f> before = map.points().points;
    const std::size_t size = map.size();
    map.add(c);
    EXPECT_EQ(map.size(), size + admitted.size()) << round;
    // Adding only the admitted points to the map as it was gives the same map.
    VoxelMap rebuilt(1.0, 5);
    rebuilt.add(cloud_of({}));
    PointCloud old;
    old.points = before;
    rebuilt.add(old);
    rebuilt.add(expected);
    auto sorted = [](std::vector<Eigen::Vector3f> v) {
      std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) {
        return std::tie(a.x(), a.y(), a.z()) < std::tie(b.x(), b.y(), b.z());
      });
      return v;
    };
    EXPECT_EQ(sorted(rebuilt.points().points), sorted(map.points().points)) << round;
  }
}

// The spacing rule: a point closer than sqrt(v^2 / N) to a point of its own voxel is not admitted
// (by admitted() and add() alike), one farther is; a point of another voxel, even one of the same
// cell of 2x2x2 voxels, does not count, and neither does a point the same cloud did not admit.
TEST(VoxelMap, APointCloserThanTheSpacingToOneOfItsVoxelIsNotAdmitted) {
  VoxelMap map(1.0, 4);  // spacing 1 / sqrt(4) = 0.5 m
  map.add(cloud_of({{0.1F, 0.1F, 0.1F}}));
  const PointCloud near = cloud_of({{0.5F, 0.1F, 0.1F}});  // 0.4 m from it, in its voxel
  EXPECT_TRUE(map.admitted(near).empty());
  map.add(near);
  EXPECT_EQ(map.size(), 1U);
  const PointCloud far = cloud_of({{0.1F, 0.1F, 0.65F}});  // 0.55 m from it
  EXPECT_EQ(map.admitted(far), std::vector<std::uint32_t>{0});
  map.add(far);
  EXPECT_EQ(map.size(), 2U);
  map.add(cloud_of({{0.9F, 0.9F, 0.1F}}));  // 1.1 m and more from both
  ASSERT_EQ(map.size(), 3U);
  // Voxel (1, 0, 0), of the same cell: 0.2 m from (0.9, 0.9, 0.1), across the voxels' face.
  const PointCloud across = cloud_of({{1.1F, 0.9F, 0.1F}});
  EXPECT_EQ(map.admitted(across), std::vector<std::uint32_t>{0});
  map.add(across);
  EXPECT_EQ(map.size(), 4U);
  EXPECT_EQ(map.voxels(), 2U);

  // Within one cloud: the second point, 0.3 m from the first, is not admitted; the third, 0.6 m
  // from the first and 0.3 m from the second (which did not enter), is.
  VoxelMap fresh(1.0, 4);
  const PointCloud row = cloud_of({{2.1F, 0.1F, 0.1F}, {2.4F, 0.1F, 0.1F}, {2.7F, 0.1F, 0.1F}});
  EXPECT_EQ(fresh.admitted(row), (std::vector<std::uint32_t>{0, 2}));
  fresh.add(row);
  EXPECT_EQ(fresh.size(), 2U);
}

// A surface seen again adds nothing once it is covered: a 2 x 2 m floor sampled on a grid of
// 0.25 m (16 points a voxel of 1 m, every spot of the floor within 0.18 m of one of its voxel's,
// under the spacing of 1 / sqrt(20) = 0.224 m), then seen 50 times more at random spots. Without
// the rule each voxel took 4 more, up to its bound of 20.
TEST(VoxelMap, ARevisitedSurfaceAddsNothingOnceCovered) {
  VoxelMap map(1.0, 20);
  PointCloud grid;
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) {
      grid.points.emplace_back(0.125F + 0.25F * static_cast<float>(i),
                               0.125F + 0.25F * static_cast<float>(j), 0.5F);
    }
  }
  map.add(grid);
  ASSERT_EQ(map.size(), 64U);
  std::mt19937_64 rng(5);
  for (int f = 0; f < 50; ++f) {
    PointCloud c;
    for (int i = 0; i < 200; ++i) {
      c.points.emplace_back(static_cast<float>(test::uniform(rng, 0.0, 2.0)),
                            static_cast<float>(test::uniform(rng, 0.0, 2.0)), 0.5F);
    }
    EXPECT_TRUE(map.admitted(c).empty()) << f;
    map.add(c);
  }
  EXPECT_EQ(map.size(), 64U);
  EXPECT_EQ(map.voxels(), 4U);
}

// A frame whose every point falls in full voxels comes as an empty cloud with no normals: it must
// leave the map's surfaces as they are (it ended them, and the next frame's plane cost failed).
TEST(VoxelMap, AnEmptyCloudKeepsTheSurfaces) {
  VoxelMap map(1.0, 1);
  PointCloud c = cloud_of({{0.5F, 0.5F, 0.5F}, {2.5F, 0.5F, 0.5F}});
  c.normals.assign(2, Eigen::Vector3f::UnitZ());
  map.add(c);
  ASSERT_TRUE(map.points().has_normals());
  const std::vector<std::uint32_t> none = map.admitted(c);
  EXPECT_TRUE(none.empty());  // both voxels are full
  map.add(PointCloud{});
  EXPECT_TRUE(map.points().has_normals());
  EXPECT_NO_THROW(check_reference_prepared(map.index(), CostType::point_to_plane));
  // A cloud with points and without normals still ends them: a cost reads all or none.
  map.add(cloud_of({{4.5F, 0.5F, 0.5F}}));
  EXPECT_FALSE(map.points().has_normals());
}

TEST(VoxelMap, NegativeCoordinatesGetTheirOwnVoxels) {
  VoxelMap map(1.0, 1);
  map.add(cloud_of({{-0.5F, 0.5F, 0.5F}, {0.5F, 0.5F, 0.5F}, {-0.5F, -0.5F, -0.5F}}));
  EXPECT_EQ(map.voxels(), 3U);
}

TEST(VoxelMap, DropsVoxelsBeyondTheRadius) {
  VoxelMap map(0.5, 20);
  map.add(cloud_of({{0, 0, 0}, {3, 0, 0}, {0, 9, 0}, {-20, 0, 0}}));
  map.remove_far_from(Eigen::Vector3d(0, 0, 0), 5.0);
  EXPECT_EQ(map.size(), 2U);
  map.remove_far_from(Eigen::Vector3d(10, 0, 0), 8.0);
  EXPECT_EQ(map.size(), 1U);  // only (3, 0, 0) is within 8 m of (10, 0, 0)
  EXPECT_FLOAT_EQ(map.points().points[0].x(), 3.0F);
}

TEST(VoxelMap, MemoryIsBoundedOverALongSequence) {
  // 200 frames along a 200 m line, each a fresh sample of 41 x 7 voxels of 1 m: the map keeps only
  // the voxels within the radius.
  VoxelMap map(1.0, 5);
  std::mt19937_64 rng(3);
  std::size_t largest = 0;
  for (int f = 0; f < 200; ++f) {
    PointCloud c;
    for (int i = -20; i <= 20; ++i) {
      for (int j = -3; j <= 3; ++j) {
        c.points.emplace_back(Eigen::Vector3d(f + i + test::uniform(rng, 0, 1),
                                              j + test::uniform(rng, 0, 1),
                                              test::uniform(rng, 0, 1))
                                  .cast<float>());
      }
    }
    map.add(c);
    map.remove_far_from(Eigen::Vector3d(f, 0, 0), 10.0);
    largest = std::max(largest, map.size());
  }
  // A cell of 2 x 2 x 2 voxels stays while its first point is within 10 m: at most 23 x 7 voxels
  // (x within 11 m), 5 points each, however long the sequence; and more than 2 a voxel.
  EXPECT_LE(largest, 23U * 7U * 5U);
  EXPECT_GT(largest, 21U * 7U * 2U);
}

TEST(VoxelMap, ASmallSceneWalkedForLongFillsItsVoxelsAndStopsGrowing) {
  // 300 fresh samples of one 4 x 4 m floor, as a sensor circling a room for a long time sees it:
  // no voxel leaves the radius, and the map stops growing once its voxels are full or covered at
  // the spacing (0.5 / sqrt(5) = 0.22 m: a few voxels of this floor hold 4 points, not 5).
  VoxelMap map(0.5, 5);
  std::mt19937_64 rng(11);
  std::size_t after_100 = 0;
  for (int f = 0; f < 300; ++f) {
    PointCloud c;
    for (int i = 0; i < 400; ++i) {
      c.points.emplace_back(static_cast<float>(test::uniform(rng, 0.0, 4.0)),
                            static_cast<float>(test::uniform(rng, 0.0, 4.0)), 0.01F);
    }
    map.add(c);
    map.remove_far_from(Eigen::Vector3d(2, 2, 0), 100.0);
    if (f == 99) after_100 = map.size();
  }
  EXPECT_EQ(map.voxels(), 64U);  // 8 x 8 voxels of 0.5 m
  EXPECT_LE(map.size(), 64U * 5U);
  EXPECT_GE(map.size(), 64U * 4U);
  EXPECT_LE(map.size() - after_100, 64U * 5U / 100U);  // less than 1 % more after frame 100
}

TEST(VoxelMap, RejectsBadSettings) {
  EXPECT_THROW(VoxelMap(0.0, 5), InvalidSettingsError);
  EXPECT_THROW(VoxelMap(std::nan(""), 5), InvalidSettingsError);
  EXPECT_THROW(VoxelMap(1.0, 0), InvalidSettingsError);
}

}  // namespace
}  // namespace sgdicp
