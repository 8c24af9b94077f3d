#pragma once
// The covariance of a handful of pose draws, shrunk toward a known shape (private to the
// library): laplace's grid bootstrap (uncertainty.cpp) has kGridOffsets + 1 = 7 draws in 6-D.
#include <vector>

#include "sgdicp/core/pose.hpp"
#include "sgdicp/costs/cost.hpp"

namespace sgdicp::detail {

/// The sample covariance S of `draws` (about their mean, nu = n - 1 degrees of freedom) has an
/// unbiased trace, but in 6-D the mean of its inverse is finite only for nu > 7 (and 6 nu /
/// (nu - 7) times the truth's in a NEES): with seven draws a NEES against it has heavy tails
/// wherever S dominates a covariance. This returns S shrunk toward `shape` (symmetric
/// positive definite) scaled to S's spread, with the Ledoit-Wolf intensity estimated from the
/// draws' own scatter (Ledoit and Wolf 2004, in the space whitened by `shape`), then rescaled so
/// that its translation and rotation blocks keep S's traces. S itself when `shape` is not
/// positive definite; zero for fewer than 2 draws.
[[nodiscard]] PoseMatrix shrunk_covariance(const std::vector<PoseVector>& draws,
                                           const PoseMatrix& shape);

}  // namespace sgdicp::detail
