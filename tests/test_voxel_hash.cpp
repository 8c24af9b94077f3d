// Tests of the voxel-hash backend of ReferenceIndex (with_voxel_hash) against brute force and
// against the KD-tree: every query gives the tree's answer, ties between points at the same
// distance aside, for cells much smaller and much larger than the query distances.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "nearest_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/io/io.hpp"
#include "sgdicp/odometry/voxel_map.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

using test::brute_force;
using test::random_cloud;
using test::squared_distance;
using test::uniformf;

constexpr float kUnbounded = std::numeric_limits<float>::max();

// Whether another point of `cloud` lies at exactly `d` from q (then either may be the answer).
bool tied(const PointCloud& cloud, const Eigen::Vector3f& q, float d, std::uint32_t index) {
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (i != index && squared_distance(cloud.points[i], q) == d) return true;
  }
  return false;
}

void expect_same_nearest(const ReferenceIndex& tree, const ReferenceIndex& hash,
                         const Eigen::Vector3f& q, float max_sq) {
  const auto want = tree.nearest(q, max_sq);
  const auto got = hash.nearest(q, max_sq);
  ASSERT_EQ(got.has_value(), want.has_value()) << "bound " << max_sq;
  if (!want) return;
  ASSERT_EQ(got->squared_distance, want->squared_distance) << "bound " << max_sq;
  if (got->index != want->index) {
    ASSERT_TRUE(tied(tree.cloud(), q, want->squared_distance, want->index));
  }
}

// nearest_and_bound: the hash's own nearest() point, the tree's distance, the tree's runner-up
// distance (the exact second nearest within the bound, else the bound).
void expect_same_nearest_and_bound(const ReferenceIndex& tree, const ReferenceIndex& hash,
                                   const Eigen::Vector3f& q, float max_sq) {
  float want_others = -1.0F;
  float got_others = -2.0F;
  const auto want = tree.nearest_and_bound(q, max_sq, want_others);
  const auto got = hash.nearest_and_bound(q, max_sq, got_others);
  const auto plain = hash.nearest(q, max_sq);
  ASSERT_EQ(got.has_value(), want.has_value()) << "bound " << max_sq;
  ASSERT_EQ(got_others, want_others) << "bound " << max_sq;
  if (!want) return;
  ASSERT_EQ(got->squared_distance, want->squared_distance);
  ASSERT_TRUE(plain.has_value());
  ASSERT_EQ(got->index, plain->index) << "ties broken as nearest() breaks them";
}

void expect_same_k_nearest(const ReferenceIndex& tree, const ReferenceIndex& hash,
                           const Eigen::Vector3f& q, std::size_t k) {
  std::vector<Neighbor> want;
  std::vector<Neighbor> got;
  tree.k_nearest(q, k, want);
  hash.k_nearest(q, k, got);
  ASSERT_EQ(got.size(), want.size()) << "k " << k;
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got[i].squared_distance, want[i].squared_distance) << "k " << k << " rank " << i;
    const bool tie =
        (i > 0 && want[i - 1].squared_distance == want[i].squared_distance) ||
        (i + 1 < want.size() && want[i + 1].squared_distance == want[i].squared_distance) ||
        (i + 1 == want.size() && tied(tree.cloud(), q, want[i].squared_distance, want[i].index));
    if (!tie) {
      ASSERT_EQ(got[i].index, want[i].index) << "k " << k << " rank " << i;
    }
  }
}

// Every query of `queries`, bounded at each of `bounds` (squared, metres^2) and unbounded.
void expect_hash_is_tree(const PointCloud& cloud, const std::vector<Eigen::Vector3f>& queries,
                         double cell_m, const std::vector<float>& bounds) {
  SCOPED_TRACE("cell " + std::to_string(cell_m));
  const ReferenceIndex tree(cloud);
  const ReferenceIndex hash = ReferenceIndex::with_voxel_hash(cloud, cell_m);
  ASSERT_EQ(hash.size(), cloud.size());
  for (std::size_t i = 0; i < queries.size(); ++i) {
    SCOPED_TRACE("query " + std::to_string(i));
    const Eigen::Vector3f& q = queries[i];
    expect_same_nearest(tree, hash, q, kUnbounded);
    for (const float b : bounds) {
      expect_same_nearest(tree, hash, q, b);
      expect_same_nearest_and_bound(tree, hash, q, b);
    }
    expect_same_nearest_and_bound(tree, hash, q, kUnbounded);
    for (const std::size_t k : {1U, 5U, 20U}) expect_same_k_nearest(tree, hash, q, k);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

// Queries inside and around the cloud's cube of half-width w, a few far outside, a few on points.
std::vector<Eigen::Vector3f> queries_around(const PointCloud& cloud, double w, std::uint64_t seed,
                                            std::size_t n) {
  std::mt19937_64 rng(seed);
  std::vector<Eigen::Vector3f> queries = random_cloud(rng, n, 1.2 * w).points;
  const PointCloud far = random_cloud(rng, n / 20 + 1, 20.0 * w);
  queries.insert(queries.end(), far.points.begin(), far.points.end());
  for (std::size_t i = 0; i < cloud.size(); i += cloud.size() / 20 + 1) {
    queries.push_back(cloud.points[i]);
  }
  return queries;
}

TEST(VoxelHash, RandomCloudEqualsBruteForce) {
  std::mt19937_64 rng(41);
  const PointCloud cloud = random_cloud(rng, 5000, 10.0);  // ~0.6 m apart
  const std::vector<Eigen::Vector3f> queries = queries_around(cloud, 10.0, 42, 1000);
  for (const double cell : {0.05, 0.5, 2.0, 50.0}) {
    const ReferenceIndex hash = ReferenceIndex::with_voxel_hash(cloud, cell);
    for (const auto& q : queries) {
      const test::Brute b = brute_force(cloud, q);
      const auto got = hash.nearest(q);
      ASSERT_TRUE(got.has_value());
      ASSERT_EQ(got->squared_distance, b.squared_distance) << "cell " << cell;
      if (b.ties == 0) {
        ASSERT_EQ(got->index, b.index) << "cell " << cell;
      }
    }
  }
}

TEST(VoxelHash, RandomCloudEqualsTree) {
  std::mt19937_64 rng(43);
  const PointCloud cloud = random_cloud(rng, 4000, 10.0);
  const std::vector<Eigen::Vector3f> queries = queries_around(cloud, 10.0, 44, 600);
  // Cells from a tenth of the spacing of the points to larger than the whole cloud.
  for (const double cell : {0.06, 0.3, 1.0, 3.0, 40.0}) {
    expect_hash_is_tree(cloud, queries, cell, {1e-4F, 0.04F, 0.5F, 4.0F});
  }
}

// Dense blobs with a sparse rim, and duplicated points: cells of very uneven counts.
TEST(VoxelHash, ClusteredCloudEqualsTree) {
  std::mt19937_64 rng(45);
  PointCloud cloud;
  for (int blob = 0; blob < 6; ++blob) {
    const Eigen::Vector3f centre(uniformf(rng, -8, 8), uniformf(rng, -8, 8), uniformf(rng, -8, 8));
    std::normal_distribution<float> spread(0.0F, blob % 2 == 0 ? 0.05F : 0.8F);
    for (int i = 0; i < 700; ++i) {
      cloud.points.push_back(centre + Eigen::Vector3f(spread(rng), spread(rng), spread(rng)));
    }
  }
  for (int i = 0; i < 300; ++i)
    cloud.points.push_back(cloud.points[static_cast<std::size_t>(7 * i)]);
  const std::vector<Eigen::Vector3f> queries = queries_around(cloud, 9.0, 46, 500);
  for (const double cell : {0.02, 0.25, 1.5, 30.0}) {
    expect_hash_is_tree(cloud, queries, cell, {1e-3F, 0.1F, 2.0F});
  }
}

// On a grid every query has ties; the hash's nearest_and_bound breaks them as its nearest().
TEST(VoxelHash, GridWithTies) {
  PointCloud grid;
  for (int x = 0; x < 10; ++x) {
    for (int y = 0; y < 10; ++y) {
      for (int z = 0; z < 10; ++z) grid.points.emplace_back(0.5F * x, 0.5F * y, 0.5F * z);
    }
  }
  std::vector<Eigen::Vector3f> queries;
  for (int x = -2; x < 22; ++x) {
    for (int y = -2; y < 22; ++y) queries.emplace_back(0.25F * x, 0.25F * y, 1.25F);
  }
  for (const double cell : {0.25, 0.5, 0.7, 5.0}) {
    expect_hash_is_tree(grid, queries, cell, {0.01F, 0.0625F, 0.3F});
  }
}

// Two hand-held LiDAR scans, as the odometry's map holds them: cells of the map's voxel size.
TEST(VoxelHash, RealScansEqualTree) {
  const auto folder = test::shared_data("balm_handheld_lidar/scans");
  if (!std::filesystem::exists(folder)) GTEST_SKIP() << "missing " << folder;
  PointCloud cloud = read_point_cloud(folder / "000100.bin").cloud;
  const PointCloud second = read_point_cloud(folder / "000110.bin").cloud;
  cloud.points.insert(cloud.points.end(), second.points.begin(), second.points.end());
  ASSERT_GT(cloud.size(), 10000U);
  // Queries on the scans, moved by up to half a metre (as a source point near the map is).
  std::mt19937_64 rng(47);
  std::vector<Eigen::Vector3f> queries;
  for (int i = 0; i < 400; ++i) {
    const auto& p = cloud.points[static_cast<std::size_t>(rng() % cloud.size())];
    queries.push_back(p + Eigen::Vector3f(uniformf(rng, -0.5, 0.5), uniformf(rng, -0.5, 0.5),
                                          uniformf(rng, -0.5, 0.5)));
  }
  for (const double cell : {0.05, 0.25, 1.0, 8.0}) {
    expect_hash_is_tree(cloud, queries, cell, {0.0025F, 0.09F, 1.0F});
  }
}

// The odometry map grows and shrinks its index in place. A plain model of its rule (a cell of
// 2x2x2 voxels per std::map entry; a point enters while its voxel holds fewer than the bound and
// none of its points lies within voxel / sqrt(bound) of it; a cell goes when its first point lies
// beyond the radius) says which points it must hold after
// each frame; its index must answer as a tree built afresh over them, and every point's normal
// must still be its own after the gaps of evicted cells were filled.
namespace map_model {
using Key = std::array<std::int64_t, 3>;
struct Cell {
  std::vector<Eigen::Vector3f> points;
  std::map<Key, std::vector<Eigen::Vector3f>> per_voxel;
};
Key floor_key(const Eigen::Vector3f& p, double size_m) {
  return {static_cast<std::int64_t>(std::floor(static_cast<double>(p.x()) / size_m)),
          static_cast<std::int64_t>(std::floor(static_cast<double>(p.y()) / size_m)),
          static_cast<std::int64_t>(std::floor(static_cast<double>(p.z()) / size_m))};
}
Eigen::Vector3f normal_of(const Eigen::Vector3f& p) {  // a normal that names its point
  return Eigen::Vector3f(p.x(), p.y() + 100.0F, p.z()).normalized();
}
std::vector<Eigen::Vector3f> sorted(std::vector<Eigen::Vector3f> v) {
  std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) {
    return std::tie(a.x(), a.y(), a.z()) < std::tie(b.x(), b.y(), b.z());
  });
  return v;
}
}  // namespace map_model

// The coarse view of a map answers as a tree over the first point each voxel received (in the
// model, the first of the cell's points in that voxel), with the map's own point indices.
void expect_coarse_view_of_first_points(const std::map<map_model::Key, map_model::Cell>& model,
                                        double voxel_m, const ReferenceIndex& index,
                                        const Eigen::Vector3f& centre, std::uint64_t seed) {
  PointCloud firsts;
  for (const auto& [key, cell] : model) {
    std::map<map_model::Key, bool> seen;
    for (const Eigen::Vector3f& p : cell.points) {
      if (!seen[map_model::floor_key(p, voxel_m)]) firsts.points.push_back(p);
      seen[map_model::floor_key(p, voxel_m)] = true;
    }
  }
  const ReferenceIndex* coarse = index.coarse_view();
  ASSERT_NE(coarse, nullptr);
  EXPECT_EQ(coarse->coarse_view(), nullptr);
  EXPECT_EQ(&coarse->cloud(), &index.cloud()) << "the same cloud, the same indices";
  const ReferenceIndex tree(firsts);
  for (const Eigen::Vector3f& around : queries_around(firsts, 4.0, seed, 200)) {
    const Eigen::Vector3f q = around + centre;
    for (const float bound : {std::numeric_limits<float>::max(), 0.04F}) {
      const auto want = tree.nearest(q, bound);
      const auto got = coarse->nearest(q, bound);
      ASSERT_EQ(got.has_value(), want.has_value());
      if (!want) continue;
      ASSERT_EQ(got->squared_distance, want->squared_distance);
      ASSERT_EQ(index.cloud().points[got->index], firsts.points[want->index]);
    }
    float want_others = 0.0F;
    float got_others = 0.0F;
    const auto want = tree.nearest_and_bound(q, 1.0F, want_others);
    const auto got = coarse->nearest_and_bound(q, 1.0F, got_others);
    ASSERT_EQ(got.has_value(), want.has_value());
    ASSERT_EQ(got_others, want_others);
  }
}

TEST(VoxelHash, AMapGrownAndEvictedInPlaceHoldsThePointsOfItsRuleAndAnswersAsATree) {
  using namespace map_model;
  constexpr double kVoxel = 0.25;
  constexpr std::size_t kBound = 3;
  constexpr double kRadius = 4.0;
  const double spacing_m = kVoxel / std::sqrt(static_cast<double>(kBound));
  const auto kSpacingSq = static_cast<float>(spacing_m * spacing_m);
  std::mt19937_64 rng(7);
  VoxelMap map(kVoxel, kBound);
  std::map<Key, Cell> model;
  for (int frame = 0; frame < 12; ++frame) {
    SCOPED_TRACE("frame " + std::to_string(frame));
    const Eigen::Vector3d centre(0.7 * frame, 0.2 * frame, 0.0);
    PointCloud c = random_cloud(rng, 1500, 3.0);
    for (auto& p : c.points) p += centre.cast<float>();
    for (const auto& p : c.points) c.normals.push_back(normal_of(p));
    map.add(c);
    for (const auto& p : c.points) {
      Cell& cell = model[floor_key(p, 2.0 * kVoxel)];
      std::vector<Eigen::Vector3f>& held = cell.per_voxel[floor_key(p, kVoxel)];
      const bool spaced = std::none_of(held.begin(), held.end(), [&](const Eigen::Vector3f& h) {
        return (h - p).squaredNorm() < kSpacingSq;
      });
      if (held.size() < kBound && spaced) {
        held.push_back(p);
        cell.points.push_back(p);
      }
    }
    map.remove_far_from(centre, kRadius);
    std::erase_if(model, [&](const auto& entry) {
      return (entry.second.points.front().template cast<double>() - centre).norm() > kRadius;
    });

    std::vector<Eigen::Vector3f> want;
    for (const auto& [key, cell] : model)
      want.insert(want.end(), cell.points.begin(), cell.points.end());
    const PointCloud& held = map.points();
    ASSERT_EQ(sorted(held.points), sorted(want));
    ASSERT_TRUE(held.has_normals());
    for (std::size_t i = 0; i < held.size(); ++i) {
      ASSERT_EQ(held.normals[i], normal_of(held.points[i])) << "point " << i;
    }
    const ReferenceIndex tree(held);
    const ReferenceIndex index = map.index();
    for (const Eigen::Vector3f& q : queries_around(held, 4.0, 100 + frame, 200)) {
      const Eigen::Vector3f shifted = q + centre.cast<float>();
      expect_same_nearest(tree, index, shifted, kUnbounded);
      expect_same_nearest(tree, index, shifted, 0.04F);
      expect_same_nearest_and_bound(tree, index, shifted, 1.0F);
      expect_same_k_nearest(tree, index, shifted, 10);
      if (HasFatalFailure()) return;
    }
    expect_coarse_view_of_first_points(model, kVoxel, index, centre.cast<float>(), 300 + frame);
    if (HasFatalFailure()) return;
  }
}

TEST(VoxelHash, AMapViewRefusesSurfacesOfItsOwnAndAnEmptyMap) {
  VoxelMap map(0.5, 2);
  EXPECT_THROW((void)map.index(), InvalidInputError);
  PointCloud two;
  two.points = {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0)};
  map.add(two);
  ReferenceIndex index = map.index();
  EXPECT_EQ(index.size(), 2U);
  EXPECT_THROW(index.set_normals_and_covariances({}, {}), InvalidInputError);
  map.remove_far_from(Eigen::Vector3d(50, 0, 0), 1.0);
  EXPECT_TRUE(map.empty());
  EXPECT_THROW((void)map.index(), InvalidInputError);
}

TEST(VoxelHash, KeepsTheCloudAsGiven) {
  std::mt19937_64 rng(48);
  PointCloud cloud = random_cloud(rng, 300, 2.0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    cloud.normals.push_back(Eigen::Vector3f::UnitZ() * static_cast<float>(i));
    cloud.covariances.push_back(Eigen::Matrix3f::Identity() * static_cast<float>(i));
  }
  const ReferenceIndex tree(cloud);
  ReferenceIndex hash = ReferenceIndex::with_voxel_hash(cloud, 0.5);
  EXPECT_EQ(hash.cloud().points, cloud.points);
  EXPECT_EQ(hash.cloud().normals, cloud.normals);
  EXPECT_EQ(hash.cloud().covariances, cloud.covariances);
  EXPECT_EQ(hash.voxel_size_m(), 0.0)
      << "the cell thins nothing: align() takes its source as given";
  EXPECT_EQ(hash.voxel_hash_cell_m(), 0.5);
  EXPECT_EQ(tree.voxel_hash_cell_m(), 0.0);
  EXPECT_EQ(hash.bounding_box().min, tree.bounding_box().min);
  EXPECT_EQ(hash.bounding_box().max, tree.bounding_box().max);

  const ReferenceIndex moved(std::move(hash));
  const auto n = moved.nearest(cloud.points[17]);
  ASSERT_TRUE(n.has_value());
  EXPECT_EQ(n->squared_distance, 0.0F);
}

TEST(VoxelHash, SinglePointAndFarQueries) {
  PointCloud one;
  one.points.emplace_back(1.0F, 2.0F, 3.0F);
  const ReferenceIndex hash = ReferenceIndex::with_voxel_hash(one, 0.1);
  const auto n = hash.nearest(Eigen::Vector3f(1.0F, 2.0F, 5.0F));
  ASSERT_TRUE(n);
  EXPECT_EQ(n->squared_distance, 4.0F);
  EXPECT_FALSE(hash.nearest(Eigen::Vector3f(1.0F, 2.0F, 5.0F), 3.9F).has_value());
  const auto far = hash.nearest(Eigen::Vector3f(-1e6F, 3e7F, 1e5F));
  ASSERT_TRUE(far);
  EXPECT_EQ(far->index, 0U);
  std::vector<Neighbor> k;
  hash.k_nearest(Eigen::Vector3f(5.0F, 5.0F, 5.0F), 3, k);
  ASSERT_EQ(k.size(), 1U);
}

// Queries with a NaN or infinite coordinate find nothing, as with the tree.
TEST(VoxelHash, NonFiniteQueriesFindNothing) {
  std::mt19937_64 rng(49);
  const PointCloud cloud = random_cloud(rng, 200, 1.0);
  const ReferenceIndex tree(cloud);
  const ReferenceIndex hash = ReferenceIndex::with_voxel_hash(cloud, 0.2);
  for (const float bad :
       {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    const Eigen::Vector3f q(0.0F, bad, 0.0F);
    EXPECT_EQ(hash.nearest(q).has_value(), tree.nearest(q).has_value());
    float hash_others = 0.0F;
    float tree_others = 0.0F;
    EXPECT_FALSE(hash.nearest_and_bound(q, 1.0F, hash_others).has_value());
    (void)tree.nearest_and_bound(q, 1.0F, tree_others);
    EXPECT_EQ(hash_others, tree_others);
    std::vector<Neighbor> a;
    std::vector<Neighbor> b;
    hash.k_nearest(q, 4, a);
    tree.k_nearest(q, 4, b);
    EXPECT_EQ(a.size(), b.size());
  }
}

TEST(VoxelHash, BadInputThrows) {
  EXPECT_THROW((void)ReferenceIndex::with_voxel_hash(PointCloud{}, 1.0), InvalidInputError);
  std::mt19937_64 rng(50);
  PointCloud cloud = random_cloud(rng, 100, 10.0);
  for (const double cell : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                            std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW((void)ReferenceIndex::with_voxel_hash(cloud, cell), InvalidSettingsError) << cell;
  }
  // A cell a billionth of the extent: refused before anything is allocated for it.
  EXPECT_THROW((void)ReferenceIndex::with_voxel_hash(cloud, 2e-8), InvalidSettingsError);
  EXPECT_NO_THROW((void)ReferenceIndex::with_voxel_hash(cloud, 2e-4));
  cloud.points[57].y() = std::numeric_limits<float>::quiet_NaN();
  try {
    (void)ReferenceIndex::with_voxel_hash(cloud, 1.0);
    ADD_FAILURE() << "a NaN point was indexed";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("57"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sgdicp
