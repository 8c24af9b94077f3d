// Replacement of the global operator new that records the largest request. In its own file so
// that the compiler does not see the replaced new and delete inlined at the call sites.
#include "allocation_tracker.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

namespace {
std::atomic<std::size_t> g_largest{0};
}  // namespace

namespace sgdicp {

void reset_largest_allocation() {
  g_largest.store(0);
}

std::size_t largest_allocation() {
  return g_largest.load();
}

}  // namespace sgdicp

void* operator new(std::size_t size) {
  std::size_t seen = g_largest.load(std::memory_order_relaxed);
  while (size > seen && !g_largest.compare_exchange_weak(seen, size)) {
  }
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}

void operator delete(void* p) noexcept {
  std::free(p);
}

void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
