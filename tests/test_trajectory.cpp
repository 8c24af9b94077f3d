// Trajectory metrics against hand-computed cases, and the trajectory files.
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "sgdicp/core/error.hpp"
#include "sgdicp/io/trajectory_io.hpp"
#include "sgdicp/metrics/trajectory_metrics.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

using test::kDeg;
using test::make_transform;

// A wavy 3D path, frames turning as they go.
std::vector<Eigen::Matrix4d> wavy_path(std::size_t n) {
  std::vector<Eigen::Matrix4d> out;
  for (std::size_t k = 0; k < n; ++k) {
    const double s = static_cast<double>(k);
    out.push_back(make_transform(0.01 * s, 0.02 * std::sin(s), 0.05 * s,
                                 {s, 2.0 * std::sin(0.3 * s), 0.1 * s}));
  }
  return out;
}

TEST(TrajectoryMetrics, ARigidlyMovedTrajectoryHasZeroError) {
  std::mt19937_64 rng(7);
  const auto truth = wavy_path(30);
  const Eigen::Matrix4d M = test::random_rigid(rng, 50.0);
  std::vector<Eigen::Matrix4d> estimate;
  for (const auto& T : truth) estimate.push_back(M * T);  // another world frame
  const auto ate = absolute_trajectory_error(estimate, truth);
  EXPECT_LT(ate.error.rmse, 1e-9);
  EXPECT_TRUE((ate.T_truth_estimate * M).isApprox(Eigen::Matrix4d::Identity(), 1e-9));
  const auto rpe = relative_pose_errors(estimate, truth, 1);
  EXPECT_LT(rpe.translation.max, 1e-9);
  EXPECT_LT(rpe.rotation.max, 1e-5);
  EXPECT_LT(end_drift(estimate, truth).translation_m, 1e-9);
}

TEST(TrajectoryMetrics, AConstantScaleDriftGivesTheKnownErrors) {
  // Straight line, 1 m per frame; the estimate moves 1.01 m per frame: every frame-to-frame
  // error is 1 cm, every segment of L m is off by L / 100 m (1 %), the end by (n - 1) cm.
  const std::size_t n = 301;
  std::vector<Eigen::Matrix4d> truth, estimate;
  for (std::size_t k = 0; k < n; ++k) {
    const double s = static_cast<double>(k);
    truth.push_back(make_transform(0, 0, 0, {s, 0, 0}));
    estimate.push_back(make_transform(0, 0, 0, {1.01 * s, 0, 0}));
  }
  const auto rpe = relative_pose_errors(estimate, truth, 1);
  EXPECT_EQ(rpe.translation.count, n - 1);
  EXPECT_NEAR(rpe.translation.rmse, 0.01, 1e-9);
  EXPECT_NEAR(rpe.translation.median, 0.01, 1e-9);
  EXPECT_NEAR(relative_pose_errors(estimate, truth, 10).translation.mean, 0.1, 1e-9);
  const auto drift = kitti_drift(estimate, truth);
  ASSERT_TRUE(drift);
  // Segments end at the first frame beyond first + L: L + 1 m long on the truth's 1 m grid,
  // so the error is (L + 1) / 100 over L.
  double expected = 0.0;
  std::size_t segments = 0;
  for (std::size_t first = 0; first < n; first += 10) {
    for (const double L : kKittiSegmentLengths_m) {
      if (static_cast<double>(first) + L + 1 > static_cast<double>(n - 1)) continue;
      expected += (L + 1) / 100.0 / L;
      ++segments;
    }
  }
  EXPECT_EQ(drift->segments, segments);
  EXPECT_NEAR(drift->translation_percent, 100.0 * expected / static_cast<double>(segments), 1e-9);
  EXPECT_NEAR(drift->rotation_deg_per_m, 0.0, 1e-9);
  const EndDrift end = end_drift(estimate, truth);
  EXPECT_NEAR(end.translation_m, 0.01 * (n - 1), 1e-9);
  EXPECT_NEAR(end.path_length_m, n - 1.0, 1e-9);
  EXPECT_NEAR(end.translation_percent, 1.0, 1e-9);
}

TEST(TrajectoryMetrics, AConstantYawDriftGivesTheKnownRotationError) {
  std::vector<Eigen::Matrix4d> truth, estimate;
  for (int k = 0; k < 20; ++k) {
    truth.push_back(Eigen::Matrix4d::Identity());
    estimate.push_back(make_transform(0, 0, 0.1 * kDeg * k, Eigen::Vector3d::Zero()));
  }
  const auto rpe = relative_pose_errors(estimate, truth, 1);
  EXPECT_NEAR(rpe.rotation.mean, 0.1, 1e-6);
  EXPECT_NEAR(rpe.rotation.max, 0.1, 1e-6);
  EXPECT_NEAR(end_drift(estimate, truth).rotation_deg, 1.9, 1e-6);
  EXPECT_FALSE(kitti_drift(estimate, truth));  // no path: no 100 m segment
}

TEST(TrajectoryMetrics, AteOfAKnownOffsetAfterAlignment) {
  // Estimate = truth with one frame displaced by d: after the best rigid fit the residual RMSE is
  // below d / sqrt(n) (the fit can only reduce it) and above 0.
  auto truth = wavy_path(10);
  auto estimate = truth;
  estimate[4](2, 3) += 1.0;
  const auto ate = absolute_trajectory_error(estimate, truth);
  EXPECT_GT(ate.error.rmse, 0.1);
  EXPECT_LE(ate.error.rmse, 1.0 / std::sqrt(10.0) + 1e-12);
}

TEST(TrajectoryMetrics, RigidAlignmentRecoversAKnownTransform) {
  std::mt19937_64 rng(3);
  const Eigen::Matrix4d T = test::random_rigid(rng, 10.0);
  std::vector<Eigen::Vector3d> p, q;
  for (int i = 0; i < 50; ++i) {
    p.emplace_back(test::uniform(rng, -5, 5), test::uniform(rng, -5, 5), test::uniform(rng, -5, 5));
    q.push_back((T * p.back().homogeneous()).head<3>());
  }
  EXPECT_TRUE(rigid_alignment(p, q).isApprox(T, 1e-10));
}

TEST(TrajectoryMetrics, DifferentLengthsAreRefused) {
  const auto a = wavy_path(5), b = wavy_path(6);
  EXPECT_THROW((void)relative_pose_errors(a, b), InvalidInputError);
  EXPECT_THROW((void)absolute_trajectory_error(a, b), InvalidInputError);
}

TEST(TrajectoryIo, KittiAndTumRoundTrip) {
  test::TempDir dir;
  const auto poses = wavy_path(12);
  std::vector<double> times;
  for (int i = 0; i < 12; ++i) times.push_back(1e9 + 0.1 * i);
  write_kitti_poses(dir.path() / "p.txt", poses);
  write_tum_trajectory(dir.path() / "p.tum", poses, times);
  const Trajectory kitti = read_trajectory(dir.path() / "p.txt");
  const Trajectory tum = read_trajectory(dir.path() / "p.tum");
  EXPECT_EQ(kitti.format, "kitti");
  EXPECT_EQ(tum.format, "tum");
  ASSERT_EQ(kitti.poses.size(), 12U);
  ASSERT_EQ(tum.poses.size(), 12U);
  for (int i = 0; i < 12; ++i) {
    EXPECT_TRUE(kitti.poses[i].isApprox(poses[i], 1e-7)) << i;
    EXPECT_TRUE(tum.poses[i].isApprox(poses[i], 1e-7)) << i;
    EXPECT_NEAR(tum.timestamps_s[i], times[i], 1e-6);
  }
  std::ifstream in(dir.path() / "p.txt");
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "1 0 0 0 0 1 0 0 0 0 1 0");
}

TEST(TrajectoryIo, SevenScenesFolderIsReadAndReOrthonormalised) {
  test::TempDir dir;
  for (int i = 0; i < 3; ++i) {
    std::ofstream out(dir.path() / ("frame-00000" + std::to_string(i) + ".pose.txt"));
    // A rotation off orthonormal by 1e-4, as dense-tracking poses are.
    out << "1.0001 0 0 " << i << "\n0 1 0 0\n0 0 0.9999 0\n0 0 0 1\n";
  }
  const Trajectory t = read_trajectory(dir.path());
  EXPECT_EQ(t.format, "7scenes");
  ASSERT_EQ(t.poses.size(), 3U);
  const Eigen::Matrix3d R = t.poses[2].topLeftCorner<3, 3>();
  EXPECT_TRUE(R.isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_DOUBLE_EQ(t.poses[2](0, 3), 2.0);
}

TEST(TrajectoryIo, BadFilesNameTheFileAndLine) {
  test::TempDir dir;
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir.path() / name) << text;
    return dir.path() / name;
  };
  const auto expect_message = [](const std::filesystem::path& p, const std::string& part) {
    try {
      (void)read_trajectory(p);
      ADD_FAILURE() << p;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  expect_message(write("a.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n"), "line 2");
  expect_message(write("b.txt", "1 2 3\n"), "12 (KITTI poses) or 8");
  expect_message(write("c.txt", "1 0 0 0 0 1 0 0 0 0 x 0\n"), "'x'");
  expect_message(write("d.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n"), "not a rigid");
  expect_message(write("e.txt", "# nothing\n"), "no pose");
  expect_message(dir.path() / "missing.txt", "cannot open");
}

}  // namespace
}  // namespace sgdicp
