#include "uncertainty/shrinkage.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "sgdicp/uncertainty/uncertainty.hpp"

namespace sgdicp::detail {
namespace {

PoseMatrix sample_covariance(const std::vector<PoseVector>& deviations) {
  PoseMatrix s = PoseMatrix::Zero();
  for (const PoseVector& d : deviations) s += d * d.transpose();
  return s / static_cast<double>(deviations.size() - 1);
}

// The traces of the translation and of the rotation block of `m`.
Eigen::Array2d block_traces(const PoseMatrix& m) {
  return {m.topLeftCorner<3, 3>().trace(), m.bottomRightCorner<3, 3>().trace()};
}

// `m` with its translation and rotation blocks scaled to the traces of `like`'s.
PoseMatrix with_block_traces_of(const PoseMatrix& m, const PoseMatrix& like) {
  const Eigen::Array2d want = block_traces(like);
  const Eigen::Array2d have = block_traces(m);
  const Eigen::Array2d factor = (have > 0.0).select((want / have).sqrt(), 0.0);
  PoseVector d;
  d.head<3>().setConstant(factor[0]);
  d.tail<3>().setConstant(factor[1]);
  return d.asDiagonal() * m * d.asDiagonal();
}

// Whether `grid` is below kGridShareNegligible of `sandwich` in the traces of both blocks.
bool negligible_beside(const PoseMatrix& grid, const PoseMatrix& sandwich) {
  return (block_traces(grid) < kGridShareNegligible * block_traces(sandwich)).all();
}

}  // namespace

PoseMatrix shrunk_covariance(const std::vector<PoseVector>& draws, const PoseMatrix& shape) {
  if (draws.size() < 2) return PoseMatrix::Zero();
  PoseVector mean = PoseVector::Zero();
  for (const PoseVector& d : draws) mean += d;
  mean /= static_cast<double>(draws.size());
  std::vector<PoseVector> deviations;
  deviations.reserve(draws.size());
  for (const PoseVector& d : draws) deviations.push_back(d - mean);
  const PoseMatrix sample = sample_covariance(deviations);

  const Eigen::LLT<PoseMatrix> llt(shape);
  if (llt.info() != Eigen::Success || !sample.allFinite()) return sample;
  const PoseMatrix l = llt.matrixL();
  const PoseMatrix l_inverse = l.inverse();
  // In the space whitened by `shape` the target is alpha I, alpha the sample's mean variance.
  for (PoseVector& d : deviations) d = l_inverse * d;
  const PoseMatrix whitened = sample_covariance(deviations);
  const double alpha = whitened.trace() / 6.0;
  const PoseMatrix target = alpha * PoseMatrix::Identity();
  // Ledoit-Wolf: the intensity is the draws' scatter about the sample covariance (each draw's
  // n/(n-1) d d^T is one unbiased estimate of it) over the sample's distance to the target.
  const auto n = static_cast<double>(draws.size());
  double scatter = 0.0;
  for (const PoseVector& d : deviations) {
    scatter += ((n / (n - 1.0)) * d * d.transpose() - whitened).squaredNorm();
  }
  const double distance = (whitened - target).squaredNorm();
  const double intensity = distance > 0.0 ? std::min(distance, scatter / (n * n)) / distance : 1.0;
  const PoseMatrix shrunk = intensity * target + (1.0 - intensity) * whitened;
  return with_block_traces_of(l * shrunk * l.transpose(), sample);
}

// Each grid costs a thinning of the raw source and a fresh search of every centroid, 2/3 of
// laplace's time. Where the first grids' share is a fraction of the sandwich (the sparse LiDAR
// scans: 4-19 % of the variance), what the rest could add moves the total by a fraction of that;
// where it dominates (dense depth frames: 0.8-5x the sandwich) every grid is needed. Three draws
// know the share to ~3x, so the threshold leaves that margin (docs/design.md, *A negligible grid
// share stops the bootstrap*).
GridShare grid_share(const std::function<std::optional<PoseVector>(int grid)>& optimum_on_grid,
                     const PoseMatrix& sandwich) {
  std::vector<PoseVector> optima{PoseVector::Zero()};
  GridShare share;
  for (; share.grids < kGridOffsets; ++share.grids) {
    // Only from a full probe: fewer draws (a grid without a finite optimum) say too little.
    if (share.grids == kGridProbeOffsets &&
        optima.size() == static_cast<std::size_t>(kGridProbeOffsets) + 1) {
      share.covariance = shrunk_covariance(optima, sandwich);
      if (negligible_beside(share.covariance, sandwich)) return share;
    }
    if (const std::optional<PoseVector> optimum = optimum_on_grid(share.grids)) {
      optima.push_back(*optimum);
    }
  }
  share.covariance = shrunk_covariance(optima, sandwich);
  return share;
}

}  // namespace sgdicp::detail
