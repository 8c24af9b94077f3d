#pragma once
// Mini-batch sampling without replacement (paper Section III-B, Algorithm 1 line 2): source
// indices are drawn from a shuffled order; when every point has been used, the order is
// reshuffled and a new epoch starts. A batch may straddle two epochs. The shuffle is lazy
// (Fisher-Yates one draw at a time): a registration that stops after a fraction of a pass pays
// only for the indices it draws, not for shuffling the whole cloud. Seeded and reproducible:
// the shuffle and the bounded draws are our own, so the sequence does not depend on the standard
// library's distribution implementations.
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "sgdicp/core/error.hpp"

namespace sgdicp {

class EpochSampler {
 public:
  EpochSampler(std::uint32_t num_points, std::uint64_t seed) : order_(num_points), rng_(seed) {
    if (num_points == 0) throw InvalidInputError("cannot sample from an empty cloud");
    std::iota(order_.begin(), order_.end(), 0U);
  }

  /// Fills batch with the next batch_size indices (cleared first).
  void next_batch(std::size_t batch_size, std::vector<std::uint32_t>& batch) {
    batch.clear();
    for (std::size_t i = 0; i < batch_size; ++i) {
      if (cursor_ == order_.size()) {
        cursor_ = 0;  // the next epoch shuffles the current order again, draw by draw
        ++epoch_;
      }
      // One Fisher-Yates step: a uniform pick among the indices not drawn in this epoch.
      const std::size_t pick = cursor_ + bounded(order_.size() - cursor_);
      std::swap(order_[cursor_], order_[pick]);
      batch.push_back(order_[cursor_++]);
    }
  }

  /// Completed passes over the cloud.
  [[nodiscard]] std::uint64_t epoch() const noexcept { return epoch_; }

 private:
  // Uniform integer in [0, bound): reject the top partial block so that the modulo is unbiased.
  std::uint64_t bounded(std::uint64_t bound) {
    const std::uint64_t limit = std::mt19937_64::max() - std::mt19937_64::max() % bound;
    std::uint64_t x = rng_();
    while (x >= limit) x = rng_();
    return x % bound;
  }
  std::vector<std::uint32_t> order_;
  std::mt19937_64 rng_;
  std::size_t cursor_ = 0;
  std::uint64_t epoch_ = 0;
};

}  // namespace sgdicp
