#pragma once
// A counter one thread advances and one other thread waits on: the hand-off of HelperThread.
// The waiter spins first (a run's batches follow each other within microseconds), then sleeps
// on a mutex and condition variable. Not std::atomic::wait: libstdc++ 12 decides whether to
// wake anyone by a load of its waiter count that may pass the store of the new value (a plain
// release store on x86), so a waiter that arrives at that moment sleeps through the only
// notification. That lost wakeup hung a two-thread run once (docs/design.md, "Threads").
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>

namespace sgdicp::detail {

class WakeCounter {
 public:
  /// Spins this many pauses (~20-90 us) before sleeping: longer than the caller's work between
  /// two batches, so a run's helper never sleeps, and short enough not to burn a core after it.
  static constexpr int kDefaultSpins = 2048;

  explicit WakeCounter(int spins = kDefaultSpins) : spins_(spins) {}

  [[nodiscard]] std::uint32_t load() const noexcept {
    return value_.load(std::memory_order_acquire);
  }

  /// Sets the counter and wakes the waiter if it sleeps. The value's store and the load of
  /// `sleeping_` are both seq_cst, as are the waiter's store of `sleeping_` and its load of the
  /// value: of the two, at least one sees the other's write, so the waiter never sleeps through
  /// a change (the store-buffer litmus test that a release store alone fails).
  void store(std::uint32_t value) {
    value_.store(value, std::memory_order_seq_cst);
    if (sleeping_.load(std::memory_order_seq_cst)) {
      const std::lock_guard lock(mutex_);  // the waiter is in wait() or has not checked yet
      changed_.notify_one();
    }
  }

  void increment() { store(value_.load(std::memory_order_relaxed) + 1); }  // one writer only

  /// Waits until the counter differs from `old`; returns the new value.
  std::uint32_t wait_change(std::uint32_t old) {
    for (int spin = 0; spin < spins_; ++spin) {
      const std::uint32_t now = value_.load(std::memory_order_acquire);
      if (now != old) return now;
      pause();
    }
    std::unique_lock lock(mutex_);
    sleeping_.store(true, std::memory_order_seq_cst);
    changed_.wait(lock, [&] { return value_.load(std::memory_order_seq_cst) != old; });
    sleeping_.store(false, std::memory_order_relaxed);
    return value_.load(std::memory_order_acquire);
  }

 private:
  static void pause() noexcept {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#else
    std::this_thread::yield();
#endif
  }

  const int spins_;
  std::atomic<std::uint32_t> value_{0};
  std::atomic<bool> sleeping_{false};
  std::mutex mutex_;
  std::condition_variable changed_;
};

}  // namespace sgdicp::detail
