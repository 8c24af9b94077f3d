// Tests of the mini-batch sampler (sampler.hpp): sampling without replacement in epochs
// (paper Algorithm 1 line 2), seeded and reproducible.
#include <algorithm>
#include <cstdint>
#include <map>
#include <numeric>
#include <vector>

#include <gtest/gtest.h>

#include "sgdicp/core/error.hpp"
#include "sgdicp/solver/sampler.hpp"

namespace {

using sgdicp::EpochSampler;

std::vector<std::uint32_t> draw(EpochSampler& sampler, std::size_t batch_size,
                                std::size_t batches) {
  std::vector<std::uint32_t> all;
  std::vector<std::uint32_t> batch;
  for (std::size_t i = 0; i < batches; ++i) {
    sampler.next_batch(batch_size, batch);
    EXPECT_EQ(batch.size(), batch_size);
    all.insert(all.end(), batch.begin(), batch.end());
  }
  return all;
}

std::vector<std::uint32_t> identity(std::uint32_t n) {
  std::vector<std::uint32_t> v(n);
  std::iota(v.begin(), v.end(), 0U);
  return v;
}

bool is_permutation_window(const std::vector<std::uint32_t>& draws, std::size_t begin,
                           std::uint32_t n) {
  std::vector<int> count(n, 0);
  for (std::size_t i = begin; i < begin + n; ++i) {
    if (draws[i] >= n) return false;
    if (++count[draws[i]] != 1) return false;
  }
  return true;
}

TEST(EpochSampler, EveryIndexExactlyOncePerEpoch) {
  const std::uint32_t n = 1000;
  const std::size_t batch_size = 160;
  EpochSampler sampler(n, 7);
  // 5 epochs = 5000 draws = 31.25 batches: draw 32 batches and look at the first 5 windows.
  const auto draws = draw(sampler, batch_size, 32);
  ASSERT_GE(draws.size(), 5U * n);
  for (std::size_t e = 0; e < 5; ++e) {
    EXPECT_TRUE(is_permutation_window(draws, e * n, n)) << "epoch " << e;
  }
  // Consecutive epochs are shuffled differently.
  EXPECT_FALSE(std::equal(draws.begin(), draws.begin() + n, draws.begin() + n));
  // A window that straddles two epochs is, in general, not a permutation: the check above is
  // not vacuous.
  EXPECT_FALSE(is_permutation_window(draws, n / 2, n));
}

TEST(EpochSampler, EpochCounter) {
  const std::uint32_t n = 10;
  EpochSampler sampler(n, 3);
  std::vector<std::uint32_t> batch;
  EXPECT_EQ(sampler.epoch(), 0U);
  sampler.next_batch(10, batch);  // exactly one full pass
  EXPECT_LE(sampler.epoch(), 1U);
  sampler.next_batch(1, batch);  // the first index of the second pass
  EXPECT_EQ(sampler.epoch(), 1U);
  sampler.next_batch(25, batch);  // 11 + 25 = 36 draws: passes 0..3 started
  EXPECT_EQ(sampler.epoch(), 3U);
}

TEST(EpochSampler, BatchesStraddleEpochs) {
  // N = 10, batch 4: the third batch holds the last 2 indices of epoch 0 and the first 2 of
  // epoch 1. Batching must not change the sequence: it equals single draws with the same seed.
  const std::uint32_t n = 10;
  EpochSampler batched(n, 99);
  EpochSampler single(n, 99);
  const auto a = draw(batched, 4, 25);  // 100 draws = 10 epochs
  const auto b = draw(single, 1, 100);
  EXPECT_EQ(a, b);
  for (std::size_t e = 0; e < 10; ++e) {
    EXPECT_TRUE(is_permutation_window(a, e * n, n)) << "epoch " << e;
  }

  // A batch larger than the cloud: holds every index, some twice, and still keeps the epochs.
  EpochSampler big(7, 5);
  const auto c = draw(big, 20, 3);  // 60 draws
  for (std::size_t e = 0; e < 8; ++e) {
    EXPECT_TRUE(is_permutation_window(c, e * 7, 7)) << "epoch " << e;
  }

  // Batch size 0 gives an empty batch and does not advance the sequence.
  EpochSampler z1(n, 42);
  EpochSampler z2(n, 42);
  std::vector<std::uint32_t> batch = {1, 2, 3};
  z1.next_batch(0, batch);
  EXPECT_TRUE(batch.empty());
  EXPECT_EQ(draw(z1, 3, 5), draw(z2, 3, 5));
}

TEST(EpochSampler, BatchIsClearedFirst) {
  EpochSampler sampler(50, 1);
  std::vector<std::uint32_t> batch(17, 12345U);
  sampler.next_batch(5, batch);
  ASSERT_EQ(batch.size(), 5U);
  for (const auto i : batch) EXPECT_LT(i, 50U);
}

TEST(EpochSampler, SameSeedSameSequence) {
  EpochSampler a(1000, 2019);
  EpochSampler b(1000, 2019);
  EXPECT_EQ(draw(a, 160, 40), draw(b, 160, 40));
}

TEST(EpochSampler, DifferentSeedDifferentSequence) {
  EpochSampler a(1000, 2019);
  EpochSampler b(1000, 2020);
  const auto da = draw(a, 160, 40);
  const auto db = draw(b, 160, 40);
  EXPECT_NE(da, db);
  // Not just different somewhere: most positions differ.
  std::size_t same = 0;
  for (std::size_t i = 0; i < da.size(); ++i) same += da[i] == db[i] ? 1 : 0;
  EXPECT_LT(same, da.size() / 20);
}

TEST(EpochSampler, OrderIsShuffled) {
  for (const std::uint64_t seed : {0ULL, 1ULL, 2019ULL, 0xFFFFFFFFFFFFFFFFULL}) {
    EpochSampler sampler(1000, seed);
    const auto first = draw(sampler, 1000, 1);
    EXPECT_NE(first, identity(1000)) << "seed " << seed;
    std::vector<std::uint32_t> reversed = identity(1000);
    std::reverse(reversed.begin(), reversed.end());
    EXPECT_NE(first, reversed) << "seed " << seed;
    // Few fixed points (a random permutation has about one).
    std::size_t fixed = 0;
    for (std::uint32_t i = 0; i < 1000; ++i) fixed += first[i] == i ? 1 : 0;
    EXPECT_LT(fixed, 10U) << "seed " << seed;
  }
}

TEST(EpochSampler, ShuffleIsUniform) {
  // Fisher-Yates with unbiased draws gives each of the 4! orders of N = 4 equally often.
  // 24000 seeds: about 1000 each, standard deviation about 31; the bounds are 6 sigma.
  std::map<std::vector<std::uint32_t>, int> count;
  for (std::uint64_t seed = 0; seed < 24000; ++seed) {
    EpochSampler sampler(4, seed);
    ++count[draw(sampler, 4, 1)];
  }
  EXPECT_EQ(count.size(), 24U);
  for (const auto& [order, c] : count) {
    EXPECT_GT(c, 810);
    EXPECT_LT(c, 1190);
  }
  // Also per position over later epochs of one sampler: index 0 lands everywhere as often.
  EpochSampler sampler(5, 77);
  std::vector<int> position(5, 0);
  const auto draws = draw(sampler, 5, 20000);
  for (std::size_t i = 0; i < draws.size(); ++i) {
    if (draws[i] == 0) ++position[i % 5];
  }
  for (const int c : position) {
    EXPECT_GT(c, 3700);  // expected 4000, sd 57
    EXPECT_LT(c, 4300);
  }
}

TEST(EpochSampler, SinglePoint) {
  EpochSampler sampler(1, 5);
  const auto draws = draw(sampler, 3, 4);
  EXPECT_EQ(draws, std::vector<std::uint32_t>(12, 0U));
}

TEST(EpochSampler, EmptyCloudThrows) {
  EXPECT_THROW(EpochSampler(0, 1), sgdicp::InvalidInputError);
}

}  // namespace
