// Odometry on the shared real sequences: the first KITTI scans, 7-Scenes frames, and the
// hand-held LiDAR at rates and in orders that turn it hardest.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <tuple>

#include <gtest/gtest.h>

#include "odometry_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/frame_source.hpp"
#include "sgdicp/io/io.hpp"
#include "sgdicp/io/trajectory_io.hpp"
#include "sgdicp/metrics/metrics.hpp"
#include "sgdicp/metrics/trajectory_metrics.hpp"
#include "sgdicp/odometry/odometry.hpp"
#include "sgdicp/odometry/voxel_map.hpp"

namespace sgdicp {
namespace {

using test::kDeg;
using test::make_transform;

// ---- real data

const std::filesystem::path kKitti =
    std::filesystem::path(SGDICP_SHARED_DATA) / "kitti_odometry_seq00";

// The 6 KITTI scans against the maintainers' ICP pseudo ground truth (PROVENANCE.md: the official
// poses are 0.15 m per frame off here): pose 5 within 10 cm and 0.2 deg of T_0_5 (the
// reference's own spread is 2-9 cm).
TEST(OdometryKitti, SixScansFollowTheReference) {
  if (!std::filesystem::exists(kKitti / "velodyne")) GTEST_SKIP() << "no " << kKitti;
  const FrameSource source = open_frame_source(kKitti);
  ASSERT_EQ(source.size(), 6U);
  EXPECT_EQ(source.layout, "kitti");
  ASSERT_EQ(source.timestamps_s.size(), 6U);
  Odometry odometry;
  for (std::size_t i = 0; i < source.size(); ++i) odometry.register_frame(source.read(i));
  for (const auto& r : odometry.reports()) EXPECT_FALSE(r.failed) << r.index << r.message;
  std::ifstream in(kKitti / "reference_relative_poses_icp.txt");
  std::string line;
  bool checked = false;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    int i = 0, j = 0;
    if (!(row >> i >> j) || i != 0 || j != 5) continue;
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) row >> T(r, c);
    }
    const Eigen::Matrix4d& P = odometry.poses()[5];
    EXPECT_LT(translation_error(P, T), 0.10);
    EXPECT_LT(rotation_error_geodesic(P, T) * 180 / std::numbers::pi, 0.2);
    checked = true;
  }
  EXPECT_TRUE(checked);
}

// The first 30 frames of 7-Scenes RedKitchen (30 Hz, hand-held): 1.5 cm ATE and 0.5 deg RPE
// bounds, about twice the measured 8 mm / 0.18 deg over 100 frames; the dense-tracking poses
// are millimetre-consistent between frames (PROVENANCE.md).
TEST(OdometrySevenScenes, FirstFramesFollowThePoses) {
  const auto folder = std::filesystem::path(SGDICP_SHARED_DATA) / "sevenscenes_redkitchen";
  if (!std::filesystem::exists(folder / "camera-intrinsics.txt")) GTEST_SKIP() << "no " << folder;
  const FrameSource source = open_frame_source(folder);
  EXPECT_EQ(source.layout, "7scenes");
  ASSERT_EQ(source.size(), 600U);
  const Trajectory truth = read_trajectory(folder);
  OdometrySettings s;
  s.max_range_m = 5.0;
  Odometry odometry(s);
  const std::size_t n = 30;
  for (std::size_t i = 0; i < n; ++i) odometry.register_frame(source.read(i));
  for (const auto& r : odometry.reports()) EXPECT_FALSE(r.failed) << r.index << r.message;
  const std::vector<Eigen::Matrix4d> gt(truth.poses.begin(), truth.poses.begin() + n);
  const auto ate = absolute_trajectory_error(odometry.poses(), gt);
  const auto rpe = relative_pose_errors(odometry.poses(), gt);
  EXPECT_LT(ate.error.rmse, 0.015);
  EXPECT_LT(rpe.rotation.rmse, 0.5);
  EXPECT_LT(rpe.translation.rmse, 0.01);
}

// A KITTI scan (57 m) as the second of the 7-Scenes frames (3.3 m): with two frames the larger
// range decides the voxel, so it asked for 0.57 m voxels; the scan is lost, and the growth is
// taken back with it (before, every frame after it was lost). The frames after it track.
TEST(OdometrySevenScenes, AScanOfAnotherSensorAsTheSecondFrameTakesItsVoxelGrowthBack) {
  const auto folder = std::filesystem::path(SGDICP_SHARED_DATA) / "sevenscenes_redkitchen";
  if (!std::filesystem::exists(folder / "camera-intrinsics.txt") ||
      !std::filesystem::exists(kKitti / "velodyne")) {
    GTEST_SKIP() << "no " << folder << " or " << kKitti;
  }
  const FrameSource source = open_frame_source(folder);
  const Trajectory truth = read_trajectory(folder);
  Odometry odometry;
  odometry.register_frame(source.read(0));
  const double voxel_m = odometry.voxel_size_m();
  odometry.register_frame(read_point_cloud(kKitti / "velodyne" / "000000.bin").cloud);
  EXPECT_TRUE(odometry.reports().back().failed);
  EXPECT_EQ(odometry.voxel_size_m(), voxel_m);
  for (std::size_t i = 1; i < 10; ++i) {
    odometry.register_frame(source.read(i));
    EXPECT_FALSE(odometry.reports().back().failed) << i << odometry.reports().back().message;
    const Eigen::Matrix4d truth_i = truth.poses[0].inverse() * truth.poses[i];
    EXPECT_LT(translation_error(odometry.poses().back(), truth_i), 0.02) << i;
  }
  EXPECT_EQ(odometry.voxel_size_m(), voxel_m);
}

// Each frame-to-frame motion of the odometry within 5 cm and 0.5 deg of the reference's
// (T_world: the reference pose of each registered frame, in order).
void expect_steps_follow(const Odometry& odometry, const std::vector<Eigen::Matrix4d>& T_world) {
  for (std::size_t k = 1; k < T_world.size(); ++k) {
    const Eigen::Matrix4d truth_step = T_world[k - 1].inverse() * T_world[k];
    const Eigen::Matrix4d step = odometry.poses()[k - 1].inverse() * odometry.poses()[k];
    EXPECT_LT(translation_error(step, truth_step), 0.05)
        << k << ": " << odometry.reports()[k].message;
    EXPECT_LT(rotation_error_geodesic(step, truth_step) * 180 / std::numbers::pi, 0.5) << k;
  }
}

// Every `step`-th scan of the shared hand-held LiDAR scans from 0 to `last`: no frame lost, and
// every frame-to-frame motion within 5 cm and 0.5 deg of the reference (the reference is good to
// about 5 mm / 0.05 deg).
// The hand-held LiDAR's `scans`, in that order, keep the track: no frame lost, each
// frame-to-frame motion within 5 cm and 0.5 deg of the reference. Fills `reports` if given.
// The first scan is cropped to first_range_m from the sensor when it is above 0. Returns the
// odometry (in `done`, as GTEST_SKIP cannot return a value).
void expect_scans_tracked(const std::vector<std::size_t>& scans,
                          std::vector<FrameReport>* reports = nullptr, double first_range_m = 0.0,
                          std::optional<Odometry>* done = nullptr) {
  const auto folder = std::filesystem::path(SGDICP_SHARED_DATA) / "balm_handheld_lidar";
  if (!std::filesystem::exists(folder / "poses.txt")) GTEST_SKIP() << "no " << folder;
  Odometry odometry;
  const FrameSource source = open_frame_source(folder / "scans");
  const Trajectory truth = read_kitti_poses(folder / "poses.txt");
  std::vector<Eigen::Matrix4d> T_world;
  for (const std::size_t i : scans) {
    const PointCloud scan = source.read(i);
    odometry.register_frame(
        T_world.empty() && first_range_m > 0.0 ? crop_range(scan, 0.0, first_range_m) : scan);
    T_world.push_back(truth.poses[i]);
  }
  EXPECT_EQ(odometry.lost_frames(), 0U);
  expect_steps_follow(odometry, T_world);
  if (reports) *reports = odometry.reports();
  if (done) done->emplace(std::move(odometry));
}

void expect_every_nth_scan_tracked(std::size_t step, std::size_t last) {
  std::vector<std::size_t> scans;
  for (std::size_t i = 0; i <= last; i += step) scans.push_back(i);
  expect_scans_tracked(scans);
}

// The hand-held LiDAR at 0.67 Hz (every third scan of ../shared/data/balm_handheld_lidar, scans
// 100-133): between scans 127 and 130 the sensor turns 62 deg, with 46 deg and 17 deg after. The
// track holds through the turn: no frame lost, each frame-to-frame motion within 5 cm and
// 0.5 deg of the reference (measured: at most 1.8 cm / 0.09 deg; the reference is good to about
// 5 mm / 0.05 deg). Before the rotation bound was dropped, frame 10 and every frame after failed.
TEST(OdometryHandheldLidar, EveryThirdScanKeepsTheTrackThroughA62DegreeTurn) {
  expect_every_nth_scan_tracked(3, 33);
}

// Never a confident wrong frame. Cropped to 4-12 m, the hand-held LiDAR sees a floor and little
// else: some motion is unconstrained, and frames register 0.1-1 m off with overlaps as high as
// the right frames'. Every frame whose motion from the frame before is more than 10 cm or 2 deg
// off the reference's is reported doubtful or lost (measured: 75, 70, 59 and 11 such frames at
// 4, 6, 8 and 12 m, every one doubtful); uncropped, every frame is right and none is doubtful.
TEST(OdometryHandheldLidar, CroppedScansEveryWrongFrameIsDoubtfulAndUncroppedNone) {
  const auto folder = std::filesystem::path(SGDICP_SHARED_DATA) / "balm_handheld_lidar";
  if (!std::filesystem::exists(folder / "poses.txt")) GTEST_SKIP() << "no " << folder;
  const FrameSource source = open_frame_source(folder / "scans");
  const Trajectory truth = read_kitti_poses(folder / "poses.txt");
  for (const double range_m : {4.0, 6.0, 8.0, 12.0, 100.0}) {
    OdometrySettings settings;
    settings.max_range_m = range_m;
    Odometry odometry(settings);
    for (std::size_t i = 0; i < source.size(); ++i) odometry.register_frame(source.read(i));
    std::size_t wrong = 0, flagged = 0;
    for (std::size_t k = 1; k < source.size(); ++k) {
      const FrameReport& r = odometry.reports()[k];
      flagged += r.doubtful || r.failed ? 1 : 0;
      const Eigen::Matrix4d step = odometry.poses()[k - 1].inverse() * odometry.poses()[k];
      const Eigen::Matrix4d truth_step = truth.poses[k - 1].inverse() * truth.poses[k];
      if (translation_error(step, truth_step) <= 0.10 &&
          rotation_error_geodesic(step, truth_step) * 180 / std::numbers::pi <= 2.0) {
        continue;
      }
      ++wrong;
      EXPECT_TRUE(r.doubtful || r.failed) << range_m << " m, frame " << k << ": " << r.message;
    }
    std::cout << "max range " << range_m << " m: " << wrong << " wrong frames, " << flagged
              << " doubtful or lost\n";
    if (range_m == 100.0) {
      EXPECT_EQ(wrong, 0U);
      EXPECT_EQ(flagged, 0U);
    }
  }
}

// Kinect frames cropped to 1.5 m (7-Scenes, the first 200): no frame is wrong (10 cm / 2 deg
// frame to frame) and at most the second is doubtful, its prediction unknown (measured over the
// 600 frames: 0 wrong, 1 doubtful; yet the end is 0.27 m / 14.5 deg off, a bias of 0.024 deg a
// frame that no per-frame test sees: docs/long-runs.md, *Doubtful frames*).
TEST(OdometrySevenScenes, CroppedTo1p5MetresNoWrongFrameGoesUnflagged) {
  const auto folder = std::filesystem::path(SGDICP_SHARED_DATA) / "sevenscenes_redkitchen";
  if (!std::filesystem::exists(folder / "camera-intrinsics.txt")) GTEST_SKIP() << "no " << folder;
  const FrameSource source = open_frame_source(folder);
  const Trajectory truth = read_trajectory(folder);
  OdometrySettings settings;
  settings.max_range_m = 1.5;
  Odometry odometry(settings);
  const std::size_t n = 200;
  for (std::size_t i = 0; i < n; ++i) odometry.register_frame(source.read(i));
  std::size_t flagged = 0;
  for (std::size_t k = 1; k < n; ++k) {
    const FrameReport& r = odometry.reports()[k];
    flagged += r.doubtful || r.failed ? 1 : 0;
    const Eigen::Matrix4d step = odometry.poses()[k - 1].inverse() * odometry.poses()[k];
    const Eigen::Matrix4d truth_step = truth.poses[k - 1].inverse() * truth.poses[k];
    const bool wrong = translation_error(step, truth_step) > 0.10 ||
                       rotation_error_geodesic(step, truth_step) * 180 / std::numbers::pi > 2.0;
    EXPECT_TRUE(!wrong || r.doubtful || r.failed) << k << ": " << r.message;
  }
  EXPECT_LE(flagged, 2U);
}

// Every fifth scan (0.4 Hz): scan 65 comes 2.8 m and 55 deg after scan 60, and from the
// prediction it registered 26 deg and 3 m off with an overlap of 0.48, above half the last
// frames' 0.82 and taken. An overlap below 0.8 of theirs is doubtful: the other starts are
// tried, and the global registration overlaps 0.97 at the right pose.
TEST(OdometryHandheldLidar, EveryFifthScanADoubtfulOverlapTriesTheOtherStarts) {
  expect_every_nth_scan_tracked(5, 70);
}

// Every eighth scan (0.25 Hz): the sensor moves 5.2-5.9 m and turns up to 115 deg between
// scans. A bound of 5 m per frame (the former default) rejected the correct registrations of
// scans 24 and 40 and lost them; the default bound is the frame's own range (about 21 m here).
TEST(OdometryHandheldLidar, EveryEighthScanTheTranslationBoundIsTheFramesRange) {
  expect_every_nth_scan_tracked(8, 72);
}

// Played backwards every sixth scan (72, 66, ... 48): the second frame comes 3 m on along a
// corridor. From the prediction it slid 3 m too far with 0.20 of it on the map, taken because no
// earlier frame's overlap was known to doubt it, and the frames after it were 2-3 m off against
// that map. Before any overlap is known, less than half the frame on the map is doubtful: the
// other starts are tried, and one of them overlaps 0.57 at the right pose.
TEST(OdometryHandheldLidar, PlayedBackwardsTheSecondFrameWithLittleOverlapIsDoubtful) {
  std::vector<FrameReport> reports;
  expect_scans_tracked({72, 66, 60, 54, 48}, &reports);
  if (reports.empty()) return;  // skipped: no shared data
  EXPECT_TRUE(reports[1].recovered) << reports[1].message;
  EXPECT_NE(reports[1].message.find("no earlier frame's to compare"), std::string::npos)
      << reports[1].message;
}

// Played backwards every eighth scan (72, 64, ... 40): scan 48 comes 5.2 m and 56 deg on, in a
// corridor. The global registration puts it 2.3 m too far along the corridor with a doubtful
// 0.57 of the frame on the map; the wide basin registers it right, but unconfirmed by the global
// answer it was thrown out and the global one taken (and the frames after it were off against
// it). A doubtful global answer that overlaps less than the wide basin's disproves nothing.
TEST(OdometryHandheldLidar, PlayedBackwardsADoubtfulGlobalAnswerDoesNotOverruleTheWideBasin) {
  expect_scans_tracked({72, 64, 56, 48, 40});
}

// The hand-held LiDAR swung round by 150 deg between its 4th and 5th scans (a sensor turned with
// frames dropped; from then on every scan comes turned): the prediction and the last pose are
// rejected, the wide basin does not reach that far, and the global registration against the map
// (no guess) registers the frame; the scans after it follow from there. Before the global retry,
// frames 4-7 were lost (141-157 deg off).
// The first scan seen from a small room: cropped to 10 m, its 1 % voxel is 10 cm for a 21 m
// scene (cropped to 5 m: 5 cm, 4x the time per frame and the memory over the 77 scans). The
// second scan sees 21 m: before it is registered the voxel grows to 1 % of that, and the track
// holds. (Within 5 or 8 m of the sensor this scene is mostly ground: the second scan's motion is
// not determined by the first one's points, whatever the voxel.)
TEST(OdometryHandheldLidar, AVoxelFromASmallFirstScanGrowsWithTheScansRange) {
  std::optional<Odometry> odometry;
  expect_scans_tracked({0, 1, 2, 3, 4, 5, 6}, nullptr, 10.0, &odometry);
  if (!odometry) return;  // skipped
  EXPECT_GT(odometry->voxel_size_m(), 0.15);
  EXPECT_LT(odometry->voxel_size_m(), 0.3);
  EXPECT_NE(odometry->reports()[1].message.find("voxel 0.0"), std::string::npos)
      << odometry->reports()[1].message;
}

TEST(OdometryHandheldLidar, AScanSpunBy150DegreesIsRecoveredByTheGlobalStart) {
  const auto folder = std::filesystem::path(SGDICP_SHARED_DATA) / "balm_handheld_lidar";
  if (!std::filesystem::exists(folder / "poses.txt")) GTEST_SKIP() << "no " << folder;
  const FrameSource source = open_frame_source(folder / "scans");
  const Trajectory truth = read_kitti_poses(folder / "poses.txt");
  const Eigen::Matrix4d spin = make_transform(0, 0, 150.0 * kDeg, Eigen::Vector3d::Zero());
  Odometry odometry;
  std::vector<Eigen::Matrix4d> T_world;  // of the sensor as it is turned
  for (std::size_t i = 0; i < 7; ++i) {
    PointCloud scan = source.read(i);
    if (i >= 4) scan = transformed(scan, spin.inverse());
    odometry.register_frame(scan);
    T_world.push_back(i >= 4 ? Eigen::Matrix4d(truth.poses[i] * spin) : truth.poses[i]);
  }
  EXPECT_EQ(odometry.lost_frames(), 0U);
  EXPECT_EQ(odometry.reports()[4].start, FrameStart::global) << odometry.reports()[4].message;
  expect_steps_follow(odometry, T_world);
}

// One entry of a hostile sequence: a scan of the hand-held LiDAR, or something else in its place.
struct HostileFrame {
  enum Kind { scan, repeat, empty, non_finite, unreadable, other_sensor } kind = scan;
  std::size_t index = 0;  // the scan (kind scan)
};

// What a long run meets, mixed into the hand-held LiDAR's scans: frames out of order (12 before
// 10 and 11), the same frame twice, an empty frame, a frame of NaN points, an unreadable file, a
// scan of another sensor (a KITTI car LiDAR), a gap of 15 scans (1.5 s: 3.4 m and 62 deg), and the
// path walked back. Each is reported on its own frame and none ends the run; every scan is
// registered, and its pose, from the first scan, within 10 cm and 1 deg of the reference's.
TEST(OdometryHandheldLidar, AHostileSequenceIsReportedFrameByFrameAndTheTrackResumes) {
  const auto folder = std::filesystem::path(SGDICP_SHARED_DATA) / "balm_handheld_lidar";
  if (!std::filesystem::exists(folder / "poses.txt") ||
      !std::filesystem::exists(kKitti / "velodyne")) {
    GTEST_SKIP() << "no " << folder << " or " << kKitti;
  }
  using K = HostileFrame::Kind;
  std::vector<HostileFrame> sequence;
  for (std::size_t i : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 12, 10, 11, 13})
    sequence.push_back({K::scan, i});
  sequence.push_back({K::repeat});
  sequence.push_back({K::empty});
  for (std::size_t i : {14, 15}) sequence.push_back({K::scan, i});
  sequence.push_back({K::non_finite});
  sequence.push_back({K::unreadable});
  sequence.push_back({K::other_sensor});
  for (std::size_t i : {16, 17, 18, 33, 34, 35, 34, 33, 32, 31}) sequence.push_back({K::scan, i});
  const FrameSource source = open_frame_source(folder / "scans");
  const Trajectory truth = read_kitti_poses(folder / "poses.txt");
  Odometry odometry;
  PointCloud last;
  for (const HostileFrame& f : sequence) {
    switch (f.kind) {
      case K::scan:
        last = source.read(f.index);
        odometry.register_frame(last);
        break;
      case K::repeat:
        odometry.register_frame(last);
        break;
      case K::empty:
        odometry.register_frame(PointCloud{});
        break;
      case K::non_finite: {
        PointCloud nans = last;
        for (auto& p : nans.points) p.setConstant(std::numeric_limits<float>::quiet_NaN());
        odometry.register_frame(nans);
        break;
      }
      case K::unreadable:
        odometry.skip_frame("unreadable: a truncated file");
        break;
      case K::other_sensor:
        odometry.register_frame(read_point_cloud(kKitti / "velodyne" / "000000.bin").cloud);
        break;
    }
  }
  ASSERT_EQ(odometry.reports().size(), sequence.size());
  for (std::size_t k = 0; k < sequence.size(); ++k) {
    const FrameReport& r = odometry.reports()[k];
    const HostileFrame& f = sequence[k];
    SCOPED_TRACE("frame " + std::to_string(k) + ": " + r.message);
    EXPECT_EQ(r.message.find(kInternalError), std::string::npos);
    if (f.kind == K::repeat) {
      EXPECT_TRUE(r.repeated);
      EXPECT_FALSE(r.failed);
    } else if (f.kind != K::scan) {
      EXPECT_TRUE(r.failed);
    } else {
      EXPECT_FALSE(r.failed);
      const Eigen::Matrix4d T_truth = truth.poses[0].inverse() * truth.poses[f.index];
      EXPECT_LT(translation_error(odometry.poses()[k], T_truth), 0.10);
      EXPECT_LT(rotation_error_geodesic(odometry.poses()[k], T_truth) * 180 / std::numbers::pi,
                1.0);
    }
  }
}

}  // namespace
}  // namespace sgdicp
