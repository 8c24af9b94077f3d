// Tests of the grids (points/voxel_grid.hpp, points/random_downsample.hpp): voxel centroids in
// first-occurrence order on any thread count, random subsets carrying their attributes.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "points/voxel_table.hpp"
#include "preprocessing_support.hpp"
#include "registration/reference_index.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/points/random_downsample.hpp"
#include "sgdicp/points/voxel_grid.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "sgdicp/surfaces/voxel_surfaces.hpp"

namespace {

using sgdicp::InvalidInputError;
using sgdicp::InvalidSettingsError;
using sgdicp::NeighborhoodSettings;
using sgdicp::PointCloud;
using sgdicp::test::random_box;

// ---------------------------------------------------------------- voxel grid

using Key = std::array<std::int64_t, 3>;

Key key_of(const Eigen::Vector3f& p, double voxel) {
  return {static_cast<std::int64_t>(std::floor(static_cast<double>(p.x()) / voxel)),
          static_cast<std::int64_t>(std::floor(static_cast<double>(p.y()) / voxel)),
          static_cast<std::int64_t>(std::floor(static_cast<double>(p.z()) / voxel))};
}

TEST(VoxelDownsample, CentroidsOfOccupiedVoxelsInFirstOccurrenceOrder) {
  std::mt19937_64 rng(21);
  PointCloud cloud = random_box(rng, 6000, {-5, -3, -2}, {4, 3, 1});
  cloud.normals.assign(cloud.size(), Eigen::Vector3f::UnitZ());
  for (const double voxel : {0.25, 0.7, 3.0}) {
    std::set<Key> occupied;
    std::vector<Key> first_order;
    std::map<Key, std::pair<Eigen::Vector3d, int>> sums;
    for (const auto& p : cloud.points) {
      const Key k = key_of(p, voxel);
      if (occupied.insert(k).second) first_order.push_back(k);
      auto& [sum, count] = sums.try_emplace(k, Eigen::Vector3d::Zero(), 0).first->second;
      sum += p.cast<double>();
      ++count;
    }
    const PointCloud out = sgdicp::voxel_downsample(cloud, voxel);
    ASSERT_EQ(out.size(), occupied.size()) << voxel;
    EXPECT_TRUE(out.normals.empty());
    EXPECT_TRUE(out.covariances.empty());
    for (std::size_t i = 0; i < out.size(); ++i) {
      // The output point lies in the voxel of the points it averages, in first-occurrence order.
      ASSERT_EQ(key_of(out.points[i], voxel), first_order[i]) << voxel << " " << i;
      const auto& [sum, count] = sums.at(first_order[i]);
      EXPECT_LT((out.points[i].cast<double>() - sum / count).norm(), 1e-5) << i;
    }
    const PointCloud again = sgdicp::voxel_downsample(cloud, voxel);
    EXPECT_EQ(again.points, out.points);
  }
}

// Clouds of 32,768 points and more are made in two halves merged in order: the same centroids in
// the same first-occurrence order as one pass over all points, for any thread count.
TEST(VoxelDownsample, HalvesMergeToTheOnePassResultOnAnyThreadCount) {
  std::mt19937_64 rng(22);
  PointCloud cloud = random_box(rng, 100000, {-5, -3, -2}, {4, 3, 1});
  // A second half that adds voxels of its own (beyond x = 4) besides shared ones.
  for (std::size_t i = cloud.size() / 2; i < cloud.size(); i += 3) cloud.points[i].x() += 3.0F;
  // ~20k voxels: the merge looks the second half's up in parts on two threads too.
  const double voxel = 0.2;
  std::map<Key, std::size_t> slot;
  std::vector<std::pair<Eigen::Vector3d, int>> sums;
  for (const auto& p : cloud.points) {
    const auto [it, added] = slot.try_emplace(key_of(p, voxel), sums.size());
    if (added) sums.emplace_back(Eigen::Vector3d::Zero(), 0);
    sums[it->second].first += p.cast<double>();
    ++sums[it->second].second;
  }
  const PointCloud one = sgdicp::voxel_downsample(cloud, voxel, 1);
  ASSERT_EQ(one.size(), sums.size());
  for (std::size_t i = 0; i < one.size(); ++i) {
    const Eigen::Vector3d centroid = sums[i].first / sums[i].second;
    ASSERT_LT((one.points[i].cast<double>() - centroid).norm(), 1e-5) << i;
  }
  EXPECT_EQ(sgdicp::voxel_downsample(cloud, voxel, 2).points, one.points);
  EXPECT_EQ(sgdicp::voxel_downsample(cloud, voxel, 0).points, one.points);
  NeighborhoodSettings settings;
  settings.num_threads = 1;
  const PointCloud surfaces_one = sgdicp::voxel_downsample_with_surfaces(cloud, voxel, settings);
  settings.num_threads = 2;
  const PointCloud surfaces_two = sgdicp::voxel_downsample_with_surfaces(cloud, voxel, settings);
  EXPECT_EQ(surfaces_one.points, one.points);
  EXPECT_EQ(surfaces_two.points, one.points);
  EXPECT_EQ(surfaces_two.normals, surfaces_one.normals);
  EXPECT_EQ(surfaces_two.covariances, surfaces_one.covariances);
  // On two threads a counting pass numbers the voxels at a split its last pass measured as
  // even (any split: the same table), and the sums follow in the fixed halves; the size search
  // (a registration's grid) counts the same way.
  settings.num_threads = 1;
  const auto grid_on = [&](const NeighborhoodSettings& s) {
    return sgdicp::detail::registration_index(cloud, {.voxel_size_m = 0.0, .downsample_to = 2000},
                                              s, true, {});
  };
  const sgdicp::ReferenceIndex grid_one = grid_on(settings);
  ASSERT_GT(grid_one.voxel_size_m(), 0.0);
  settings.num_threads = 2;
  for (const double share : {0.0, 0.2, 0.5, 0.77, 1.0}) {
    SCOPED_TRACE(share);
    sgdicp::detail::counting_share() = share;
    EXPECT_EQ(sgdicp::voxel_downsample(cloud, voxel, 2).points, one.points);
    sgdicp::detail::counting_share() = share;
    EXPECT_EQ(sgdicp::voxel_downsample_with_surfaces(cloud, voxel, settings).covariances,
              surfaces_one.covariances);
    sgdicp::detail::counting_share() = share;
    const sgdicp::ReferenceIndex grid_two = grid_on(settings);
    EXPECT_EQ(grid_two.voxel_size_m(), grid_one.voxel_size_m());
    EXPECT_EQ(grid_two.cloud().points, grid_one.cloud().points);
    EXPECT_EQ(grid_two.cloud().covariances, grid_one.cloud().covariances);
  }
  EXPECT_THROW((void)sgdicp::voxel_downsample(cloud, voxel, 5000), InvalidSettingsError);
}

TEST(VoxelDownsample, NegativeCoordinatesUseFloor) {
  PointCloud cloud;
  // -0.1 and 0.1 straddle 0: truncation towards zero would merge them into one voxel.
  cloud.points = {{-0.1F, 0.5F, 0.5F},  {0.1F, 0.5F, 0.5F},   {-0.3F, 0.5F, 0.5F},
                  {-1.0F, -1.5F, 0.5F}, {-1.2F, -1.5F, 0.5F}, {-0.9F, -1.5F, 0.5F}};
  const PointCloud out = sgdicp::voxel_downsample(cloud, 1.0);
  ASSERT_EQ(out.size(), 4U);
  EXPECT_TRUE(out.points[0].isApprox(Eigen::Vector3f(-0.2F, 0.5F, 0.5F)));
  EXPECT_TRUE(out.points[1].isApprox(Eigen::Vector3f(0.1F, 0.5F, 0.5F)));
  // -1.0 lies on the lower face of voxel x = -1 (with -0.9); -1.2 is alone in x = -2.
  EXPECT_TRUE(out.points[2].isApprox(Eigen::Vector3f(-0.95F, -1.5F, 0.5F)));
  EXPECT_TRUE(out.points[3].isApprox(Eigen::Vector3f(-1.2F, -1.5F, 0.5F)));
}

TEST(VoxelDownsample, CentroidOfPointsOnAVoxelFaceStaysInside) {
  // Many points at the lower face of a voxel and one inside: the float centroid must not round
  // into the neighbouring voxel.
  PointCloud cloud;
  for (int i = 0; i < 1000; ++i) cloud.points.emplace_back(0.3F, 0.6F, 0.9F);
  cloud.points.emplace_back(0.3999F, 0.6F, 0.9F);
  for (const double voxel : {0.1, 0.3, 0.05}) {
    const PointCloud out = sgdicp::voxel_downsample(cloud, voxel);
    std::set<Key> occupied;
    for (const auto& p : cloud.points) occupied.insert(key_of(p, voxel));
    ASSERT_EQ(out.size(), occupied.size());
    for (const auto& p : out.points) EXPECT_TRUE(occupied.count(key_of(p, voxel)) == 1) << voxel;
  }
}

TEST(VoxelDownsample, BadSizesAndOverflowThrow) {
  PointCloud cloud;
  cloud.points = {{1000.0F, 0.0F, -1000.0F}, {1.0F, 2.0F, 3.0F}};
  for (const double voxel : {0.0, -0.5, std::nan(""), HUGE_VAL, -HUGE_VAL}) {
    EXPECT_THROW((void)sgdicp::voxel_downsample(cloud, voxel), InvalidSettingsError) << voxel;
  }
  EXPECT_THROW((void)sgdicp::voxel_downsample(cloud, 1e-300), InvalidSettingsError);
  EXPECT_THROW((void)sgdicp::voxel_downsample(cloud, 1e-16), InvalidSettingsError);
  EXPECT_EQ(sgdicp::voxel_downsample(cloud, 1e-12).size(), 2U);  // 1e15 fits
  EXPECT_EQ(sgdicp::voxel_downsample(cloud, 1e300).size(), 2U);  // voxels 0 and -1
  EXPECT_EQ(sgdicp::voxel_downsample(PointCloud{}, 0.1).size(), 0U);
  cloud.points[1].z() = std::nanf("");
  EXPECT_THROW((void)sgdicp::voxel_downsample(cloud, 0.1), InvalidInputError);
}

// ---------------------------------------------------------------- random subsets

// A cloud whose point i is (i, 0, 0), with normals and covariances that encode i too.
PointCloud indexed_cloud(std::size_t n) {
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    const auto f = static_cast<float>(i);
    c.points.emplace_back(f, 0.0F, 0.0F);
    c.normals.emplace_back(0.0F, f, 0.0F);
    c.covariances.push_back(Eigen::Matrix3f::Constant(f));
  }
  return c;
}

std::vector<std::size_t> indices_of(const PointCloud& c) {
  std::vector<std::size_t> idx;
  for (const auto& p : c.points) idx.push_back(static_cast<std::size_t>(p.x()));
  return idx;
}

TEST(RandomDownsample, DistinctOrderedSubsetCarryingAttributes) {
  const PointCloud cloud = indexed_cloud(1000);
  const PointCloud out = sgdicp::random_downsample(cloud, 137, 42);
  ASSERT_EQ(out.size(), 137U);
  ASSERT_EQ(out.normals.size(), 137U);
  ASSERT_EQ(out.covariances.size(), 137U);
  const auto idx = indices_of(out);
  // Strictly increasing: input order and distinct.
  EXPECT_EQ(std::adjacent_find(idx.begin(), idx.end(), std::greater_equal<>()), idx.end());
  for (std::size_t j = 0; j < out.size(); ++j) {
    ASSERT_LT(idx[j], cloud.size());
    EXPECT_EQ(out.points[j], cloud.points[idx[j]]);
    EXPECT_EQ(out.normals[j], cloud.normals[idx[j]]);
    EXPECT_EQ(out.covariances[j], cloud.covariances[idx[j]]);
  }
  EXPECT_EQ(sgdicp::random_downsample(cloud, 137, 42).points, out.points);
  EXPECT_NE(sgdicp::random_downsample(cloud, 137, 43).points, out.points);

  PointCloud points_only = cloud;
  points_only.normals.clear();
  points_only.covariances.clear();
  const PointCloud bare = sgdicp::random_downsample(points_only, 137, 42);
  EXPECT_EQ(bare.points, out.points);
  EXPECT_TRUE(bare.normals.empty() && bare.covariances.empty());
}

TEST(RandomDownsample, EdgeCountsAndRatio) {
  const PointCloud cloud = indexed_cloud(200);
  for (const std::size_t count : {200UL, 201UL, 100000UL}) {
    const PointCloud all = sgdicp::random_downsample(cloud, count, 1);
    EXPECT_EQ(all.points, cloud.points);
    EXPECT_EQ(all.normals, cloud.normals);
  }
  EXPECT_EQ(sgdicp::random_downsample(cloud, 0, 1).size(), 0U);
  EXPECT_EQ(sgdicp::random_downsample(cloud, 1, 1).size(), 1U);
  EXPECT_EQ(sgdicp::random_downsample(cloud, 199, 1).size(), 199U);
  EXPECT_EQ(sgdicp::random_downsample(PointCloud{}, 5, 1).size(), 0U);

  EXPECT_EQ(sgdicp::random_downsample_ratio(cloud, 0.25, 3).size(), 50U);
  EXPECT_EQ(sgdicp::random_downsample_ratio(cloud, 0.25, 3).points,
            sgdicp::random_downsample(cloud, 50, 3).points);
  EXPECT_EQ(sgdicp::random_downsample_ratio(cloud, 1.0, 3).points, cloud.points);
  EXPECT_EQ(sgdicp::random_downsample_ratio(cloud, 1e-9, 3).size(), 1U);
  for (const double ratio : {0.0, -0.1, 1.0001, std::nan(""), HUGE_VAL}) {
    EXPECT_THROW((void)sgdicp::random_downsample_ratio(cloud, ratio, 3), InvalidSettingsError)
        << ratio;
  }
  PointCloud bad = cloud;
  bad.normals.pop_back();
  EXPECT_THROW((void)sgdicp::random_downsample(bad, 10, 1), InvalidInputError);
  bad = cloud;
  bad.covariances.resize(3);
  EXPECT_THROW((void)sgdicp::random_downsample(bad, 10, 1), InvalidInputError);
}

TEST(RandomDownsample, EveryPointAndPairIsEquallyLikely) {
  // 3 of 8 points over many seeds: each point is chosen with probability 3/8, each pair with
  // 3/28. Bounds are 5 binomial standard deviations.
  const PointCloud cloud = indexed_cloud(8);
  const int trials = 40000;
  std::array<int, 8> singles{};
  std::map<std::pair<std::size_t, std::size_t>, int> pairs;
  for (int t = 0; t < trials; ++t) {
    const auto idx = indices_of(sgdicp::random_downsample(cloud, 3, 1000 + t));
    ASSERT_EQ(idx.size(), 3U);
    for (std::size_t a = 0; a < 3; ++a) {
      ++singles[idx[a]];
      for (std::size_t b = a + 1; b < 3; ++b) ++pairs[{idx[a], idx[b]}];
    }
  }
  const auto within = [&](int observed, double p) {
    const double mean = trials * p;
    return std::abs(observed - mean) < 5.0 * std::sqrt(mean * (1.0 - p));
  };
  for (std::size_t i = 0; i < 8; ++i) EXPECT_TRUE(within(singles[i], 3.0 / 8.0)) << i;
  EXPECT_EQ(pairs.size(), 28U);
  for (const auto& [pair, n] : pairs) {
    EXPECT_TRUE(within(n, 3.0 / 28.0)) << pair.first << "," << pair.second << ": " << n;
  }
}

}  // namespace
