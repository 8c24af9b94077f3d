#pragma once
// RANSAC over putative correspondences (Fischler and Bolles 1981) with the edge-length test of
// Open3D's and FGR's correspondence checkers (a rigid motion keeps the distances between the
// sampled points), keeping the best few distinct hypotheses rather than the best alone, so that
// a second explanation of the data (a symmetric object, a repetitive scene) is seen.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace sgdicp::detail {

struct ConsensusSettings {
  double inlier_distance_m = 1.0;  ///< a correspondence agrees with T within this
  double edge_ratio = 0.9;         ///< sampled edges must agree in length to this ratio
  double min_edge_m = 0.0;         ///< and be at least this long (a well-spread sample)
  std::size_t max_iterations = 100000;
  double confidence = 0.999;  ///< stop once a better sample is this unlikely
  std::size_t keep = 8;       ///< distinct hypotheses kept, most consensus first
  double distinct_rotation_rad = 0.17;
  double distinct_translation_m = 1.0;
};

struct Hypothesis {
  Eigen::Matrix4d T_to_from = Eigen::Matrix4d::Identity();  ///< maps `from` points onto `to`
  std::size_t consensus = 0;  ///< correspondences within inlier_distance_m
};

struct Consensus {
  std::vector<Hypothesis> hypotheses;  ///< distinct, most consensus first, each refitted
  std::size_t iterations = 0;          ///< samples drawn
};

/// Correspondence k is from[k] -> to[k] (same length, at least 3).
[[nodiscard]] Consensus find_consensus(const std::vector<Eigen::Vector3f>& from,
                                       const std::vector<Eigen::Vector3f>& to,
                                       const ConsensusSettings& settings, std::uint64_t seed);

/// Whether two poses differ by more than the settings' rotation or translation.
[[nodiscard]] bool distinct(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b,
                            const ConsensusSettings& settings);

}  // namespace sgdicp::detail
