// Tests of the grid bootstrap's shrunk covariance and its stopping rule (src/uncertainty/
// shrinkage.hpp) on draws of a known 6-D Gaussian, against the covariance that generated them.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <optional>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>

#include "sgdicp/uncertainty/uncertainty.hpp"
#include "uncertainty/shrinkage.hpp"

namespace sgdicp::detail {
namespace {

// Q diag(scales^2) Q^T for a random rotation Q: correlated axes (a pose's translation in scaled
// units against its rotation in radians, whose standard deviations are of one order on the
// shared scans).
PoseMatrix random_covariance(std::mt19937_64& rng, const PoseVector& scales) {
  std::normal_distribution<double> normal(0.0, 1.0);
  PoseMatrix m;
  for (int i = 0; i < 36; ++i) m(i / 6, i % 6) = normal(rng);
  const PoseMatrix q = Eigen::HouseholderQR<PoseMatrix>(m).householderQ();
  return q * scales.array().square().matrix().asDiagonal() * q.transpose();
}

std::vector<PoseVector> draws_of(const PoseMatrix& covariance, int n, std::mt19937_64& rng) {
  const PoseMatrix l = Eigen::LLT<PoseMatrix>(covariance).matrixL();
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<PoseVector> out(static_cast<std::size_t>(n));
  for (PoseVector& d : out) {
    PoseVector z;
    for (int k = 0; k < 6; ++k) z[k] = normal(rng);
    d = l * z;
  }
  return out;
}

PoseMatrix sample_of(const std::vector<PoseVector>& draws) {
  PoseVector mean = PoseVector::Zero();
  for (const PoseVector& d : draws) mean += d;
  mean /= static_cast<double>(draws.size());
  PoseMatrix s = PoseMatrix::Zero();
  for (const PoseVector& d : draws) s += (d - mean) * (d - mean).transpose();
  return s / static_cast<double>(draws.size() - 1);
}

struct Fixture {
  PoseMatrix truth;
  PoseMatrix shape;  // the truth's shape, wrong by up to 2x in variance along random axes
};

Fixture fixture(std::mt19937_64& rng) {
  PoseVector scales;
  scales << 1.0, 0.6, 0.3, 0.1, 0.06, 0.03;
  const PoseMatrix truth = random_covariance(rng, scales);
  const PoseMatrix root = Eigen::LLT<PoseMatrix>(truth).matrixL();
  PoseVector off;
  off << 2.0, 1.6, 1.2, 0.9, 0.7, 0.5;
  const PoseMatrix mismatch = random_covariance(rng, off.cwiseSqrt());
  return {truth, root * mismatch * root.transpose()};
}

// The mean NEES of an independent error against the covariance of seven draws, as the grid
// bootstrap has: raw, and shrunk toward `shape`.
std::pair<double, double> mean_nees_of_seven(const PoseMatrix& truth, const PoseMatrix& shape,
                                             std::mt19937_64& rng) {
  double raw = 0.0;
  double shrunk = 0.0;
  constexpr int kRepeats = 4000;
  for (int r = 0; r < kRepeats; ++r) {
    const std::vector<PoseVector> draws = draws_of(truth, 7, rng);
    const PoseVector e = draws_of(truth, 1, rng).front();
    raw += e.dot(sample_of(draws).ldlt().solve(e));
    shrunk += e.dot(shrunk_covariance(draws, shape).ldlt().solve(e));
  }
  return {raw / kRepeats, shrunk / kRepeats};
}

// The raw sample covariance has 6 degrees of freedom in 6-D: its inverse has no finite mean (here
// 1e6-4e7). Shrunk, the mean NEES is finite, within 3x of chi-squared's 6 (11.6 toward the
// truth's shape, 16.2 toward one 2x off: seven draws leave the Ledoit-Wolf intensity short of
// 1 even when the target is exact). In laplace the sandwich is added to it.
TEST(GridShrinkage, SevenDrawsGiveAFiniteNees) {
  std::mt19937_64 rng(50);
  const Fixture f = fixture(rng);
  const auto [raw, right] = mean_nees_of_seven(f.truth, f.truth, rng);
  const auto [raw_again, off] = mean_nees_of_seven(f.truth, f.shape, rng);
  std::cout << "mean NEES: sample " << raw << " and " << raw_again << ", shrunk toward the truth "
            << right << ", toward a shape 2x off " << off << "\n";
  EXPECT_GT(std::min(raw, raw_again), 1000.0);
  EXPECT_GT(right, 6.0);
  EXPECT_LT(right, 18.0);
  EXPECT_GT(off, 6.0);
  EXPECT_LT(off, 18.0);
}

// The blocks' traces are the sample covariance's (an unbiased estimate of the truth's).
TEST(GridShrinkage, KeepsTheSampleTracesOfBothBlocks) {
  std::mt19937_64 rng(53);
  const Fixture f = fixture(rng);
  const std::vector<PoseVector> draws = draws_of(f.truth, 7, rng);
  const PoseMatrix s = sample_of(draws);
  const PoseMatrix c = shrunk_covariance(draws, f.shape);
  const auto translation = [](const PoseMatrix& m) { return m.topLeftCorner<3, 3>().trace(); };
  const auto rotation = [](const PoseMatrix& m) { return m.bottomRightCorner<3, 3>().trace(); };
  EXPECT_NEAR(translation(c), translation(s), 1e-9 * translation(s));
  EXPECT_NEAR(rotation(c), rotation(s), 1e-9 * rotation(s));
  EXPECT_TRUE(c.isApprox(c.transpose(), 1e-12));
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<PoseMatrix>(c).eigenvalues().minCoeff(), 0.0);
}

// Many draws: the scatter says the sample is well determined, the intensity falls toward 0 and
// the result is the sample covariance, whatever the shape.
TEST(GridShrinkage, ManyDrawsLeaveTheSampleCovariance) {
  std::mt19937_64 rng(56);
  const Fixture f = fixture(rng);
  const std::vector<PoseVector> draws = draws_of(f.truth, 5000, rng);
  const PoseMatrix root_inverse = PoseMatrix(Eigen::LLT<PoseMatrix>(f.truth).matrixL()).inverse();
  const auto whitened = [&](const PoseMatrix& m) {
    return PoseMatrix(root_inverse * m * root_inverse.transpose());
  };
  const PoseMatrix s = whitened(sample_of(draws));
  const PoseMatrix c = whitened(shrunk_covariance(draws, f.shape));
  EXPECT_LT((c - s).norm(), 0.05 * s.norm());
  EXPECT_LT((c - PoseMatrix::Identity()).norm(), 0.15);
}

// The grid bootstrap asks for every shifted grid where the grids' share is of the sandwich's
// order, and stops after kGridProbeOffsets where it is a small fraction of it in both blocks;
// a share small in one block only is not negligible. Grids are drawn in order, and what the
// bootstrap returns is the shrunk covariance of the draws it asked for, the actual grid's 0
// among them.
TEST(GridShare, StopsEarlyOnlyWhereTheShareIsNegligibleInBothBlocks) {
  std::mt19937_64 rng(62);
  const Fixture f = fixture(rng);
  const auto run = [&](const PoseMatrix& grids_covariance) {
    const std::vector<PoseVector> draws = draws_of(grids_covariance, kGridOffsets, rng);
    std::vector<PoseVector> asked{PoseVector::Zero()};
    const GridShare share = grid_share(
        [&](int grid) -> std::optional<PoseVector> {
          EXPECT_EQ(grid, static_cast<int>(asked.size()) - 1);
          asked.push_back(draws[static_cast<std::size_t>(grid)]);
          return asked.back();
        },
        f.truth);
    EXPECT_EQ(share.grids, static_cast<int>(asked.size()) - 1);
    EXPECT_TRUE(share.covariance.isApprox(shrunk_covariance(asked, f.truth)));
    return share.grids;
  };
  EXPECT_EQ(run(f.truth), kGridOffsets);
  EXPECT_EQ(run(0.003 * f.truth), kGridProbeOffsets);
  // Negligible in translation, as large as the sandwich in rotation: every grid.
  PoseVector blocks;
  blocks << 0.05, 0.05, 0.05, 1.0, 1.0, 1.0;
  EXPECT_EQ(run(blocks.asDiagonal() * f.truth * blocks.asDiagonal()), kGridOffsets);
}

// A grid whose optimum is not finite is left out of the draws, and the others still count; a
// probe short of a grid does not stop the bootstrap, however small the draw it has.
TEST(GridShare, LeavesOutGridsWithoutAFiniteOptimum) {
  std::mt19937_64 rng(65);
  const Fixture f = fixture(rng);
  const std::vector<PoseVector> small = draws_of(0.003 * f.truth, kGridOffsets, rng);
  const GridShare probe_short = grid_share(
      [&](int grid) -> std::optional<PoseVector> {
        if (grid == 0) return std::nullopt;
        return small[static_cast<std::size_t>(grid)];
      },
      f.truth);
  EXPECT_EQ(probe_short.grids, kGridOffsets);
  const std::vector<PoseVector> draws = draws_of(f.truth, kGridOffsets, rng);
  std::vector<PoseVector> kept{PoseVector::Zero()};
  const GridShare share = grid_share(
      [&](int grid) -> std::optional<PoseVector> {
        if (grid == 1) return std::nullopt;
        kept.push_back(draws[static_cast<std::size_t>(grid)]);
        return kept.back();
      },
      f.truth);
  EXPECT_EQ(share.grids, kGridOffsets);
  EXPECT_EQ(kept.size(), static_cast<std::size_t>(kGridOffsets));
  EXPECT_TRUE(share.covariance.isApprox(shrunk_covariance(kept, f.truth)));
}

// Three draws know a block's trace to within ~3x: a probe showing a fifth of the sandwich may
// hide a share as large as the sandwich (at a coarse voxel on a depth frame, 0.16 / 0.12 in the
// probe and 0.57 / 0.93 over 30 grids), so it takes every grid; a tenth stops. The probe's draws
// are 0, d and -d, whose sample covariance is d d^T: its block traces are exactly |d_t|^2, |d_r|^2.
TEST(GridShare, KeepsDrawingWhereTheProbeIsWithinItsSamplingErrorOfTheSandwich) {
  std::mt19937_64 rng(66);
  const Fixture f = fixture(rng);
  const auto grids_for = [&](double share) {
    PoseVector d = PoseVector::Zero();
    d(0) = std::sqrt(share * f.truth.topLeftCorner<3, 3>().trace());
    d(3) = std::sqrt(share * f.truth.bottomRightCorner<3, 3>().trace());
    const std::vector<PoseVector> probe{d, -d};
    return grid_share(
               [&](int grid) -> std::optional<PoseVector> {
                 return grid < kGridProbeOffsets ? probe[static_cast<std::size_t>(grid)] : d;
               },
               f.truth)
        .grids;
  };
  EXPECT_EQ(grids_for(0.2), kGridOffsets);
  EXPECT_EQ(grids_for(0.1), kGridProbeOffsets);
}

TEST(GridShrinkage, DegenerateInputs) {
  EXPECT_TRUE(shrunk_covariance({}, PoseMatrix::Identity()).isZero());
  EXPECT_TRUE(shrunk_covariance({PoseVector::Ones()}, PoseMatrix::Identity()).isZero());
  std::mt19937_64 rng(59);
  const Fixture f = fixture(rng);
  const std::vector<PoseVector> draws = draws_of(f.truth, 7, rng);
  // A shape that is not positive definite: the sample covariance itself.
  EXPECT_TRUE(shrunk_covariance(draws, -PoseMatrix::Identity()).isApprox(sample_of(draws)));
  // Identical draws: no spread, zero.
  EXPECT_TRUE(shrunk_covariance(std::vector<PoseVector>(7, PoseVector::Ones()), f.shape).isZero());
}

}  // namespace
}  // namespace sgdicp::detail
