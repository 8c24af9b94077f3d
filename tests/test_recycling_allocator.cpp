// The block cache of the voxel passes' temporary arrays (src/util/recycling_allocator.hpp).
#include "util/recycling_allocator.hpp"

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

namespace sgdicp {
namespace {

using detail::BlockCache;
using detail::RecycledVector;

constexpr std::size_t kMiB = std::size_t{1} << 20;

// A large array freed on one thread is the next one of its rounded size, on any thread.
TEST(RecyclingAllocator, HandsAFreedLargeBlockToTheNextArrayOfItsSize) {
  if (BlockCache::kMaxKeptBytes == 0) GTEST_SKIP() << "AddressSanitizer build: nothing is kept";
  BlockCache::release();
  const void* first = nullptr;
  std::thread([&] {
    RecycledVector<std::uint32_t> a(kMiB / 4);  // 1 MiB
    first = a.data();
  }).join();
  EXPECT_EQ(BlockCache::kept_bytes(), kMiB);
  RecycledVector<std::uint32_t> b(kMiB / 4 - 1000);  // rounds up to the same 1 MiB block
  EXPECT_EQ(b.data(), first);
  EXPECT_EQ(BlockCache::kept_bytes(), 0U);
  for (const std::uint32_t v : b) ASSERT_EQ(v, 0U);  // value-initialised as any vector
}

// Blocks below the threshold are not kept; the kept bytes never pass the cap.
TEST(RecyclingAllocator, KeepsOnlyLargeBlocksUpToItsCap) {
  if (BlockCache::kMaxKeptBytes == 0) GTEST_SKIP() << "AddressSanitizer build: nothing is kept";
  BlockCache::release();
  { RecycledVector<char> small(BlockCache::kMinBlockBytes - 1); }
  EXPECT_EQ(BlockCache::kept_bytes(), 0U);
  {
    std::vector<RecycledVector<char>> many;
    for (std::size_t i = 0; i < 2 * BlockCache::kMaxKeptBytes / kMiB; ++i) many.emplace_back(kMiB);
  }
  EXPECT_EQ(BlockCache::kept_bytes(), BlockCache::kMaxKeptBytes);
  BlockCache::release();
  EXPECT_EQ(BlockCache::kept_bytes(), 0U);
}

// Two threads taking and returning blocks at once (ThreadSanitizer's case): no block is handed
// to both (each thread's mark survives in its own), and the cap holds.
TEST(RecyclingAllocator, TwoThreadsShareTheCache) {
  BlockCache::release();
  bool intact[2] = {true, true};
  const auto churn = [&](int thread) {
    for (int i = 0; i < 200; ++i) {
      RecycledVector<int> v(static_cast<std::size_t>(16384 + 2048 * (i % 7)), thread);
      std::this_thread::yield();
      for (const int mark : v) intact[thread] = intact[thread] && mark == thread;
    }
  };
  std::thread other(churn, 1);
  churn(0);
  other.join();
  EXPECT_TRUE(intact[0]);
  EXPECT_TRUE(intact[1]);
  EXPECT_LE(BlockCache::kept_bytes(), BlockCache::kMaxKeptBytes);
  BlockCache::release();
}

// fork() while another thread takes and returns blocks: every child can still allocate (without
// the fork handlers a child forked while the other thread held the cache's mutex waits for it
// forever; an alarm ends such a child, which fails the test).
TEST(RecyclingAllocator, ForkedChildrenAllocateWhileAnotherThreadChurns) {
  std::atomic<bool> stop{false};
  std::thread churn([&] {
    while (!stop.load(std::memory_order_relaxed)) {
      RecycledVector<char> v(BlockCache::kMinBlockBytes);
      (void)BlockCache::kept_bytes();
    }
  });
  int hung = 0;  // no ASSERT in the loop: the churning thread must be joined
  for (int i = 0; i < 40; ++i) {
    const pid_t child = fork();
    if (child == 0) {
      alarm(5);
      { RecycledVector<char> v(2 * BlockCache::kMinBlockBytes); }
      _exit(BlockCache::kept_bytes() <= BlockCache::kMaxKeptBytes ? 0 : 1);
    }
    int status = 0;
    const bool exited = child > 0 && waitpid(child, &status, 0) == child && WIFEXITED(status);
    hung += exited && WEXITSTATUS(status) == 0 ? 0 : 1;
  }
  stop = true;
  churn.join();
  EXPECT_EQ(hung, 0) << "children of 40 that hung, failed or were not forked";
  BlockCache::release();
}

}  // namespace
}  // namespace sgdicp
