#pragma once
// Each source point's nearest reference point, remembered between the mini-batches that draw it,
// with a certificate that answers a later query without the tree. A point queried at q0 whose
// nearest was a and whose every other reference point lay at least L away is, now at q with
// delta = |q - q0|, still nearest to a whenever |q - a| + delta < L: every other point is at least
// L - delta away (triangle inequality). The answer is then the tree's, point and distance bit for
// bit, so a registration gives the same result with or without the memory (tests). Late in a run
// the pose moves by less than the spacing of the reference, and a small source is drawn many
// times (the 361-point bunny about ten), so most of its queries need no search. Private to the
// library.
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "index/squared_distance.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"

namespace sgdicp::detail {

class NearestMemory {
 public:
  struct Entry {
    Eigen::Vector3f query = Eigen::Vector3f::Zero();  // where the tree was asked, metres
    std::uint32_t index = kNone;                      // its nearest, or kNone
    float others_m = -1.0F;  // every other point (every point if kNone) is at least this far
  };

  NearestMemory(const ReferenceIndex& reference, std::size_t source_points)
      : reference_(reference), entries_(source_points) {}

  // The nearest reference point to `query` (source point i, moved) within
  // sqrt(max_squared_distance), as ReferenceIndex::nearest gives it. When the memory cannot
  // certify the answer the tree is asked, and `fresh` is set to the new entry (kept by
  // remember(), so that two threads may look up at once); otherwise to Entry{}, which
  // remember() ignores.
  [[nodiscard]] std::optional<Neighbor> nearest(std::uint32_t i, const Eigen::Vector3f& query,
                                                float max_squared_distance, Entry& fresh) const {
    fresh = Entry{};
    const Entry& known = entries_[i];
    const double delta_m = (query - known.query).cast<double>().norm();
    // Certified with a margin far above the float rounding of the stored distances.
    const double others_m = static_cast<double>(known.others_m) * (1.0 - 1e-5);
    if (known.index != kNone) {
      const float squared = squared_distance(query, known.index);
      if (std::sqrt(static_cast<double>(squared)) + delta_m < others_m) {
        if (squared < max_squared_distance) return Neighbor{known.index, squared};
        return std::nullopt;
      }
    } else if (others_m - delta_m >= std::sqrt(static_cast<double>(max_squared_distance))) {
      return std::nullopt;
    }
    float others_squared = 0.0F;
    const auto found = reference_.nearest_and_bound(query, max_squared_distance, others_squared);
    fresh = Entry{query, found ? found->index : kNone, std::sqrt(others_squared)};
    return found;
  }

  void remember(std::uint32_t i, const Entry& fresh) {
    if (fresh.others_m >= 0.0F) entries_[i] = fresh;
  }

  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

 private:
  [[nodiscard]] float squared_distance(const Eigen::Vector3f& query, std::uint32_t index) const {
    return tree_squared_distance(query, reference_.cloud().points[index]);
  }

  const ReferenceIndex& reference_;
  std::vector<Entry> entries_;
};

}  // namespace sgdicp::detail
