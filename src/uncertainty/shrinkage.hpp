#pragma once
// The covariance of a handful of pose draws, shrunk toward a known shape (private to the
// library): laplace's grid bootstrap (uncertainty.cpp) has kGridOffsets + 1 = 7 draws in 6-D.
#include <functional>
#include <optional>
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

/// The grid's share of the pose's variance (laplace's grid bootstrap): the shrunk covariance of
/// the actual grid's optimum (0) and of `optimum_on_grid(k)`, the optima of the source thinned on
/// shifted grids k = 0, 1, ... (nullopt: not finite, left out), toward `sandwich`, the rest of
/// the covariance. It asks for kGridOffsets grids, and stops after kGridProbeOffsets of them
/// when each gave an optimum and their covariance is below kGridShareNegligible of the sandwich's
/// variance in both blocks (translation, rotation). `grids`: how many it asked for.
struct GridShare {
  PoseMatrix covariance = PoseMatrix::Zero();
  int grids = 0;
};
[[nodiscard]] GridShare grid_share(
    const std::function<std::optional<PoseVector>(int grid)>& optimum_on_grid,
    const PoseMatrix& sandwich);

}  // namespace sgdicp::detail
