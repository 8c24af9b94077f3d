// Tests of the certified nearest-neighbour memory of a run (src/index/nearest_memory.hpp): every
// answer is the tree's, point and distance bit for bit, whether it came from memory or not.
#include <cstdint>
#include <optional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "index/nearest_memory.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"

namespace sgdicp::detail {
namespace {

struct Tally {
  std::size_t remembered = 0;  // answered without the tree
  std::size_t asked = 0;
};

// Source points that drift as a registration's pose does (big moves first, then small ones),
// each looked up through the memory and in the tree with the same bound, which shrinks and
// widens as d_max does.
Tally drift_and_compare(const PointCloud& reference, std::uint64_t seed) {
  const ReferenceIndex index(reference);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0F, 1.0F);
  constexpr std::size_t kSource = 300;
  std::vector<Eigen::Vector3f> where;
  for (std::size_t i = 0; i < kSource; ++i) where.emplace_back(unit(rng), unit(rng), unit(rng));
  NearestMemory memory(index, kSource);
  Tally tally;
  for (int round = 0; round < 40; ++round) {
    const float step = round < 10 ? 0.05F : (round < 25 ? 0.003F : 0.0003F);
    const float bound = round % 7 == 3 ? 0.5F : (round < 20 ? 0.04F : 0.01F);
    for (std::uint32_t i = 0; i < kSource; ++i) {
      where[i] += step * Eigen::Vector3f(unit(rng), unit(rng), unit(rng));
      NearestMemory::Entry fresh;
      const auto got = memory.nearest(i, where[i], bound, fresh);
      const auto want = index.nearest(where[i], bound);
      EXPECT_EQ(got.has_value(), want.has_value()) << "round " << round << " point " << i;
      if (got && want) {
        EXPECT_EQ(got->index, want->index) << "round " << round << " point " << i;
        EXPECT_EQ(got->squared_distance, want->squared_distance) << "round " << round;
      }
      if (fresh.others_m < 0.0F) {
        ++tally.remembered;
      } else {
        ++tally.asked;
      }
      memory.remember(i, fresh);
    }
  }
  return tally;
}

TEST(NearestMemory, AnswersAsTheTreeWhilePointsDrift) {
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<float> unit(-1.2F, 1.2F);
  PointCloud reference;
  for (int i = 0; i < 4000; ++i) reference.points.emplace_back(unit(rng), unit(rng), unit(rng));
  const Tally tally = drift_and_compare(reference, 42);
  // Most slow-drift lookups are certified; the fast ones and the first need the tree.
  EXPECT_GT(tally.remembered, tally.asked / 2);
  EXPECT_GT(tally.asked, 300U);
}

// A grid: ties everywhere (a tie is never certified, so the tree's tie-break stands), queries
// far from every point (the bound-only certificate), and points that coincide.
TEST(NearestMemory, AnswersAsTheTreeOnAGridWithTies) {
  PointCloud reference;
  for (int x = -5; x <= 5; ++x) {
    for (int y = -5; y <= 5; ++y) {
      for (int z = -5; z <= 5; ++z) reference.points.emplace_back(0.1F * x, 0.1F * y, 0.1F * z);
    }
  }
  for (int i = 0; i < 50; ++i) reference.points.push_back(reference.points[i * 13]);
  const Tally tally = drift_and_compare(reference, 43);
  EXPECT_GT(tally.remembered, 0U);
}

TEST(NearestMemory, FirstLookupAsksTheTree) {
  PointCloud reference;
  reference.points.emplace_back(0.0F, 0.0F, 0.0F);
  reference.points.emplace_back(1.0F, 0.0F, 0.0F);
  const ReferenceIndex index(reference);
  NearestMemory memory(index, 1);
  NearestMemory::Entry fresh;
  const Eigen::Vector3f q(0.1F, 0.0F, 0.0F);
  const auto first = memory.nearest(0, q, 4.0F, fresh);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->index, 0U);
  EXPECT_FLOAT_EQ(fresh.others_m, 0.9F);  // the runner-up, 0.9 m away
  memory.remember(0, fresh);
  // Moved 0.3 m: 0.4 + 0.3 < 0.9, certified without the tree.
  const auto second = memory.nearest(0, Eigen::Vector3f(0.4F, 0.0F, 0.0F), 4.0F, fresh);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->index, 0U);
  EXPECT_LT(fresh.others_m, 0.0F);
  // 0.5 m from where it was asked: 0.6 + 0.5 > 0.9, not certified; the tree finds point 1.
  const auto third = memory.nearest(0, Eigen::Vector3f(0.6F, 0.0F, 0.0F), 4.0F, fresh);
  ASSERT_TRUE(third);
  EXPECT_EQ(third->index, 1U);
  EXPECT_GE(fresh.others_m, 0.0F);
  // Certified (0.3 + 0.2 < 0.9) but beyond the bound: no pair, as the tree says.
  EXPECT_FALSE(memory.nearest(0, Eigen::Vector3f(0.3F, 0.0F, 0.0F), 0.01F, fresh));
}

}  // namespace
}  // namespace sgdicp::detail
