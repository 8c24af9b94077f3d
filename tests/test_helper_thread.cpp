// The helper thread of a registration's mini-batch queries (src/util/helper_thread.hpp).
#include "util/helper_thread.hpp"
#include "util/wake_counter.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

namespace sgdicp {
namespace {

// The helper thread runs the second half of every job, the caller the first; each index once.
TEST(HelperThread, SplitsAJobIntoTwoHalvesAndPassesExceptionsOn) {
  detail::HelperThread helper;
  for (const std::size_t n : {0u, 1u, 2u, 7u, 160u}) {
    for (int round = 0; round < 50; ++round) {
      std::vector<int> visits(n, 0);
      helper.split(n, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) ++visits[i];
      });
      EXPECT_EQ(std::count(visits.begin(), visits.end(), 1), static_cast<std::ptrdiff_t>(n));
    }
  }
  const auto throw_in = [&](std::size_t half_start) {
    helper.split(10, [&](std::size_t begin, std::size_t) {
      if (begin == half_start) throw std::runtime_error("half " + std::to_string(begin));
    });
  };
  EXPECT_THROW(throw_in(5), std::runtime_error);  // the helper's half
  EXPECT_THROW(throw_in(0), std::runtime_error);  // the caller's half
  int after = 0;
  helper.split(4, [&](std::size_t begin, std::size_t end) {
    if (begin == 0) after += static_cast<int>(end);
  });
  EXPECT_EQ(after, 2) << "the helper still serves after an exception";
}

// run_ranges: each range once, the first on the caller and the others on helpers that stay for
// the next call; a call from within a range still runs (on threads of its own); exceptions
// come back in range order.
TEST(HelperThread, RunRangesKeepsItsHelpersAndNests) {
  const std::vector<std::size_t> bounds{0, 3, 10, 16};
  std::vector<std::thread::id> first(3);
  for (int round = 0; round < 20; ++round) {
    std::vector<int> visits(16, 0);
    std::vector<std::thread::id> ids(3);
    detail::run_ranges(bounds, [&](std::size_t begin, std::size_t end) {
      const auto part =
          static_cast<std::size_t>(std::find(bounds.begin(), bounds.end(), begin) - bounds.begin());
      ids[part] = std::this_thread::get_id();
      for (std::size_t i = begin; i < end; ++i) ++visits[i];
    });
    EXPECT_EQ(std::count(visits.begin(), visits.end(), 1), 16);
    EXPECT_EQ(ids[0], std::this_thread::get_id());
    EXPECT_NE(ids[1], ids[2]);
    if (round == 0) first = ids;
    EXPECT_EQ(ids, first) << "the same helpers serve every call";
  }
  std::vector<int> inner(8, 0);
  const std::vector<std::size_t> halves{0, 4, 8};
  detail::run_ranges(halves, [&](std::size_t begin, std::size_t) {
    if (begin != 0) return;
    detail::run_ranges(halves, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) ++inner[i];
    });
  });
  EXPECT_EQ(std::count(inner.begin(), inner.end(), 1), 8);
  try {
    detail::run_ranges(bounds, [&](std::size_t begin, std::size_t) {
      if (begin > 0) throw std::runtime_error("range at " + std::to_string(begin));
    });
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "range at 3");
  }
}

// A child of fork() has none of the parent's helper threads: its passes start their own instead
// of waiting for the inherited ones forever (an alarm ends a hung child, which fails the test).
TEST(ForkedProcess, RunsRangesOnHelpersOfItsOwn) {
  const std::vector<std::size_t> halves{0, 50, 100};
  std::vector<int> visits(100, 0);
  const auto count = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) ++visits[i];
  };
  detail::run_ranges(halves, count);  // the parent's helper exists now
  const pid_t child = fork();
  ASSERT_NE(child, -1);
  if (child == 0) {
    alarm(20);
    std::fill(visits.begin(), visits.end(), 0);
    detail::run_ranges(halves, count);
    _exit(std::count(visits.begin(), visits.end(), 1) == 100 ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "the child hung or crashed";
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(std::count(visits.begin(), visits.end(), 1), 100);
}

// Ends the test binary if its scope lasts longer than `limit`: a lost wakeup leaves every thread
// asleep, and the test must then fail rather than stall (works under TSan, unlike a fork).
class AbortIfHung {
 public:
  AbortIfHung(std::chrono::seconds limit, std::string what)
      : watchdog_([limit, what = std::move(what), this](std::stop_token) {
          std::unique_lock lock(mutex_);
          if (!done_cv_.wait_for(lock, limit, [this] { return done_; })) {
            std::fprintf(stderr, "hung: %s\n", what.c_str());
            std::abort();
          }
        }) {}
  ~AbortIfHung() {
    {
      const std::lock_guard lock(mutex_);
      done_ = true;
    }
    done_cv_.notify_one();
  }
  AbortIfHung(const AbortIfHung&) = delete;
  AbortIfHung& operator=(const AbortIfHung&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable done_cv_;
  bool done_ = false;
  std::jthread watchdog_;  // last: joins before the members above go
};

// Two threads hand a counter back and forth, every wait asleep (no spins) or after a few spins,
// so that each hand-off meets the sleeping path at a different moment.
TEST(WakeCounter, NeverSleepsThroughAChange) {
  for (const int spins : {0, 3, 40}) {
    const AbortIfHung guard(std::chrono::seconds(60),
                            "a hand-off was lost with " + std::to_string(spins) + " spins");
    detail::WakeCounter ping(spins);
    detail::WakeCounter pong(spins);
    constexpr std::uint32_t kRounds = 20000;
    std::jthread other([&] {
      std::uint32_t seen = 0;
      while (seen != kRounds) {
        seen = ping.wait_change(seen);
        pong.store(seen);
      }
    });
    for (std::uint32_t round = 1; round <= kRounds; ++round) {
      ping.store(round);
      std::uint32_t answer = pong.load();
      while (answer != round) answer = pong.wait_change(answer);
    }
  }
}

// The helper's hand-offs at the edge of its spin phase: jobs whose length straddles the time the
// caller spins before it sleeps (20-90 us), many times.
TEST(HelperThread, SoaksAtTheEdgeOfItsSpinPhase) {
  const AbortIfHung guard(std::chrono::seconds(60),
                          "the caller or the helper slept through a hand-off");
  detail::HelperThread helper;
  std::uint64_t state = 1;
  std::vector<std::uint64_t> sums(2, 0);
  for (int round = 0; round < 4000; ++round) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const std::uint64_t helper_steps = 20000 + (state >> 40) % 60000;
    helper.split(2, [&](std::size_t begin, std::size_t) {
      const std::uint64_t steps = begin == 0 ? 0 : helper_steps;
      std::uint64_t sum = 0;
      for (std::uint64_t i = 0; i < steps; ++i) sum = sum * 31 + i;
      sums[begin] += sum;
    });
  }
  EXPECT_NE(sums[1], 0u);
}

}  // namespace
}  // namespace sgdicp
