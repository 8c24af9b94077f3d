#pragma once
// A voxel key -> slot table that also forgets keys (private): open addressing with linear
// probing in one flat array, erased by backward shift (no tombstones, so a long-lived table that
// keeps gaining and losing keys, such as an odometry map's cells, never slows down). VoxelSlots
// (points/voxel_table.hpp) numbers the keys of one pass and never forgets one; this one is told
// each key's slot, so that the slots can stay dense while keys come and go.
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "points/voxel_table.hpp"

namespace sgdicp::detail {

class KeySlots {
 public:
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

  KeySlots() { entries_.resize(64); }

  /// The slot of `key`, or kNone.
  [[nodiscard]] std::uint32_t find(const VoxelKey& key) const {
    const std::size_t mask = entries_.size() - 1;
    for (std::size_t i = hash_of(key) & mask;; i = (i + 1) & mask) {
      const Entry& e = entries_[i];
      if (e.slot == kNone || e.key == key) return e.slot;
    }
  }

  /// Gives `key` (absent) the slot `slot`.
  void insert(const VoxelKey& key, std::uint32_t slot) {
    if (4 * (size_ + 1) > 3 * entries_.size()) rehash(2 * entries_.size());  // 3/4 full
    entries_[free_position(key)] = {key, slot};
    ++size_;
  }

  /// Gives `key` (present) the slot `slot`.
  void reassign(const VoxelKey& key, std::uint32_t slot) { entries_[position(key)].slot = slot; }

  /// Forgets `key` (present): the entries after it in its run move back into the gap when
  /// their home position allows it (Knuth's algorithm R).
  void erase(const VoxelKey& key) {
    const std::size_t mask = entries_.size() - 1;
    std::size_t gap = position(key);
    for (std::size_t j = (gap + 1) & mask; entries_[j].slot != kNone; j = (j + 1) & mask) {
      const std::size_t home = hash_of(entries_[j].key) & mask;
      // Movable unless its home lies cyclically in (gap, j]: then the gap is before its home.
      if (((j - home) & mask) >= ((j - gap) & mask)) {
        entries_[gap] = entries_[j];
        gap = j;
      }
    }
    entries_[gap].slot = kNone;
    --size_;
  }

  void clear() {
    entries_.assign(64, Entry{});
    size_ = 0;
  }

 private:
  struct Entry {
    VoxelKey key;
    std::uint32_t slot = kNone;
  };

  [[nodiscard]] std::size_t position(const VoxelKey& key) const {
    const std::size_t mask = entries_.size() - 1;
    std::size_t i = hash_of(key) & mask;
    while (!(entries_[i].key == key && entries_[i].slot != kNone)) i = (i + 1) & mask;
    return i;
  }

  [[nodiscard]] std::size_t free_position(const VoxelKey& key) const {
    const std::size_t mask = entries_.size() - 1;
    std::size_t i = hash_of(key) & mask;
    while (entries_[i].slot != kNone) i = (i + 1) & mask;
    return i;
  }

  void rehash(std::size_t capacity) {
    RecycledVector<Entry> old(capacity);
    old.swap(entries_);
    for (const Entry& e : old) {
      if (e.slot != kNone) entries_[free_position(e.key)] = e;
    }
  }

  RecycledVector<Entry> entries_;
  std::size_t size_ = 0;
};

}  // namespace sgdicp::detail
