// A few far points (a spurious return, a sky point, a bad depth pixel) must not set the scale
// of the scene: bulk_bounding_box on its own, and registrations of real and synthetic clouds with
// far points added, against the same registrations without them (issue: one point at 1 km made
// a KITTI pair take 2080 mini-batches instead of ~120; one at 1e30 m returned the identity as
// converged).
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"
#include "sgdicp/metrics/metrics.hpp"
#include "sgdicp/points/scaling.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/tools/pairs.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

using test::kDeg;
using test::make_transform;
using test::synthetic_scene;

PointCloud with_point(PointCloud cloud, const Eigen::Vector3f& p) {
  cloud.points.insert(cloud.points.begin() + static_cast<std::ptrdiff_t>(cloud.size() / 2), p);
  return cloud;
}

TEST(BulkBoundingBox, IsTheExactBoxWithoutFarPoints) {
  const PointCloud cloud = synthetic_scene(1, 20000);
  const ScalingBox bulk = bulk_bounding_box(cloud);
  const BoundingBox all = BoundingBox::of(cloud);
  EXPECT_EQ(bulk.far_points, 0U);
  EXPECT_EQ(bulk.box.min, all.min);
  EXPECT_EQ(bulk.box.max, all.max);
}

TEST(BulkBoundingBox, LeavesOutAndCountsFarPoints) {
  const PointCloud cloud = synthetic_scene(2, 20000);
  const BoundingBox all = BoundingBox::of(cloud);
  for (const float far : {1e3F, -1e4F, 1e30F}) {
    PointCloud noisy = with_point(cloud, {far, 0.0F, 0.0F});
    noisy = with_point(noisy, {0.0F, far, far});
    const ScalingBox bulk = bulk_bounding_box(noisy);
    EXPECT_EQ(bulk.far_points, 2U) << far;
    EXPECT_EQ(bulk.box.min, all.min) << far;
    EXPECT_EQ(bulk.box.max, all.max) << far;
  }
}

TEST(BulkBoundingBox, KeepsAFlatSceneAndItsNearbyPoints) {
  // A wall (no extent in z): the margin is relative to the bulk's largest side, so a point 1 m
  // off a 4 m wall is part of the scene.
  PointCloud wall;
  for (int i = 0; i < 100; ++i) {
    for (int j = 0; j < 100; ++j) wall.points.emplace_back(0.04F * i, 0.04F * j, 0.0F);
  }
  const PointCloud with_off_plane = with_point(wall, {2.0F, 2.0F, 1.0F});
  const ScalingBox bulk = bulk_bounding_box(with_off_plane);
  EXPECT_EQ(bulk.far_points, 0U);
  EXPECT_EQ(bulk.box.max.z(), 1.0);
}

TEST(BulkBoundingBox, TinyCloudsKeepEveryPoint) {
  PointCloud three;
  three.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 1}};
  EXPECT_EQ(bulk_bounding_box(three).far_points, 0U);
}

// A synthetic 2 m scene with one point at 1e30 m in the source: the scale and the answer are
// those of the clean pair (the bounding box made every other point a dot at the origin).
TEST(RobustScaling, AFarPointDoesNotChangeTheAnswer) {
  const Eigen::Matrix4d T_gt = make_transform(3 * kDeg, -2 * kDeg, 10 * kDeg, {0.15, 0.1, 0.05});
  const PointCloud source = synthetic_scene(41);
  const ReferenceIndex reference(transformed(synthetic_scene(42), T_gt));
  const RegistrationResult clean = align(source, reference);
  for (const float far : {1e3F, 1e5F, 1e30F}) {
    const RegistrationResult r = align(with_point(source, {far, -far, far}), reference);
    EXPECT_TRUE(r.converged) << far << ": " << r.message;
    EXPECT_EQ(r.far_points, 1U);
    EXPECT_EQ(r.scale_m, clean.scale_m);
    EXPECT_LT(translation_error(r.T_reference_source, T_gt), 0.01) << far;
    EXPECT_LT(rotation_error_geodesic(r.T_reference_source, T_gt), 0.3 * kDeg) << far;
  }
}

TEST(RobustScaling, ThePaperPresetKeepsThePapersBoundingBox) {
  const PointCloud source = with_point(synthetic_scene(43, 5000), {1e3F, 0.0F, 0.0F});
  const ReferenceIndex reference(synthetic_scene(44, 5000));
  SgdSettings paper = SgdSettings::paper();
  paper.max_iterations = 50;
  const RegistrationResult r = align(source, reference, paper);
  EXPECT_EQ(r.far_points, 0U);
  EXPECT_GT(r.scale_m, 1e3);
}

// The real case: KITTI 000001 <- 000000 with one return added at 1 km, 10 km and 100 km.
// Expected: the accuracy and the work of the clean pair, within the noise of a different
// sampling order (one point more changes every mini-batch).
TEST(RobustScaling, KittiScanWithAFarReturn) {
  const auto file = std::filesystem::path(SGDICP_SHARED_DATA) / "pairs/kitti_seq00.txt";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "missing " << file;
  const RegistrationPair pair = read_pairs_file(file).front();
  const PointCloud source = read_point_cloud(pair.source).cloud;
  const ReferenceIndex reference(read_point_cloud(pair.reference).cloud);
  const RegistrationResult clean = align(source, reference);
  ASSERT_TRUE(clean.converged);
  for (const float far : {1e3F, 1e4F, 1e5F}) {
    const RegistrationResult r = align(with_point(source, {far, far, 10.0F}), reference);
    EXPECT_TRUE(r.converged) << far << ": " << r.message;
    EXPECT_EQ(r.far_points, 1U);
    EXPECT_LT(r.iterations, 2 * clean.iterations) << far;
    EXPECT_LT(translation_error(r.T_reference_source, pair.T_reference_source_gt), 0.05) << far;
    EXPECT_LT(rotation_error_geodesic(r.T_reference_source, pair.T_reference_source_gt), 0.2 * kDeg)
        << far;
  }
}

// A whole scene beyond 1e9 m (a cloud scaled by 1e30) cannot be paired in single precision: a
// clear error, not "degenerate" or a silent identity. A single far point stays fine (above).
TEST(RobustScaling, ASceneBeyondTheFloatRangeIsRejected) {
  PointCloud source = synthetic_scene(45, 2000);
  for (auto& p : source.points) p *= 1e30F;
  const PointCloud reference = source;
  EXPECT_THROW((void)align(source, reference), InvalidInputError);
  EXPECT_THROW((void)align(source, reference, SgdSettings::paper()), InvalidInputError);
}

// One evaluation point does not decide the geometry: the degeneracy check samples on its own.
TEST(RobustScaling, OneEvaluationPointDoesNotMakeTheSceneDegenerate) {
  const Eigen::Matrix4d T_gt = make_transform(2 * kDeg, 1 * kDeg, 5 * kDeg, {0.05, 0.02, 0.0});
  const PointCloud source = synthetic_scene(46);
  const PointCloud reference = transformed(synthetic_scene(47), T_gt);
  SgdSettings settings;
  settings.evaluation.evaluation_points = 1;
  const RegistrationResult r = align(source, reference, settings);
  EXPECT_EQ(r.evaluated_points, 1U);
  EXPECT_FALSE(r.degenerate) << r.message;
  const double usual = align(source, reference).constraint_ratio;
  EXPECT_NEAR(r.constraint_ratio, usual, 0.2 * usual);
}

}  // namespace
}  // namespace sgdicp
