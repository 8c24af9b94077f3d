#pragma once
// How many independent draws a Markov chain's samples are worth (private to the library): sgld
// reports it for its chain (RegistrationResult::effective_samples).
#include <vector>

#include "sgdicp/core/pose.hpp"

namespace sgdicp::detail {

/// The effective sample size n / tau of one coordinate's chain `x` (in the order drawn), tau the
/// integrated autocorrelation time by Geyer's initial monotone sequence (Geyer 1992; BDA3
/// 11.5): the autocorrelations summed in adjacent pairs while the pairs' sums stay positive,
/// each sum capped by the one before. A chain of independent draws gives about n, an AR(1) chain
/// of lag-one correlation r about n (1 - r) / (1 + r). 0 for fewer than 4 samples or a chain
/// that never moves.
[[nodiscard]] double effective_sample_size(const std::vector<double>& x);

/// The smallest effective sample size over the six coordinates of a chain of poses.
[[nodiscard]] double effective_sample_size(const std::vector<PoseVector>& chain);

}  // namespace sgdicp::detail
