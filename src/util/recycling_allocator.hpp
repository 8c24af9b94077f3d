#pragma once
// An allocator for the voxel passes' large temporary arrays that keeps freed blocks for the next
// pass instead of handing them back to the system. A registration's tables are a few MB each;
// glibc serves such blocks with mmap (or trims them off its heap at the free), so every table of
// every registration had its pages faulted in and zeroed again by the kernel: ~10 % of a
// one-thread registration run in a loop on KITTI scans (57,700 page faults in 40 registrations,
// 5,880 with this cache: 1.17x faster end to end).
// Blocks of at least kMinBlockBytes are rounded up to a power of two and kept, up to
// kMaxKeptBytes in all, in one process-wide cache shared by every thread (a pass's halves are
// made on two threads and freed on one); smaller blocks go straight to operator new. The kept
// bytes stay within the peak-memory budget (docs/performance.md, "Peak memory": 50 MB above the
// input). AddressSanitizer builds keep nothing, so that it still sees every use after free.
#include <bit>
#include <cstddef>
#include <map>
#include <mutex>
#include <new>
#include <vector>

#include <pthread.h>

#if defined(__has_feature)
#define SGDICP_HAS_ADDRESS_SANITIZER __has_feature(address_sanitizer)  // clang
#else
#define SGDICP_HAS_ADDRESS_SANITIZER 0
#endif

namespace sgdicp::detail {

class BlockCache {
 public:
  static constexpr std::size_t kMinBlockBytes = std::size_t{64} << 10;
#if defined(__SANITIZE_ADDRESS__) || SGDICP_HAS_ADDRESS_SANITIZER
  static constexpr std::size_t kMaxKeptBytes = 0;
#else
  static constexpr std::size_t kMaxKeptBytes = std::size_t{32} << 20;
#endif

  static void* allocate(std::size_t bytes) {
    if (bytes < kMinBlockBytes || kMaxKeptBytes == 0) return ::operator new(bytes);
    const std::size_t block = std::bit_ceil(bytes);
    {
      const std::lock_guard lock(instance().mutex_);
      auto& free = instance().free_;
      const auto it = free.find(block);
      if (it != free.end() && !it->second.empty()) {
        void* p = it->second.back();
        it->second.pop_back();
        instance().kept_bytes_ -= block;
        return p;
      }
    }
    return ::operator new(block);
  }

  /// The bytes kept for reuse now.
  [[nodiscard]] static std::size_t kept_bytes() {
    const std::lock_guard lock(instance().mutex_);
    return instance().kept_bytes_;
  }

  /// Makes the cache if no use has yet (kBlockCacheMadeBeforeThreads, below); true.
  static bool made() {
    (void)instance();
    return true;
  }

  /// Frees every kept block.
  static void release() {
    const std::lock_guard lock(instance().mutex_);
    for (auto& [block, blocks] : instance().free_) {
      for (void* p : blocks) ::operator delete(p);
      blocks.clear();
    }
    instance().kept_bytes_ = 0;
  }

  static void deallocate(void* p, std::size_t bytes) noexcept {
    if (bytes < kMinBlockBytes || kMaxKeptBytes == 0) {
      ::operator delete(p);
      return;
    }
    const std::size_t block = std::bit_ceil(bytes);
    {
      const std::lock_guard lock(instance().mutex_);
      auto& cache = instance();
      if (cache.kept_bytes_ + block <= kMaxKeptBytes) {
        try {
          cache.free_[block].push_back(p);
          cache.kept_bytes_ += block;
          return;
        } catch (...) {  // no memory to keep it: free it
        }
      }
    }
    ::operator delete(p);
  }

 private:
  BlockCache() = default;
  // Never destroyed: a vector freed during static destruction still finds it.
  static BlockCache& instance() {
    static auto* const cache = make();
    return *cache;
  }

  // A fork() while another thread holds the mutex would leave it locked for good in the child
  // (a Python multiprocessing worker, forked from a process registering on other threads):
  // fork() waits for the mutex and both processes release it after, as glibc does for malloc.
  static BlockCache* make() {
    auto* const cache = new BlockCache;
    pthread_atfork([] { instance().mutex_.lock(); }, [] { instance().mutex_.unlock(); },
                   [] { instance().mutex_.unlock(); });
    return cache;
  }

  std::mutex mutex_;
  std::map<std::size_t, std::vector<void*>> free_;  // block size -> kept blocks
  std::size_t kept_bytes_ = 0;
};

template <class T>
struct RecyclingAllocator {
  using value_type = T;
  RecyclingAllocator() = default;
  template <class U>
  explicit RecyclingAllocator(const RecyclingAllocator<U>& /*other*/) noexcept {}
  T* allocate(std::size_t n) { return static_cast<T*>(BlockCache::allocate(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) noexcept { BlockCache::deallocate(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const RecyclingAllocator<U>& /*other*/) const noexcept {
    return true;
  }
};

// The cache is made during static initialisation, before any thread runs: a fork() while another
// thread was inside the first instance() (its guard taken, the atfork handlers being registered)
// left the child waiting on that guard for good (the test of forked children, under load: 1 run
// in ~60 before, none in 800 after).
inline const bool kBlockCacheMadeBeforeThreads = BlockCache::made();

/// A vector whose large blocks come from and go back to the BlockCache.
template <class T>
using RecycledVector = std::vector<T, RecyclingAllocator<T>>;

}  // namespace sgdicp::detail
