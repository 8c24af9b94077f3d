#pragma once
// A persistent second thread for short, frequent jobs: a mini-batch's nearest-neighbour queries
// take 20-150 us and a run makes hundreds of them, too short to start a thread for each (a
// std::jthread's start and join cost 30-100 us here). The caller hands one half of a job to the
// helper, runs the other half and waits. Which half runs where changes no value, so the results
// are the same as on one thread (docs/design.md, "Threads"). run_ranges gives the voxel passes
// the calling thread's own helpers the same way.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <span>
#include <thread>
#include <vector>

#include <unistd.h>

#include "util/wake_counter.hpp"

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
    start(part, n / 2, n);
    try {
      part(0, n / 2);
    } catch (...) {
      wait_done();  // the helper's half reads the caller's data: let it finish first
      throw;
    }
    finish();
  }

  // part(begin, end) on the helper; `part` must outlive the matching finish().
  template <class Part>
  void start(const Part& part, std::size_t begin, std::size_t end) {
    job_ = [](const void* context, std::size_t b, std::size_t e) {
      (*static_cast<const Part*>(context))(b, e);
    };
    context_ = &part;
    begin_ = begin;
    end_ = end;
    error_ = nullptr;
    publish();
  }

  // Waits for the job of start(); rethrows its exception.
  void finish() {
    wait_done();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void publish() { posted_.increment(); }

  void wait_done() {
    const std::uint32_t target = posted_.load();
    std::uint32_t done = done_.load();
    while (done != target) done = done_.wait_change(done);
  }

  void serve() {
    std::uint32_t seen = 0;
    for (;;) {
      seen = posted_.wait_change(seen);
      if (stop_.load(std::memory_order_relaxed)) return;
      try {
        job_(context_, begin_, end_);
      } catch (...) {
        error_ = std::current_exception();
      }
      done_.store(seen);
    }
  }

  // Written by the caller before publish(), read by the helper after it sees the new count.
  void (*job_)(const void*, std::size_t, std::size_t) = nullptr;
  const void* context_ = nullptr;
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
  std::exception_ptr error_;  // written by the helper before done_
  std::atomic<bool> stop_{false};
  WakeCounter posted_;   // jobs handed over; written by the caller, waited on by the helper
  WakeCounter done_;     // jobs finished; written by the helper, waited on by the caller
  std::jthread thread_;  // last: starts after the members above exist, joins before they go
};

/// The calling thread's helpers for run_ranges (one set per thread).
struct ThreadHelpers {
  std::vector<std::unique_ptr<HelperThread>> helpers;
  bool serving = false;      // a run_ranges of this thread is under way
  pid_t process = getpid();  // the process whose threads the helpers are

  ThreadHelpers() = default;
  ThreadHelpers(const ThreadHelpers&) = delete;
  ThreadHelpers& operator=(const ThreadHelpers&) = delete;
  ~ThreadHelpers() { forget_if_forked(); }

  // A child of fork() (Python's multiprocessing, say) has none of its parent's threads: handing
  // work to the helpers it inherited, or joining them, would wait forever. It forgets them (their
  // memory is the parent's copy) and starts its own.
  void forget_if_forked() {
    if (getpid() == process) return;
    for (auto& helper : helpers) static_cast<void>(helper.release());
    helpers.clear();
    serving = false;
    process = getpid();
  }
};

inline ThreadHelpers& thread_helpers() {
  thread_local ThreadHelpers team;
  team.forget_if_forked();
  return team;
}

inline void rethrow_first(const std::vector<std::exception_ptr>& errors) {
  for (const auto& error : errors) {
    if (error) std::rethrow_exception(error);
  }
}

/// run_ranges on threads started for this call (a nested call: the helpers are busy).
template <class Body>
void run_ranges_on_new_threads(std::span<const std::size_t> bounds, const Body& body) {
  std::vector<std::exception_ptr> errors(bounds.size() - 1);
  const auto run = [&](std::size_t t) {
    try {
      body(bounds[t], bounds[t + 1]);
    } catch (...) {
      errors[t] = std::current_exception();
    }
  };
  {
    std::vector<std::jthread> workers;
    for (std::size_t t = 1; t < errors.size(); ++t) workers.emplace_back(run, t);
    run(0);
  }  // jthreads join here
  rethrow_first(errors);
}

/// body(bounds[t], bounds[t + 1]) for every t < bounds.size() - 1: the first range on the
/// calling thread, the others on its own helpers, started on its first parallel pass and kept
/// until it ends (they sleep after ~50 us without work). Returns when all ranges are done;
/// rethrows the first exception in range order. A call made from within a range runs on
/// threads of its own, so that it never waits for a helper that runs it.
template <class Body>
void run_ranges(std::span<const std::size_t> bounds, const Body& body) {
  const std::size_t parts = bounds.size() - 1;
  if (parts == 1) {
    body(bounds[0], bounds[1]);
    return;
  }
  ThreadHelpers& team = thread_helpers();
  if (team.serving) {
    run_ranges_on_new_threads(bounds, body);
    return;
  }
  auto& helpers = team.helpers;
  while (helpers.size() + 1 < parts) helpers.push_back(std::make_unique<HelperThread>());
  std::vector<std::exception_ptr> errors(parts);
  team.serving = true;
  for (std::size_t t = 1; t < parts; ++t) helpers[t - 1]->start(body, bounds[t], bounds[t + 1]);
  try {
    body(bounds[0], bounds[1]);
  } catch (...) {
    errors[0] = std::current_exception();
  }
  for (std::size_t t = 1; t < parts; ++t) {
    try {
      helpers[t - 1]->finish();  // the helpers read the caller's data: wait for each
    } catch (...) {
      errors[t] = std::current_exception();
    }
  }
  team.serving = false;
  rethrow_first(errors);
}

}  // namespace sgdicp::detail
