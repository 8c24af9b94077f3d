// Registration on two threads: the same bits as on one (and clean under ThreadSanitizer, which
// runs the Threads tests: scripts/sanitize.sh).
#include <utility>

#include <gtest/gtest.h>

#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/registration/registration.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

using test::kDeg;
using test::make_transform;
using test::synthetic_scene;

// The registrations of `source` to `reference` with `settings` on one thread and on two.
std::pair<RegistrationResult, RegistrationResult> on_one_and_two_threads(
    const PointCloud& source, const PointCloud& reference, SgdSettings settings) {
  settings.num_threads = 1;
  RegistrationResult one = align(source, reference, settings);
  settings.num_threads = 2;
  return {std::move(one), align(source, reference, settings)};
}

// The final statistics' inlier queries in two halves on two threads, in blocks of 4,096 samples:
// the same inliers, RMSE and constraint ratio as on one thread, and the count a direct query of
// every source point gives.
TEST(Threads, FinalStatisticsOnTwoThreadsCountEveryInlierOnce) {
  const PointCloud reference = synthetic_scene(63, 20000);
  PointCloud source = synthetic_scene(64, 9000);
  for (std::size_t i = 0; i < source.size(); i += 7) source.points[i].z() += 5.0F;  // outliers
  const ReferenceIndex index(reference);
  RegistrationResult one;
  one.T_reference_source = make_transform(0.5 * kDeg, 0, -1 * kDeg, {0.01, 0.02, 0});
  RegistrationResult two = one;
  EvaluationSettings settings;
  settings.evaluation_points = 0;  // every point: three blocks
  evaluate_alignment(source, index, 0.05, settings, 1, one);
  evaluate_alignment(source, index, 0.05, settings, 2, two);
  std::size_t expected = 0;
  const Eigen::Affine3f T(one.T_reference_source.cast<float>());
  for (const auto& p : source.points) expected += index.nearest(T * p, 0.05F * 0.05F) ? 1 : 0;
  EXPECT_GT(expected, 1000U);
  EXPECT_LT(expected, source.size());
  EXPECT_EQ(one.evaluated_points, source.size());
  EXPECT_EQ(one.inliers, expected);
  EXPECT_EQ(two.inliers, expected);
  EXPECT_EQ(two.inlier_rmse_m, one.inlier_rmse_m);
  EXPECT_EQ(two.constraint_ratio, one.constraint_ratio);
}

// Two threads split each mini-batch's queries (and the voxel passes: clouds of >= 32,768
// points); the sums are made in batch order on the caller, so the result is the same to the bit
// as on one thread, on the default's plane cost and the paper's plain point-to-point path.
TEST(Threads, TwoThreadsRegisterBitIdenticallyToOne) {
  const Eigen::Matrix4d T_gt = make_transform(4 * kDeg, -3 * kDeg, 12 * kDeg, {0.2, -0.1, 0.05});
  const PointCloud reference = synthetic_scene(61, 34000);
  const PointCloud source = transformed(synthetic_scene(62, 34000), T_gt.inverse());
  for (const SgdSettings& settings : {SgdSettings{}, SgdSettings::paper(OptimizerType::adam)}) {
    const auto [a, b] = on_one_and_two_threads(source, reference, settings);
    EXPECT_TRUE(a.converged) << a.message;
    EXPECT_EQ(a.T_reference_source, b.T_reference_source);
    EXPECT_EQ(a.iterations, b.iterations);
    EXPECT_EQ(a.points_processed, b.points_processed);
    EXPECT_EQ(a.inlier_rmse_m, b.inlier_rmse_m);
  }
}

// laplace on a thinned source: its grid bootstrap searches every centroid of each shifted grid
// afresh, in two halves summed apart (on the helper with two threads) and added in order: the
// same covariance to the bit (and clean under ThreadSanitizer).
TEST(Threads, TwoThreadsGiveLaplacesCovarianceBitIdentically) {
  const Eigen::Matrix4d T_gt = make_transform(3 * kDeg, -2 * kDeg, 5 * kDeg, {0.1, -0.05, 0.02});
  const PointCloud reference = synthetic_scene(65, 34000);
  const PointCloud source = transformed(synthetic_scene(66, 34000), T_gt.inverse());
  SgdSettings settings;
  settings.uncertainty.method = UncertaintyType::laplace;
  const auto [a, b] = on_one_and_two_threads(source, reference, settings);
  ASSERT_TRUE(a.converged) << a.message;
  EXPECT_GT(a.voxel_size_m, 0.0) << "the grid bootstrap needs a thinned source";
  EXPECT_GT(a.covariance.trace(), 0.0);
  EXPECT_EQ(a.T_reference_source, b.T_reference_source);
  EXPECT_EQ(a.covariance, b.covariance);
}

// A small source is drawn many times, so from its second pass on its queries go through the
// run's memory (src/index/nearest_memory.hpp): looked up in both halves of a batch, new entries
// written after them. Still the same bits as one thread (and clean under ThreadSanitizer, which
// runs the Threads tests).
TEST(Threads, SmallSourceDrawnManyTimesRegistersBitIdenticallyOnTwoThreads) {
  const Eigen::Matrix4d T_gt = make_transform(6 * kDeg, -4 * kDeg, 9 * kDeg, {0.05, -0.03, 0.02});
  const PointCloud reference = synthetic_scene(63, 700);
  const PointCloud source = transformed(synthetic_scene(64, 600), T_gt.inverse());
  const auto [a, b] = on_one_and_two_threads(source, reference, SgdSettings{});
  EXPECT_TRUE(a.converged) << a.message;
  EXPECT_GT(a.points_processed, 3 * source.size()) << "the memory starts with the second pass";
  EXPECT_GE(a.points_processed, a.iterations * 32) << "batches of >= 32 are split";
  EXPECT_EQ(a.T_reference_source, b.T_reference_source);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.inlier_rmse_m, b.inlier_rmse_m);
}

}  // namespace
}  // namespace sgdicp
