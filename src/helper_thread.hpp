#pragma once
// A persistent second thread for short, frequent jobs: a mini-batch's nearest-neighbour queries
// take 20-150 us and a run makes hundreds of them, too short to start a thread for each
// (parallel_chunks' std::jthread costs 30-60 us). The caller hands one half of a job to the
// helper, runs the other half and waits. Which half runs where changes no value, so the results
// are the same as on one thread (docs/design.md, "Threads").
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <thread>

namespace sgdicp::detail {

class HelperThread {
 public:
  HelperThread() : thread_([this] { serve(); }) {}
  ~HelperThread() {
    stop_.store(true, std::memory_order_relaxed);
    publish();
  }  // thread_ joins
  HelperThread(const HelperThread&) = delete;
  HelperThread& operator=(const HelperThread&) = delete;

  // part(begin, end) over [0, n): [n / 2, n) on the helper, [0, n / 2) on the caller. Returns
  // when both halves are done; rethrows the first exception of either.
  template <class Part>
  void split(std::size_t n, const Part& part) {
    job_ = [](const void* context, std::size_t begin, std::size_t end) {
      (*static_cast<const Part*>(context))(begin, end);
    };
    context_ = &part;
    begin_ = n / 2;
    end_ = n;
    error_ = nullptr;
    publish();
    try {
      part(0, n / 2);
    } catch (...) {
      wait_done();  // the helper's half reads the caller's data: let it finish first
      throw;
    }
    wait_done();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  // Spins this many pauses (~20-90 us) before sleeping: longer than the caller's work between
  // two batches, so a run's helper never sleeps, and short enough not to burn a core after it.
  static constexpr int kSpins = 2048;

  static void pause() noexcept {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#else
    std::this_thread::yield();
#endif
  }

  // Waits until `value` differs from `old`; returns the new value.
  static std::uint32_t wait_change(const std::atomic<std::uint32_t>& value, std::uint32_t old) {
    for (int spin = 0; spin < kSpins; ++spin) {
      const std::uint32_t now = value.load(std::memory_order_acquire);
      if (now != old) return now;
      pause();
    }
    value.wait(old, std::memory_order_acquire);
    return value.load(std::memory_order_acquire);
  }

  void publish() {
    posted_.fetch_add(1, std::memory_order_release);
    posted_.notify_one();
  }

  void wait_done() {
    const std::uint32_t target = posted_.load(std::memory_order_relaxed);
    std::uint32_t done = done_.load(std::memory_order_acquire);
    while (done != target) done = wait_change(done_, done);
  }

  void serve() {
    std::uint32_t seen = 0;
    for (;;) {
      seen = wait_change(posted_, seen);
      if (stop_.load(std::memory_order_relaxed)) return;
      try {
        job_(context_, begin_, end_);
      } catch (...) {
        error_ = std::current_exception();
      }
      done_.store(seen, std::memory_order_release);
      done_.notify_one();
    }
  }

  // Written by the caller before publish(), read by the helper after it sees the new count.
  void (*job_)(const void*, std::size_t, std::size_t) = nullptr;
  const void* context_ = nullptr;
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
  std::exception_ptr error_;  // written by the helper before done_
  std::atomic<bool> stop_{false};
  std::atomic<std::uint32_t> posted_{0};
  std::atomic<std::uint32_t> done_{0};
  std::jthread thread_;  // last: starts after the members above exist, joins before they go
};

}  // namespace sgdicp::detail
