// Tests of the reference kd-tree (nearest_neighbor.hpp) against brute force.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "nearest_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "test_support.hpp"

namespace {

using sgdicp::Neighbor;
using sgdicp::PointCloud;
using sgdicp::ReferenceIndex;
using sgdicp::test::Brute;
using sgdicp::test::brute_force;
using sgdicp::test::random_cloud;
using sgdicp::test::squared_distance;
using sgdicp::test::uniformf;

class NearestNeighborTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937_64 rng(31);
    cloud_ = random_cloud(rng, 5000, 10.0);
    // Queries inside and around the cloud, some far outside it.
    queries_ = random_cloud(rng, 1800, 12.0).points;
    const PointCloud far = random_cloud(rng, 200, 100.0);
    queries_.insert(queries_.end(), far.points.begin(), far.points.end());
    // Some queries exactly on reference points.
    for (std::size_t i = 0; i < 50; ++i) queries_.push_back(cloud_.points[i * 97]);
    for (const auto& q : queries_) expected_.push_back(brute_force(cloud_, q));
  }

  void check_all(const ReferenceIndex& index) const {
    for (std::size_t i = 0; i < queries_.size(); ++i) {
      const std::optional<Neighbor> n = index.nearest(queries_[i]);
      ASSERT_TRUE(n.has_value()) << "query " << i;
      const Brute& b = expected_[i];
      ASSERT_EQ(n->squared_distance, b.squared_distance) << "query " << i;
      ASSERT_LT(n->index, cloud_.size());
      ASSERT_EQ(squared_distance(cloud_.points[n->index], queries_[i]), b.squared_distance);
      if (b.ties == 0) {
        ASSERT_EQ(n->index, b.index) << "query " << i;
      }
    }
  }

  PointCloud cloud_;
  std::vector<Eigen::Vector3f> queries_;
  std::vector<Brute> expected_;
};

TEST_F(NearestNeighborTest, EqualsBruteForce) {
  const ReferenceIndex index(cloud_);
  EXPECT_EQ(index.size(), cloud_.size());
  check_all(index);
  // Queries on reference points find them at distance 0.
  for (std::size_t i = 0; i < 50; ++i) {
    const auto n = index.nearest(cloud_.points[i * 97]);
    ASSERT_TRUE(n);
    EXPECT_EQ(n->squared_distance, 0.0F);
  }
}

TEST_F(NearestNeighborTest, EqualsBruteForceForOtherLeafSizes) {
  for (const std::size_t leaf : {1U, 3U, 64U, 10000U}) {
    SCOPED_TRACE(leaf);
    const ReferenceIndex index(cloud_, sgdicp::KdTreeSettings{leaf});
    check_all(index);
  }
  EXPECT_THROW(ReferenceIndex(cloud_, sgdicp::KdTreeSettings{0}), sgdicp::InvalidSettingsError);
}

// nearest_within: the brute-force list of points closer than the radius, closest first and ties
// by index, cut to k; the same from the KD-tree and from a voxel hash.
TEST_F(NearestNeighborTest, NearestWithinIsTheBruteForceListCutAtTheRadiusAndAtK) {
  const ReferenceIndex tree(cloud_);
  const ReferenceIndex hash = ReferenceIndex::with_voxel_hash(cloud_, 0.4);
  std::vector<Neighbor> got;
  std::size_t cut_at_k = 0;
  std::size_t cut_at_radius = 0;
  for (std::size_t i = 0; i < queries_.size(); i += 7) {
    const Eigen::Vector3f& q = queries_[i];
    for (const float radius2 : {0.05F, 0.5F, 2.0F}) {
      std::vector<Neighbor> want;
      for (std::uint32_t j = 0; j < cloud_.size(); ++j) {
        const float d2 = squared_distance(cloud_.points[j], q);
        if (d2 < radius2) want.push_back({j, d2});
      }
      std::sort(want.begin(), want.end(), [](const Neighbor& a, const Neighbor& b) {
        return a.squared_distance < b.squared_distance ||
               (a.squared_distance == b.squared_distance && a.index < b.index);
      });
      for (const std::size_t k : {1U, 10U, 65U}) {
        const std::size_t n = std::min(k, want.size());
        (want.size() > k ? cut_at_k : cut_at_radius) += 1;
        for (const ReferenceIndex* index : {&tree, &hash}) {
          index->nearest_within(q, radius2, k, got);
          ASSERT_EQ(got.size(), n) << "query " << i << " radius^2 " << radius2 << " k " << k;
          for (std::size_t r = 0; r < n; ++r) {
            ASSERT_EQ(got[r].index, want[r].index) << "query " << i << " rank " << r;
            ASSERT_EQ(got[r].squared_distance, want[r].squared_distance);
          }
        }
      }
    }
  }
  EXPECT_GT(cut_at_k, 100U);  // both cuts exercised
  EXPECT_GT(cut_at_radius, 100U);
  tree.nearest_within(queries_[0], 0.0F, 10, got);
  EXPECT_TRUE(got.empty());
  tree.nearest_within(queries_[0], 2.0F, 0, got);
  EXPECT_TRUE(got.empty());
}

TEST_F(NearestNeighborTest, MaxDistanceBound) {
  const ReferenceIndex index(cloud_);
  std::mt19937_64 rng(32);
  std::size_t found = 0;
  std::size_t rejected = 0;
  for (std::size_t i = 0; i < queries_.size(); ++i) {
    const Brute& b = expected_[i];
    // Bounds from well inside to well outside the true distance.
    const float bound = b.squared_distance * uniformf(rng, 0.0, 2.0) + uniformf(rng, 0.0, 1e-3);
    const std::optional<Neighbor> n = index.nearest(queries_[i], bound);
    if (b.squared_distance > bound) {
      ASSERT_FALSE(n.has_value()) << "query " << i << ": nearest " << b.squared_distance
                                  << " is beyond the bound " << bound;
      ++rejected;
    } else if (b.squared_distance < bound) {
      ASSERT_TRUE(n.has_value()) << "query " << i << ": nearest " << b.squared_distance
                                 << " is within the bound " << bound;
      ASSERT_EQ(n->squared_distance, b.squared_distance);
      if (b.ties == 0) {
        ASSERT_EQ(n->index, b.index);
      }
      ++found;
    }
  }
  // Both branches were exercised substantially.
  EXPECT_GT(found, queries_.size() / 4);
  EXPECT_GT(rejected, queries_.size() / 4);

  // Right at the boundary, one float step either side.
  for (std::size_t i = 0; i < 200; ++i) {
    const Brute& b = expected_[i];
    if (b.squared_distance == 0.0F) continue;
    const float above = std::nextafter(b.squared_distance, std::numeric_limits<float>::max());
    const float below = std::nextafter(b.squared_distance, 0.0F);
    const auto hit = index.nearest(queries_[i], above);
    ASSERT_TRUE(hit.has_value()) << "query " << i;
    ASSERT_EQ(hit->squared_distance, b.squared_distance);
    ASSERT_FALSE(index.nearest(queries_[i], below).has_value()) << "query " << i;
  }
}

// nearest_and_bound: nearest()'s point at nearest()'s distance, and the second-nearest distance
// (brute force) when it lies within the bound, else the bound itself.
TEST_F(NearestNeighborTest, NearestAndBoundIsNearestWithTheRunnerUp) {
  const ReferenceIndex index(cloud_);
  std::mt19937_64 rng(35);
  std::size_t seconds_within = 0;
  for (std::size_t i = 0; i < queries_.size(); ++i) {
    const Brute& b = expected_[i];
    const float bound = b.squared_distance * uniformf(rng, 0.0, 3.0) + uniformf(rng, 0.0, 1e-2);
    float others = -1.0F;
    const auto got = index.nearest_and_bound(queries_[i], bound, others);
    const auto want = index.nearest(queries_[i], bound);
    ASSERT_EQ(got.has_value(), want.has_value()) << "query " << i;
    if (want) {
      ASSERT_EQ(got->index, want->index) << "query " << i;
      ASSERT_EQ(got->squared_distance, want->squared_distance) << "query " << i;
    }
    float second = std::numeric_limits<float>::infinity();
    for (std::size_t p = 0; p < cloud_.size(); ++p) {
      if (want && p == want->index) continue;
      second = std::min(second, squared_distance(cloud_.points[p], queries_[i]));
    }
    if (second < bound) {
      ASSERT_EQ(others, second) << "query " << i;
      ++seconds_within;
    } else {
      ASSERT_EQ(others, bound) << "query " << i;
    }
  }
  EXPECT_GT(seconds_within, queries_.size() / 4);
}

// On a grid every query has ties; the runner-up query must still break them as nearest() does.
TEST(NearestNeighbor, NearestAndBoundBreaksTiesAsNearest) {
  PointCloud grid;
  for (int x = 0; x < 12; ++x) {
    for (int y = 0; y < 12; ++y) {
      for (int z = 0; z < 12; ++z) grid.points.emplace_back(0.5F * x, 0.5F * y, 0.5F * z);
    }
  }
  const ReferenceIndex index(grid, sgdicp::KdTreeSettings{.leaf_size = 4});
  for (int x = 0; x < 22; ++x) {
    for (int y = 0; y < 22; ++y) {
      const Eigen::Vector3f q(0.25F * x, 0.25F * y, 1.25F);
      float others = 0.0F;
      const auto got = index.nearest_and_bound(q, 10.0F, others);
      const auto want = index.nearest(q, 10.0F);
      ASSERT_TRUE(got && want);
      ASSERT_EQ(got->index, want->index) << x << " " << y;
      EXPECT_EQ(others, got->squared_distance) << "a tie is its own runner-up";
    }
  }
}

TEST_F(NearestNeighborTest, ConcurrentQueriesMatchSingleThreaded) {
  const ReferenceIndex index(cloud_);
  std::vector<std::optional<Neighbor>> single;
  for (const auto& q : queries_) single.push_back(index.nearest(q, 4.0F));

  constexpr int kThreads = 4;
  std::vector<std::vector<std::optional<Neighbor>>> results(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      auto& out = results[static_cast<std::size_t>(t)];
      // Every thread runs every query several times, in its own order.
      for (int round = 0; round < 5; ++round) {
        out.assign(queries_.size(), std::nullopt);
        for (std::size_t k = 0; k < queries_.size(); ++k) {
          // A rotation of the query order, different for each thread.
          const std::size_t n = queries_.size();
          const std::size_t i = (k + static_cast<std::size_t>(t) * n / kThreads) % n;
          out[i] = index.nearest(queries_[i], 4.0F);
        }
      }
    });
  }
  for (auto& th : threads) th.join();
  for (int t = 0; t < kThreads; ++t) {
    const auto& out = results[static_cast<std::size_t>(t)];
    ASSERT_EQ(out.size(), single.size());
    for (std::size_t i = 0; i < single.size(); ++i) {
      ASSERT_EQ(out[i].has_value(), single[i].has_value()) << "thread " << t << " query " << i;
      if (single[i]) {
        ASSERT_EQ(out[i]->index, single[i]->index) << "thread " << t << " query " << i;
        ASSERT_EQ(out[i]->squared_distance, single[i]->squared_distance);
      }
    }
  }
}

TEST_F(NearestNeighborTest, MoveKeepsWorking) {
  ReferenceIndex a(cloud_);
  const sgdicp::BoundingBox box = a.bounding_box();
  ReferenceIndex b(std::move(a));
  EXPECT_EQ(b.size(), cloud_.size());
  EXPECT_EQ(b.bounding_box().min, box.min);
  EXPECT_EQ(b.bounding_box().max, box.max);
  check_all(b);

  // Move assignment over an index of another cloud.
  std::mt19937_64 rng(33);
  ReferenceIndex c(random_cloud(rng, 100, 1.0));
  c = std::move(b);
  EXPECT_EQ(c.size(), cloud_.size());
  check_all(c);

  // Indexes kept in a growing vector (which moves them) stay valid.
  std::vector<ReferenceIndex> many;
  for (int i = 0; i < 5; ++i) many.emplace_back(cloud_);
  for (const auto& index : many) check_all(index);
}

TEST_F(NearestNeighborTest, CloudAndBoundingBox) {
  const ReferenceIndex index(cloud_);
  ASSERT_EQ(index.cloud().size(), cloud_.size());
  for (std::size_t i = 0; i < cloud_.size(); ++i) {
    ASSERT_EQ(index.cloud().points[i], cloud_.points[i]);
  }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& p : cloud_.points) {
    lo = lo.cwiseMin(p.cast<double>());
    hi = hi.cwiseMax(p.cast<double>());
  }
  EXPECT_EQ(index.bounding_box().min, lo);
  EXPECT_EQ(index.bounding_box().max, hi);
}

TEST(NearestNeighbor, SinglePointCloud) {
  PointCloud one;
  one.points.emplace_back(1.0F, 2.0F, 3.0F);
  const ReferenceIndex index(one);
  const auto n = index.nearest(Eigen::Vector3f(1.0F, 2.0F, 5.0F));
  ASSERT_TRUE(n);
  EXPECT_EQ(n->index, 0U);
  EXPECT_EQ(n->squared_distance, 4.0F);
  EXPECT_FALSE(index.nearest(Eigen::Vector3f(1.0F, 2.0F, 5.0F), 3.9F).has_value());
}

TEST(NearestNeighbor, DuplicatePointsAreFine) {
  PointCloud dup;
  for (int i = 0; i < 100; ++i) dup.points.emplace_back(0.5F, 0.5F, 0.5F);
  dup.points.emplace_back(2.0F, 0.5F, 0.5F);
  const ReferenceIndex index(dup);
  const auto n = index.nearest(Eigen::Vector3f(0.0F, 0.5F, 0.5F));
  ASSERT_TRUE(n);
  EXPECT_LT(n->index, 100U);
  EXPECT_EQ(n->squared_distance, 0.25F);
  const auto m = index.nearest(Eigen::Vector3f(3.0F, 0.5F, 0.5F));
  ASSERT_TRUE(m);
  EXPECT_EQ(m->index, 100U);
}

TEST(NearestNeighbor, EmptyCloudThrows) {
  EXPECT_THROW(ReferenceIndex(PointCloud{}), sgdicp::InvalidInputError);
}

TEST(NearestNeighbor, NonFinitePointThrows) {
  std::mt19937_64 rng(34);
  for (const float bad :
       {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
        -std::numeric_limits<float>::infinity()}) {
    for (int axis = 0; axis < 3; ++axis) {
      PointCloud cloud = random_cloud(rng, 100, 1.0);
      cloud.points[57][axis] = bad;
      EXPECT_THROW(ReferenceIndex{cloud}, sgdicp::InvalidInputError) << "axis " << axis;
      try {
        const ReferenceIndex index(cloud);
      } catch (const sgdicp::InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("57"), std::string::npos)
            << "the message should name the point: " << e.what();
      }
    }
  }
}

}  // namespace

namespace sgdicp {
namespace {

// The threaded build splits the top of the tree on the calling thread and builds the subtrees
// below on others (nearest_neighbor.cpp): the same tree as nanoflann's own build, so every
// query gives the same neighbour at the same distance, ties included.
TEST(ReferenceIndex, ThreadedBuildGivesTheSameTree) {
  std::mt19937_64 rng(77);
  PointCloud cloud;
  std::normal_distribution<float> spread(0.0F, 3.0F);  // dense core, sparse rim: uneven splits
  for (int i = 0; i < 150000; ++i) cloud.points.emplace_back(spread(rng), spread(rng), spread(rng));
  for (int i = 0; i < 2000; ++i) cloud.points.push_back(cloud.points[static_cast<std::size_t>(i)]);
  const ReferenceIndex one(cloud, KdTreeSettings{.num_threads = 1});
  std::vector<Neighbor> expected, got;
  for (const std::size_t threads : {2U, 3U, 4U, 7U}) {
    const ReferenceIndex many(cloud, KdTreeSettings{.num_threads = threads});
    std::mt19937_64 queries(5);
    for (int q = 0; q < 3000; ++q) {
      const Eigen::Vector3f p(spread(queries), spread(queries), spread(queries));
      const auto a = one.nearest(p, 4.0F);
      const auto b = many.nearest(p, 4.0F);
      ASSERT_EQ(a.has_value(), b.has_value()) << threads;
      if (a) {
        EXPECT_EQ(a->index, b->index) << threads;
        EXPECT_EQ(a->squared_distance, b->squared_distance) << threads;
      }
      one.k_nearest(p, 12, expected);
      many.k_nearest(p, 12, got);
      ASSERT_EQ(expected.size(), got.size());
      for (std::size_t k = 0; k < got.size(); ++k) EXPECT_EQ(expected[k].index, got[k].index);
    }
  }
}

TEST(ReferenceIndex, BuildThreadsAreChecked) {
  const PointCloud cloud = test::synthetic_scene(3, 100);
  EXPECT_THROW(ReferenceIndex(cloud, KdTreeSettings{.num_threads = 5000}), InvalidSettingsError);
  EXPECT_THROW(ReferenceIndex(cloud, KdTreeSettings{.leaf_size = 0}), InvalidSettingsError);
  EXPECT_NO_THROW(ReferenceIndex(cloud, KdTreeSettings{.num_threads = 0}));
}

}  // namespace
}  // namespace sgdicp
