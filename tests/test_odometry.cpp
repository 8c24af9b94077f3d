// Odometry: the adaptive threshold, the prediction, failure reporting, a synthetic sequence with
// exact ground truth (the voxel map: test_voxel_map.cpp; the real sequences:
// test_odometry_real_data.cpp).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <random>
#include <sstream>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "odometry_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/frame_source.hpp"
#include "sgdicp/io/trajectory_io.hpp"
#include "sgdicp/metrics/metrics.hpp"
#include "sgdicp/metrics/trajectory_metrics.hpp"
#include "sgdicp/odometry/odometry.hpp"

namespace sgdicp {
namespace {

using test::kDeg;
using test::make_transform;

TEST(AdaptiveThreshold, InitialUntilAMotionIsSeen) {
  AdaptiveThreshold t(2.0, 0.1);
  EXPECT_DOUBLE_EQ(t.sigma_m(), 2.0);
  t.update(make_transform(0, 0, 0, {0.05, 0, 0}), 10.0);  // below min motion: not a sample
  EXPECT_EQ(t.samples(), 0U);
  EXPECT_DOUBLE_EQ(t.sigma_m(), 2.0);
}

TEST(AdaptiveThreshold, IsTheRmsOfTheDeviations) {
  AdaptiveThreshold t(2.0, 0.1);
  t.update(make_transform(0, 0, 0, {0.3, 0, 0}), 10.0);
  t.update(make_transform(0, 0, 0, {0, 0.4, 0}), 10.0);
  EXPECT_EQ(t.samples(), 2U);
  EXPECT_NEAR(t.sigma_m(), std::sqrt((0.09 + 0.16) / 2.0), 1e-12);
}

TEST(AdaptiveThreshold, ARotationCountsAsTheDisplacementAtMaxRange) {
  // 1 degree at 100 m: a chord of 2 * 100 * sin(0.5 deg) = 1.745 m.
  const Eigen::Matrix4d R = make_transform(0, 0, 1.0 * kDeg, Eigen::Vector3d::Zero());
  EXPECT_NEAR(AdaptiveThreshold::displacement_m(R, 100.0), 200.0 * std::sin(0.5 * kDeg), 1e-9);
  const Eigen::Matrix4d both = make_transform(0, 0, 1.0 * kDeg, {0.3, 0.4, 0});
  EXPECT_NEAR(AdaptiveThreshold::displacement_m(both, 10.0), 0.5 + 20.0 * std::sin(0.5 * kDeg),
              1e-9);
}

TEST(OdometrySettings, ValidateNamesTheOption) {
  OdometrySettings s;
  s.max_range_m = -1;
  try {
    s.validate(SettingNames::cli);
    FAIL();
  } catch (const InvalidSettingsError& e) {
    EXPECT_NE(std::string(e.what()).find("--max-range"), std::string::npos) << e.what();
  }
  s = {};
  s.min_range_m = 200;
  EXPECT_THROW(s.validate(), InvalidSettingsError);
  s = {};
  s.max_points_per_voxel = 0;
  EXPECT_THROW(Odometry{s}, InvalidSettingsError);
  EXPECT_THROW(Odometry({}, "no-such-method"), InvalidSettingsError);
  // Settings given with a method are used as they are, so they must carry its cost.
  EXPECT_THROW(Odometry({}, "sgd-plane", SgdSettings::paper()), InvalidSettingsError);
  EXPECT_THROW(Odometry({}, "icp-plane", std::nullopt, BatchSettings{}), InvalidSettingsError);
  EXPECT_NE(find_odometry_setting("max_points_per_voxel"), nullptr);
}

TEST(Odometry, FirstFrameIsTheIdentityAndEmptyFramesFail) {
  Odometry odometry;
  const auto seq = test::synthetic_sequence(2, 0.3, 0.0, 1, 4000);
  EXPECT_TRUE(odometry.register_frame(seq.frames[0]).isIdentity());
  EXPECT_FALSE(odometry.reports()[0].failed);
  odometry.register_frame(PointCloud{});
  EXPECT_TRUE(odometry.reports()[1].failed);
  EXPECT_EQ(odometry.poses().size(), 2U);
}

namespace {
Eigen::Matrix4d motion_of(double yaw_rad, const Eigen::Vector3d& t_m) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).matrix();
  T.topRightCorner<3, 1>() = t_m;
  return T;
}
}  // namespace

TEST(MotionModel, ASteadyMotionIsPredictedAsItIs) {
  MotionModel model;
  EXPECT_TRUE(model.predicted().isIdentity());
  const Eigen::Matrix4d step = motion_of(0.1, Eigen::Vector3d(0.5, 0.1, 0.0));
  for (int k = 0; k < 10; ++k) model.update(step);
  EXPECT_NEAR(model.rotation_carry(), 1.0, 1e-12);
  EXPECT_NEAR(model.translation_carry(), 1.0, 1e-12);
  EXPECT_TRUE(model.predicted().isApprox(step, 1e-12));
  model.forget_last();  // frames lost: the motion since the last registered one is unknown
  EXPECT_TRUE(model.predicted().isIdentity());
}

// The covariance's softening: measured on the first kWarmUp frames, then on every kEvery-th;
// between, the last one measured, so that a softening drifting as the map fills is followed (a
// frame without a laplace covariance, softening 0, measures nothing).
TEST(SofteningMemory, MeasuresEveryFewFramesAndGivesTheLastMeasured) {
  SofteningMemory memory;
  double last = 0.0;
  int measurements = 0;
  for (int frame = 0; frame < 60; ++frame) {
    const double asked = memory.next();
    if (frame < static_cast<int>(SofteningMemory::kWarmUp)) {
      EXPECT_EQ(asked, 0.0) << "frame " << frame << " is in the warm-up";
    }
    if (asked == 0.0) {
      last = 0.8 - 0.01 * frame;  // drifting, as along a sequence
      ++measurements;
      memory.record(last);
      continue;
    }
    EXPECT_EQ(asked, last) << "frame " << frame;
    memory.record(asked);
  }
  // 3 warm-up measurements, then one in every kEvery frames of the other 57.
  EXPECT_EQ(measurements, 3 + 57 / static_cast<int>(SofteningMemory::kEvery));
  SofteningMemory none;
  for (int frame = 0; frame < 20; ++frame) {
    EXPECT_EQ(none.next(), 0.0);
    none.record(0.0);  // sgld or svgd: no softening
  }
}

// A sensor swung to and fro (turns of alternating sign) while walking steadily: the turns do not
// carry over, the walk does; before kMinPairs pairs, constant velocity.
TEST(MotionModel, TurnsThatDoNotCarryOverAreNotPredicted) {
  MotionModel model;
  const Eigen::Vector3d walk(0.4, 0.0, 0.0);
  for (std::size_t k = 0; k < MotionModel::kMinPairs; ++k) {
    model.update(motion_of(k % 2 == 0 ? 0.3 : -0.3, walk));
  }
  EXPECT_EQ(model.rotation_carry(), 1.0) << "too few pairs: constant velocity";
  for (int k = 0; k < 20; ++k) model.update(motion_of(k % 2 == 0 ? 0.3 : -0.3, walk));
  EXPECT_EQ(model.rotation_carry(), 0.0) << "negative correlation is clamped to none";
  EXPECT_NEAR(model.translation_carry(), 1.0, 1e-12);
  EXPECT_TRUE(model.predicted().isApprox(motion_of(0.0, walk), 1e-12));
  // Half of each turn carries over (a turn fading out, then a new one every ten frames): c = 1/2
  // up to the new turns' tiny pairs (0.2 after 0.0004 rad).
  MotionModel half;
  double yaw = 0.2;
  for (int k = 0; k < 40; ++k) {
    half.update(motion_of(yaw, walk));
    yaw = (k + 1) % 10 == 0 ? 0.2 : 0.5 * yaw;
  }
  EXPECT_NEAR(half.rotation_carry(), 0.5, 0.01);
}

TEST(Odometry, AFailedFrameGetsTheConstantVelocityPrediction) {
  const auto seq = test::synthetic_sequence(3, 0.4, 2.0, 2, 8000);
  Odometry odometry;
  for (const auto& f : seq.frames) odometry.register_frame(f);
  const Eigen::Matrix4d T1 = odometry.poses()[1], T2 = odometry.poses()[2];
  const Eigen::Matrix4d T3 = odometry.skip_frame("cannot read");
  EXPECT_TRUE(odometry.reports().back().failed);
  EXPECT_EQ(odometry.reports().back().message, "cannot read");
  EXPECT_TRUE(T3.isApprox(T2 * T1.inverse() * T2, 1e-12));
  // ... and the next failure repeats the same motion again.
  const Eigen::Matrix4d T4 = odometry.skip_frame("cannot read");
  EXPECT_TRUE(T4.isApprox(T3 * T2.inverse() * T3, 1e-12));
}

TEST(Odometry, AMotionBeyondThePhysicalBoundIsAFailureNotAPose) {
  const auto seq = test::synthetic_sequence(4, 0.5, 0.0, 3, 8000);
  OdometrySettings s;
  s.max_translation_per_frame_m = 0.05;  // the sensor moves 0.4-0.6 m per frame
  Odometry odometry(s);
  for (const auto& f : seq.frames) odometry.register_frame(f);
  for (std::size_t i = 1; i < 4; ++i) {
    EXPECT_TRUE(odometry.reports()[i].failed) << i;
    EXPECT_NE(odometry.reports()[i].message.find("beyond the bounds"), std::string::npos);
    EXPECT_TRUE(odometry.poses()[i].isIdentity(1e-12));  // the prediction from standing still
  }
}

// The whole pipeline on a sequence with exact ground truth: 30 frames, 0.4 m and 1 deg per
// frame (12 m, a 30 deg bend). Each frame is a fresh sample of the world (no point is seen
// Without settings the method's cost is used in every stage; given settings are kept as they
// are, so that a coarse cost chosen after the method's (--coarse-cost, coarse_cost=) survives.
TEST(Odometry, MethodCostAndAChosenCoarseCost) {
  const Odometry plane({}, "sgd-plane");
  EXPECT_EQ(plane.sgd_settings().cost, CostType::point_to_plane);
  EXPECT_EQ(plane.sgd_settings().coarse_cost, CostType::point_to_plane);
  EXPECT_EQ(Odometry({}, "icp-plane").batch_settings().cost, CostType::point_to_plane);
  SgdSettings chosen;
  BatchSettings batch;
  apply_method_cost(method_from_string("sgd-plane"), chosen, batch);
  chosen.coarse_cost = CostType::point_to_point;
  const Odometry kept({}, "sgd-plane", chosen);
  EXPECT_EQ(kept.sgd_settings().cost, CostType::point_to_plane);
  EXPECT_EQ(kept.sgd_settings().coarse_cost, CostType::point_to_point);
  EXPECT_EQ(kept.sgd_settings().downsampling.downsample_to, 0U);  // the pipeline keeps its own grid
}

// twice), 5 mm noise.
TEST(Odometry, SyntheticSequenceEndDriftIsSmall) {
  const auto seq = test::synthetic_sequence(30, 0.4, 1.0, 4, 6000);
  // Bounds about 3x the measured errors: sgd 2.5 cm / 0.12 deg, icp-plane 7.5 cm / 0.92 deg.
  // icp-plane may lose one frame: on the spaced map (a point enters a voxel only with no point of
  // it within v / sqrt(20)) its batch solver cycles on frame 28 of this seed, unconverged after
  // 100 or 1000 iterations from every start (it took 3 on the map without the spacing); seeds 1-3
  // and 5-10 lose none, and its end drift and ATE here are lower than without the spacing.
  struct Case {
    const char* method;
    double max_m, max_deg;
    std::size_t max_lost;
  };
  for (const auto& [method, max_m, max_deg, max_lost] :
       {Case{"sgd", 0.08, 0.4, 0}, Case{"icp-plane", 0.2, 2.5, 1}}) {
    Odometry odometry({}, method);
    for (const auto& f : seq.frames) odometry.register_frame(f);
    std::size_t failed = 0;
    for (const auto& r : odometry.reports()) failed += r.failed ? 1 : 0;
    EXPECT_LE(failed, max_lost) << method;
    const EndDrift end = end_drift(odometry.poses(), seq.T_world_frame);
    const auto ate = absolute_trajectory_error(odometry.poses(), seq.T_world_frame);
    const auto rpe = relative_pose_errors(odometry.poses(), seq.T_world_frame);
    std::vector<double> times, builds;
    for (const auto& r : odometry.reports()) {
      times.push_back(r.time_ms);
      builds.push_back(r.index_build_ms);
    }
    std::sort(times.begin(), times.end());
    std::sort(builds.begin(), builds.end());
    std::cout << method << ": median " << times[times.size() / 2] << " ms per frame, index "
              << builds[builds.size() / 2] << " ms, map " << odometry.map()->size() << " points\n";
    std::cout << method << ": end drift " << end.translation_m << " m " << end.rotation_deg
              << " deg, ATE " << ate.error.rmse << " m, RPE " << rpe.translation.rmse << " m "
              << rpe.rotation.rmse << " deg\n";
    EXPECT_LT(end.translation_m, max_m) << method;
    EXPECT_LT(end.rotation_deg, max_deg) << method;
    EXPECT_LT(rpe.translation.max, 0.05) << method;
  }
}

// A derived voxel follows the frames' range upwards; a voxel the user set stays. The first
// frame is cropped to 6 m (a sensor starting close to a wall), the others see 15 m.
TEST(Odometry, ADerivedVoxelGrowsWithTheFramesRangeAndASetOneStays) {
  const auto seq = test::synthetic_sequence(8, 0.4, 1.0, 4, 6000);
  for (const double set_m : {0.0, 0.05}) {
    OdometrySettings settings;
    settings.voxel_size_m = set_m;
    Odometry odometry(settings);
    odometry.register_frame(crop_range(seq.frames[0], 0.0, 6.0));
    const double first_m = odometry.voxel_size_m();
    for (std::size_t f = 1; f < seq.frames.size(); ++f) odometry.register_frame(seq.frames[f]);
    EXPECT_EQ(odometry.lost_frames(), 0U) << set_m;
    if (set_m > 0.0) {
      EXPECT_EQ(odometry.voxel_size_m(), set_m);
      continue;
    }
    EXPECT_LT(first_m, 0.065);
    EXPECT_GT(odometry.voxel_size_m(), 0.12);  // 1 % of the 15 m frames' 99th percentile
    EXPECT_LT(odometry.voxel_size_m(), 0.16);
    const EndDrift end = end_drift(odometry.poses(), seq.T_world_frame);
    EXPECT_LT(end.translation_m, 0.08);
  }
}

// The registrations that track take Gauss-Newton steps in their coarse stage while the optimizer
// is the default (tracking_gauss_newton): fewer mini-batches than Adam's steps of one length, as
// precise; a step rule of the user's own is kept from every start.
TEST(Odometry, TrackingTakesGaussNewtonStepsUnlessAStepRuleIsChosen) {
  // A hand-held sensor swung about: turns of up to 20 deg that do not carry over, so that the
  // prediction is degrees off and the coarse stage has a way to go.
  std::vector<Eigen::Matrix4d> T_world{test::synthetic_start()};
  for (int f = 1; f < 12; ++f) {
    T_world.push_back(T_world.back() * make_transform(0.02 * std::sin(2.1 * f), 0.0,
                                                      20 * std::sin(1.3 * f) * kDeg,
                                                      Eigen::Vector3d(0.3, 0.05, 0.0)));
  }
  test::SyntheticSequence seq;
  seq.frames = test::synthetic_frames(T_world, 4, 6000);
  for (const auto& T : T_world) seq.T_world_frame.push_back(T_world.front().inverse() * T);
  OdometrySettings adam_steps;
  adam_steps.tracking_gauss_newton = false;
  Odometry newton, adam(adam_steps);
  SgdSettings momentum;
  momentum.optimizer = {OptimizerType::momentum, default_learning_rate(OptimizerType::momentum)};
  OdometrySettings momentum_off;
  momentum_off.tracking_gauss_newton = false;
  Odometry chosen({}, "sgd", momentum), chosen_off(momentum_off, "sgd", momentum);
  std::size_t newton_iterations = 0, adam_iterations = 0;
  for (const auto& f : seq.frames) {
    newton.register_frame(f);
    adam.register_frame(f);
    EXPECT_TRUE(chosen.register_frame(f) == chosen_off.register_frame(f))
        << "a chosen step rule is used from every start";
    newton_iterations += newton.reports().back().iterations;
    adam_iterations += adam.reports().back().iterations;
  }
  EXPECT_EQ(newton.lost_frames() + adam.lost_frames(), 0U);
  const EndDrift newton_drift = end_drift(newton.poses(), seq.T_world_frame);
  const EndDrift adam_drift = end_drift(adam.poses(), seq.T_world_frame);
  std::cout << "tracking: Gauss-Newton " << newton_iterations << " mini-batches, end drift "
            << newton_drift.translation_m << " m " << newton_drift.rotation_deg << " deg; Adam "
            << adam_iterations << ", " << adam_drift.translation_m << " m "
            << adam_drift.rotation_deg << " deg\n";
  EXPECT_LT(newton_iterations, 0.85 * static_cast<double>(adam_iterations));
  EXPECT_LT(newton_drift.translation_m, 0.05);
  EXPECT_LT(newton_drift.rotation_deg, 0.3);
}

// Two views of one place fed back and forth, as a robot that paces a corridor: the map's voxels
// fill, and soon a frame adds no point to the map. The map's normals must outlive that frame (the
// frame after it found none: "the point-to-plane cost needs reference normals", issue 54).
TEST(Odometry, AFrameThatAddsNoPointKeepsTheMapsSurfaces) {
  const auto seq = test::synthetic_sequence(2, 0.2, 2.0, 21, 6000);
  OdometrySettings settings;
  settings.max_points_per_voxel = 1;
  Odometry odometry(settings);
  std::size_t added_none = 0;
  for (std::size_t k = 0; k < 6; ++k) {
    const std::size_t map_size = odometry.map() ? odometry.map()->size() : 0;
    odometry.register_frame(seq.frames[k % 2]);
    const FrameReport& r = odometry.reports().back();
    ASSERT_FALSE(r.failed) << "frame " << k << ": " << r.message;
    EXPECT_TRUE(odometry.map()->points().has_normals()) << "frame " << k;
    if (k > 0 && odometry.map()->size() == map_size) ++added_none;
  }
  EXPECT_GE(added_none, 3U);  // the case is met
  EXPECT_LT(translation_error(odometry.poses().back(), seq.T_world_frame[1]), 0.02);
}

// A sensor delivering the same frame again and again (a stalled driver): ten repeats each keep
// the pose, and the motion model waits for the next real frame.
TEST(Odometry, ARepeatedFrameKeepsThePoseAndTheMotion) {
  const auto seq = test::synthetic_sequence(4, 0.4, 1.0, 6, 6000);
  Odometry odometry;
  for (std::size_t i = 0; i < 3; ++i) odometry.register_frame(seq.frames[i]);
  const Eigen::Matrix4d T2 = odometry.poses()[2];
  for (int repeat = 0; repeat < 10; ++repeat) {
    EXPECT_TRUE(odometry.register_frame(seq.frames[2]) == T2);  // the same frame again
    EXPECT_TRUE(odometry.reports().back().repeated);
    EXPECT_FALSE(odometry.reports().back().failed);
  }
  // The motion model is kept: frame 3 registers from the prediction of the motion before.
  odometry.register_frame(seq.frames[3]);
  EXPECT_FALSE(odometry.reports().back().failed) << odometry.reports().back().message;
  EXPECT_FALSE(odometry.reports().back().recovered) << odometry.reports().back().message;
  EXPECT_LT(translation_error(odometry.poses().back(), seq.T_world_frame[3]), 0.05);
}

// A hand-held jerk: after six frames walking 0.5 m per frame the sensor steps 0.5 m back and
// turns 60 deg in one frame. The prediction (0.5 m ahead, no turn) and the last pose are beyond
// the adaptive threshold's reach (measured: overlap 0.05 and 0.03 against 0.74 before); the wide
// basin registers the frame, and the walk that follows keeps the track. (A 40 deg turn the
// tracking's Gauss-Newton steps now register from the prediction itself.)
TEST(Odometry, AFrameBeyondThePredictionIsRecovered) {
  std::vector<Eigen::Matrix4d> T_world{test::synthetic_start()};
  for (int f = 1; f < 10; ++f) {
    const bool jerk = f == 6;  // a step back and a turn
    T_world.push_back(T_world.back() * make_transform(0, 0, jerk ? 60.0 * kDeg : 0.0,
                                                      Eigen::Vector3d(jerk ? -0.5 : 0.5, 0, 0)));
  }
  const auto frames = test::synthetic_frames(T_world, 8, 6000);
  Odometry odometry;
  for (const auto& f : frames) odometry.register_frame(f);
  const FrameReport& jerk = odometry.reports()[6];
  EXPECT_FALSE(jerk.failed) << jerk.message;
  EXPECT_TRUE(jerk.recovered) << jerk.message;
  EXPECT_NE(jerk.start, FrameStart::prediction);
  for (std::size_t i = 1; i < frames.size(); ++i) {
    EXPECT_FALSE(odometry.reports()[i].failed) << i << ": " << odometry.reports()[i].message;
    const Eigen::Matrix4d T_truth = T_world[0].inverse() * T_world[i];
    EXPECT_LT(translation_error(odometry.poses()[i], T_truth), 0.05) << i;
    EXPECT_LT(rotation_error_geodesic(odometry.poses()[i], T_truth) * 180.0 / std::numbers::pi, 0.5)
        << i;
  }
}

// The synthetic hall is nearly symmetric under a half turn (floor and walls dominate): a frame
// spun by 150 deg in place was registered by the wide basin 180 deg off, with a high overlap. A
// wide-basin answer stands only if the global registration confirms it: the frame is registered
// right, or lost saying why, never a confident wrong pose that poisons the map. (Without the
// check, frames 6-8 end 180 deg off.)
TEST(Odometry, AFrameSpunBeyondTheWideBasinIsRightOrLostNeverConfidentlyWrong) {
  std::vector<Eigen::Matrix4d> T_world{test::synthetic_start()};
  for (int f = 1; f < 9; ++f) {
    const bool spin = f == 6;
    T_world.push_back(T_world.back() * make_transform(0, 0, spin ? 150.0 * kDeg : 0.0,
                                                      Eigen::Vector3d(spin ? 0.0 : 0.5, 0, 0)));
  }
  const auto frames = test::synthetic_frames(T_world, 8, 6000);
  Odometry odometry;
  for (const auto& f : frames) odometry.register_frame(f);
  for (std::size_t i = 1; i < frames.size(); ++i) {
    const FrameReport& r = odometry.reports()[i];
    if (r.failed) continue;
    const Eigen::Matrix4d T_truth = T_world[0].inverse() * T_world[i];
    EXPECT_LT(rotation_error_geodesic(odometry.poses()[i], T_truth) * 180.0 / std::numbers::pi, 1.0)
        << i << ": " << r.message;
  }
}

// A scan of another world in the middle of a sequence: lost, reported, and neither the map nor
// the motion model takes it in, so the next frame registers from the motion before it.
TEST(Odometry, AFrameOfAnotherSceneIsLostWithoutPoisoningTheTrack) {
  const auto seq = test::synthetic_sequence(8, 0.4, 1.0, 9, 6000);
  std::mt19937_64 rng(3);
  PointCloud stranger;  // a 2 m ball of points: nothing like the room
  for (int i = 0; i < 6000; ++i) {
    stranger.points.emplace_back(Eigen::Vector3d(test::uniform(rng, -1, 1),
                                                 test::uniform(rng, -1, 1),
                                                 test::uniform(rng, -1, 1))
                                     .normalized()
                                     .cast<float>() *
                                 2.0F);
  }
  Odometry odometry;
  for (std::size_t i = 0; i < 4; ++i) odometry.register_frame(seq.frames[i]);
  const std::size_t map_points = odometry.map()->size();
  odometry.register_frame(stranger);
  EXPECT_TRUE(odometry.reports().back().failed);
  EXPECT_NE(odometry.reports().back().message.find("lost"), std::string::npos);
  EXPECT_EQ(odometry.map()->size(), map_points);
  for (std::size_t i = 4; i < 8; ++i) {
    odometry.register_frame(seq.frames[i]);
    EXPECT_FALSE(odometry.reports().back().failed)
        << i << ": " << odometry.reports().back().message;
    EXPECT_LT(translation_error(odometry.poses().back(), seq.T_world_frame[i]), 0.05) << i;
  }
}

// A covariance is symmetric positive definite: every eigenvalue above 0, within rounding of
// its transpose.
void expect_covariance(const Eigen::Matrix<double, 6, 6>& C, const std::string& what) {
  ASSERT_TRUE(C.allFinite()) << what << ":\n" << C;
  EXPECT_LE((C - C.transpose()).cwiseAbs().maxCoeff(), 1e-12 * C.cwiseAbs().maxCoeff()) << what;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(C);
  EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0) << what << ":\n" << C;
}

bool all_nan(const Eigen::Matrix<double, 6, 6>& C) {
  return C.array().isNaN().all();
}

SgdSettings with_laplace() {
  SgdSettings s;
  s.uncertainty.method = UncertaintyType::laplace;
  return s;
}

// With an uncertainty each registered frame carries the covariance of its pose relative to the
// map (its registration's covariance_se3); the first frame's is zero (it defines the coordinates),
// a repeated frame keeps the previous one's, and a frame without a registration has NaN.
TEST(Odometry, EveryRegisteredFrameCarriesTheCovarianceOfItsPose) {
  const auto seq = test::synthetic_sequence(4, 0.4, 1.0, 12, 6000);
  Odometry odometry({}, "sgd", with_laplace());
  odometry.register_frame(seq.frames[0]);
  odometry.register_frame(seq.frames[1]);
  odometry.register_frame(seq.frames[1]);  // repeated
  odometry.register_frame(PointCloud{});   // no point: failed
  odometry.register_frame(seq.frames[2]);
  odometry.register_frame(seq.frames[3]);
  const std::vector<FrameReport>& r = odometry.reports();
  ASSERT_EQ(r.size(), 6U);
  EXPECT_TRUE(r[0].covariance.isZero(0.0)) << r[0].covariance;
  for (const std::size_t i : {1U, 4U, 5U}) {
    ASSERT_FALSE(r[i].failed) << i << ": " << r[i].message;
    expect_covariance(r[i].covariance, "frame " + std::to_string(i));
    // Metres and radians: a frame of 6000 points with 5 mm noise is registered within
    // millimetres and hundredths of a degree, not a scaled unit's 30 m.
    const Eigen::Matrix<double, 6, 1> sd = r[i].covariance.diagonal().cwiseSqrt();
    EXPECT_LT(sd.head<3>().maxCoeff(), 0.01) << i << ": " << sd.transpose();
    EXPECT_LT(sd.tail<3>().maxCoeff(), 0.1 * kDeg) << i << ": " << sd.transpose();
  }
  EXPECT_TRUE(r[2].repeated);
  EXPECT_TRUE(r[2].covariance == r[1].covariance);
  EXPECT_TRUE(r[3].failed);
  EXPECT_TRUE(all_nan(r[3].covariance)) << r[3].covariance;
  EXPECT_FALSE(r[4].covariance == r[5].covariance);  // each frame its own
  odometry.skip_frame("unreadable");
  EXPECT_TRUE(all_nan(odometry.reports().back().covariance));
}

// A softening the user gives (UncertaintySettings::softening) is used on every frame, in place of
// the sequence's own: half of it about quadruples every frame's covariance.
TEST(Odometry, ASofteningTheUserGivesIsKept) {
  const auto seq = test::synthetic_sequence(6, 0.4, 1.0, 12, 6000);
  std::vector<double> traces[2];
  for (const double given : {0.6, 0.3}) {
    SgdSettings s = with_laplace();
    s.uncertainty.softening = given;
    Odometry odometry({}, "sgd", s);
    for (const auto& f : seq.frames) odometry.register_frame(f);
    for (const FrameReport& r : odometry.reports()) {
      if (r.index > 0) traces[given < 0.5 ? 1 : 0].push_back(r.covariance.trace());
    }
  }
  ASSERT_EQ(traces[0].size(), 5U);
  ASSERT_EQ(traces[1].size(), 5U);
  for (std::size_t k = 0; k < traces[0].size(); ++k) {
    EXPECT_NEAR(traces[1][k] / traces[0][k], 4.0, 1.0) << "frame " << k + 1;
  }
}

// Without an uncertainty nothing is estimated: every frame's covariance is NaN, the first too.
TEST(Odometry, WithoutAnUncertaintyEveryCovarianceIsNaN) {
  const auto seq = test::synthetic_sequence(3, 0.4, 1.0, 12, 6000);
  Odometry odometry;
  for (const auto& f : seq.frames) odometry.register_frame(f);
  odometry.register_frame(seq.frames[2]);  // repeated
  for (const FrameReport& r : odometry.reports()) {
    EXPECT_FALSE(r.failed) << r.index << ": " << r.message;
    EXPECT_TRUE(all_nan(r.covariance)) << r.index << ":\n" << r.covariance;
  }
}

// A frame registered by a retry carries its covariance as well: the global start and the wide
// basin register with the settings' uncertainty. A batch method has none to give: refused.
TEST(Odometry, ARecoveredFrameCarriesItsCovarianceAndABatchMethodHasNone) {
  std::vector<Eigen::Matrix4d> T_world{test::synthetic_start()};
  for (int f = 1; f < 8; ++f) {
    const bool jerk = f == 6;  // as AFrameBeyondThePredictionIsRecovered
    T_world.push_back(T_world.back() * make_transform(0, 0, jerk ? 60.0 * kDeg : 0.0,
                                                      Eigen::Vector3d(jerk ? -0.5 : 0.5, 0, 0)));
  }
  const auto frames = test::synthetic_frames(T_world, 8, 6000);
  Odometry odometry({}, "sgd", with_laplace());
  for (const auto& f : frames) odometry.register_frame(f);
  const FrameReport& jerk = odometry.reports()[6];
  ASSERT_FALSE(jerk.failed) << jerk.message;
  EXPECT_TRUE(jerk.recovered) << jerk.message;
  expect_covariance(jerk.covariance, "frame 6, from the " + std::string(enum_name(jerk.start)));
  expect_covariance(odometry.reports()[7].covariance, "frame 7");

  try {
    const Odometry batch({}, "icp-plane", with_laplace());
    FAIL() << "icp-plane with an uncertainty";
  } catch (const InvalidSettingsError& e) {
    EXPECT_NE(std::string(e.what()).find("only the SGD methods estimate an uncertainty"),
              std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(Odometry({}, "sgd-plane", [] {
    SgdSettings s = with_laplace();
    s.cost = s.coarse_cost = CostType::point_to_plane;
    return s;
  }()));
}

TEST(Odometry, SameSeedSameTrajectory) {
  const auto seq = test::synthetic_sequence(6, 0.4, 1.0, 5, 6000);
  Odometry a, b;
  SgdSettings two_threads;
  two_threads.num_threads = 2;  // the queries and the map's surfaces in two halves
  Odometry c({}, "sgd", two_threads);
  for (const auto& f : seq.frames) {
    const Eigen::Matrix4d T = a.register_frame(f);
    EXPECT_TRUE(T == b.register_frame(f));
    EXPECT_TRUE(T == c.register_frame(f)) << "the same for any thread count";
  }
  ASSERT_NE(a.map(), nullptr);
  ASSERT_NE(c.map(), nullptr);
  EXPECT_EQ(a.map()->points().points, c.map()->points().points);
  EXPECT_EQ(a.map()->points().covariances, c.map()->points().covariances);
}

}  // namespace
}  // namespace sgdicp
