// Registration against ground truth: synthetic clouds, the real pairs of shared/data, seeds,
// threads, and every way the input can be bad.
#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"
#include "sgdicp/metrics/metrics.hpp"
#include "sgdicp/registration/evaluation.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/tools/pairs.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

using test::kDeg;
using test::make_transform;
using test::synthetic_scene;

// ---------------------------------------------------------------------------------------------
// Synthetic: the reference is an independent sampling of the same scene moved by T_gt, so T_gt
// is exact but no point has an exact twin: with samples ~4 cm apart, nearest-neighbour
// distances are ~2 cm (the inlier RMSE bound) and the point-to-point optimum is biased by a few
// mm; 1 cm and 0.3 deg leave room for that and fail any wrong basin.

struct SyntheticCase {
  const char* name;
  double roll, pitch, yaw;
  Eigen::Vector3d t;
};

class SyntheticRecovery : public ::testing::TestWithParam<SyntheticCase> {};

TEST_P(SyntheticRecovery, DefaultSettingsRecoverTheTransform) {
  const auto& c = GetParam();
  const Eigen::Matrix4d T_gt = make_transform(c.roll, c.pitch, c.yaw, c.t);
  const PointCloud source = synthetic_scene(1);
  const PointCloud reference = transformed(synthetic_scene(2), T_gt);
  const RegistrationResult r = align(source, reference);
  EXPECT_TRUE(r.converged) << r.message;
  EXPECT_LT(translation_error(r.T_reference_source, T_gt), 0.01);
  EXPECT_LT(rotation_error_geodesic(r.T_reference_source, T_gt), 0.3 * kDeg);
  EXPECT_GT(r.inlier_ratio, 0.9);
  EXPECT_LT(r.inlier_rmse_m, 0.03);
}

INSTANTIATE_TEST_SUITE_P(
    Transforms, SyntheticRecovery,
    ::testing::Values(SyntheticCase{"identity", 0, 0, 0, {0, 0, 0}},
                      SyntheticCase{"translation", 0, 0, 0, {0.3, -0.2, 0.1}},
                      SyntheticCase{"yaw20", 0, 0, 20 * kDeg, {0.1, 0.2, 0}},
                      SyntheticCase{"mixed", 5 * kDeg, -8 * kDeg, 15 * kDeg, {-0.25, 0.1, 0.05}}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(Synthetic, PaperPresetsRecoverAModerateTransform) {
  const Eigen::Matrix4d T_gt = make_transform(2 * kDeg, -3 * kDeg, 10 * kDeg, {0.2, -0.1, 0.05});
  const PointCloud source = synthetic_scene(3);
  const PointCloud reference = transformed(synthetic_scene(4), T_gt);
  for (const auto type : {OptimizerType::sgd, OptimizerType::adam}) {
    const RegistrationResult r = align(source, reference, SgdSettings::paper(type));
    SCOPED_TRACE(std::string(to_string(type)));
    // The paper's single phase keeps d_max = 0.5 scaled (no outliers here) and returns the last
    // noisy iterate: a cm and a degree are what it reaches on 20k points.
    EXPECT_LT(translation_error(r.T_reference_source, T_gt), 0.03);
    EXPECT_LT(rotation_error_geodesic(r.T_reference_source, T_gt), 1.0 * kDeg);
  }
}

TEST(Synthetic, EveryOptimizerRecoversTheTransform) {
  const Eigen::Matrix4d T_gt = make_transform(0, 0, 8 * kDeg, {0.15, 0.1, 0});
  const PointCloud source = synthetic_scene(5);
  const PointCloud reference = transformed(synthetic_scene(6), T_gt);
  for (const auto& [type, lr] :
       std::vector<std::pair<OptimizerType, double>>{{OptimizerType::sgd, 2.0},
                                                     {OptimizerType::momentum, 0.2},
                                                     {OptimizerType::rmsprop, 0.01},
                                                     {OptimizerType::adam, 0.01},
                                                     {OptimizerType::gauss_newton, 1.0}}) {
    SgdSettings s;
    s.optimizer.type = type;
    s.optimizer.learning_rate = lr;
    s.max_iterations = 20000;
    const RegistrationResult r = align(source, reference, s);
    SCOPED_TRACE(std::string(to_string(type)));
    EXPECT_LT(translation_error(r.T_reference_source, T_gt), 0.02);
    EXPECT_LT(rotation_error_geodesic(r.T_reference_source, T_gt), 0.5 * kDeg);
  }
}

TEST(Synthetic, InitialGuessIsUsed) {
  // 60 degrees of yaw, started from a guess 5 degrees and 7 cm away.
  const Eigen::Matrix4d T_gt = make_transform(0, 0, 60 * kDeg, {0.5, 0.3, 0});
  const PointCloud source = synthetic_scene(7);
  const PointCloud reference = transformed(synthetic_scene(8), T_gt);
  const Eigen::Matrix4d guess = make_transform(0, 0, 55 * kDeg, {0.45, 0.35, 0});
  const RegistrationResult r = align(source, reference, SgdSettings{}, guess);
  EXPECT_LT(translation_error(r.T_reference_source, T_gt), 0.01);
  EXPECT_LT(rotation_error_geodesic(r.T_reference_source, T_gt), 0.3 * kDeg);
}

TEST(Synthetic, SameSeedSameBitsOtherSeedOtherPath) {
  const Eigen::Matrix4d T_gt = make_transform(0, 0, 10 * kDeg, {0.1, 0.1, 0});
  const PointCloud source = synthetic_scene(9);
  const PointCloud reference = transformed(synthetic_scene(10), T_gt);
  SgdSettings s;
  s.record_trace = true;
  const RegistrationResult a = align(source, reference, s);
  const RegistrationResult b = align(source, reference, s);
  EXPECT_EQ(a.T_reference_source, b.T_reference_source);  // bitwise
  EXPECT_EQ(a.iterations, b.iterations);
  ASSERT_EQ(a.trace.size(), b.trace.size());
  s.sampling.seed += 1;
  const RegistrationResult c = align(source, reference, s);
  EXPECT_NE(a.T_reference_source, c.T_reference_source);
  EXPECT_LT(translation_error(c.T_reference_source, T_gt), 0.01);
}

TEST(Synthetic, TraceDescribesEveryIteration) {
  const PointCloud source = synthetic_scene(11);
  const PointCloud reference =
      transformed(synthetic_scene(12), make_transform(0, 0, 0.1, {0.1, 0, 0}));
  SgdSettings s;
  s.record_trace = true;
  const RegistrationResult r = align(source, reference, s);
  ASSERT_EQ(r.trace.size(), r.iterations);
  for (std::size_t i = 0; i < r.trace.size(); ++i) {
    EXPECT_EQ(r.trace[i].iteration, i + 1);
    EXPECT_EQ(r.trace[i].points_processed, (i + 1) * s.sampling.batch_size);
    EXPECT_LE(r.trace[i].inliers, s.sampling.batch_size);
    EXPECT_GT(r.trace[i].step_size, 0.0);
    if (i > 0 && r.trace[i].inliers > 0) {
      // d_max grows back only after a mini-batch without any pair.
      EXPECT_LE(r.trace[i].max_distance_m, r.trace[i - 1].max_distance_m);
    }
  }
  EXPECT_EQ(r.points_processed, r.iterations * s.sampling.batch_size);
}

TEST(Synthetic, ResultIsTheMeanOfTheFinalStationaryWindow) {
  const PointCloud source = synthetic_scene(13);
  const PointCloud reference =
      transformed(synthetic_scene(14), make_transform(0.02, -0.03, 0.1, {0.1, -0.05, 0.02}));
  SgdSettings s;
  s.record_trace = true;
  const RegistrationResult averaged = align(source, reference, s);
  ASSERT_TRUE(averaged.converged) << averaged.message;
  // Stages end only at window boundaries and the run stops at the final stage's stationary
  // window, without a further window of iterations.
  const std::size_t w = s.convergence.window;
  EXPECT_EQ(averaged.iterations % w, 0U);
  // Every stage, or a refinement stage whose pairs had settled (settle_tolerance). A stage ends
  // with a stationary window and the next one starts with a new d_max, so the trace shows each
  // stage but the last as a change of d_max at a window boundary (d_max widens only for lost
  // pairs, which this scene does not lose).
  EXPECT_GE(averaged.stages, 2U);
  EXPECT_LE(averaged.stages, s.refinement.stages + 1);
  std::size_t stage_ends = 0;
  for (std::size_t i = 1; i < averaged.trace.size(); ++i) {
    if (averaged.trace[i].max_distance_m == averaged.trace[i - 1].max_distance_m) continue;
    EXPECT_EQ(i % w, 0U) << "d_max changed within a window, at iteration " << i;
    ++stage_ends;
  }
  EXPECT_EQ(averaged.stages, stage_ends + 1);
  // Without settling every stage runs.
  SgdSettings every_stage = s;
  every_stage.refinement.settle_tolerance = 0.0;
  EXPECT_EQ(align(source, reference, every_stage).stages, s.refinement.stages + 1);
  // The result is the mean of that window's iterates (means of the Euler poses, so compare with
  // the mean of the metric translations to within the iterates' jitter), not the last iterate.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i = averaged.trace.size() - w; i < averaged.trace.size(); ++i) {
    mean += averaged.trace[i].T_reference_source.block<3, 1>(0, 3) / static_cast<double>(w);
  }
  const Eigen::Vector3d result = averaged.T_reference_source.block<3, 1>(0, 3);
  const Eigen::Vector3d last = averaged.trace.back().T_reference_source.block<3, 1>(0, 3);
  EXPECT_LT((result - mean).norm(), 0.1 * (last - mean).norm());

  s.average_iterates = false;
  const RegistrationResult plain = align(source, reference, s);
  EXPECT_EQ(plain.iterations, averaged.iterations);  // same seed, same path
  EXPECT_TRUE(plain.T_reference_source.isApprox(plain.trace.back().T_reference_source, 1e-12));
}

// ---------------------------------------------------------------------------------------------
// Status reporting and bad input.

TEST(Status, IterationLimitIsReportedAsNotConverged) {
  const PointCloud source = synthetic_scene(13);
  const PointCloud reference =
      transformed(synthetic_scene(14), make_transform(0, 0, 0.3, {0.3, 0, 0}));
  SgdSettings s;
  s.max_iterations = 5;
  const RegistrationResult r = align(source, reference, s);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.stop_reason, StopReason::max_iterations);
  EXPECT_EQ(r.iterations, 5U);
  EXPECT_NE(r.message.find("limit"), std::string::npos);
}

TEST(Status, NoCorrespondencesIsReported) {
  const PointCloud source = synthetic_scene(15);
  // The reference is 100 m away and d_max is 0.1 m: no pair can ever be found.
  const PointCloud reference =
      transformed(synthetic_scene(16), make_transform(0, 0, 0, {100, 0, 0}));
  SgdSettings s;
  s.pairing.max_correspondence_distance = Distance::metres(0.1);
  const RegistrationResult r = align(source, reference, s);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.stop_reason, StopReason::no_correspondences);
  EXPECT_EQ(r.inliers, 0U);
  EXPECT_NE(r.message.find("d_max"), std::string::npos);
}

TEST(Status, ExactCopyMinusOnePointConverges) {
  // The refined d_max follows the median pair distance, 0 on an exact copy, while Adam still
  // steps ~alpha: it must widen again instead of stopping with no correspondences.
  const PointCloud cloud = synthetic_scene(23, 2000);
  PointCloud copy = cloud;
  copy.points.pop_back();
  SgdSettings s;
  s.sampling.batch_size = 50;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    s.sampling.seed = seed;
    const RegistrationResult r = align(cloud, copy, s);
    EXPECT_TRUE(r.converged) << "seed " << seed << ": " << r.message;
    EXPECT_LT(translation_error(r.T_reference_source, Eigen::Matrix4d::Identity()), 0.01);
  }
}

TEST(Status, DivergenceIsReported) {
  const PointCloud source = synthetic_scene(17);
  const PointCloud reference =
      transformed(synthetic_scene(18), make_transform(0, 0, 0.2, {0.2, 0, 0}));
  SgdSettings s = SgdSettings::paper(OptimizerType::sgd);
  s.optimizer.learning_rate = 1e4;  // absurd but valid: the pose must blow up, and say so
  const RegistrationResult r = align(source, reference, s);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.stop_reason, StopReason::diverged);
}

TEST(BadInput, EmptyTooSmallAndNonFiniteCloudsThrow) {
  const PointCloud good = synthetic_scene(19, 2000);
  EXPECT_THROW((void)align(PointCloud{}, good), InvalidInputError);
  EXPECT_THROW((void)align(good, PointCloud{}), InvalidInputError);
  PointCloud small;
  small.points.assign(20, Eigen::Vector3f(1, 2, 3));
  try {
    (void)align(small, good);
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("fewer than the smallest mini-batch 32"),
              std::string::npos)
        << e.what();
  }
  small.points.assign(100, Eigen::Vector3f(1, 2, 3));
  try {
    (void)align(small, good, SgdSettings::paper());
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("fewer than the mini-batch size 160"), std::string::npos)
        << e.what();
  }
  PointCloud nan_source = good;
  nan_source.points[5].x() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW((void)align(nan_source, good), InvalidInputError);
  PointCloud inf_reference = good;
  inf_reference.points[7].z() = std::numeric_limits<float>::infinity();
  EXPECT_THROW((void)align(good, inf_reference), InvalidInputError);
  PointCloud single_point;
  single_point.points.assign(500, Eigen::Vector3f(1, 1, 1));
  EXPECT_THROW((void)align(single_point, single_point), InvalidInputError);  // zero extent
}

TEST(BadInput, BadInitialTransformsThrow) {
  const PointCloud cloud = synthetic_scene(20, 2000);
  Eigen::Matrix4d scaled = Eigen::Matrix4d::Identity() * 2.0;
  scaled(3, 3) = 1.0;
  EXPECT_THROW((void)align(cloud, cloud, SgdSettings{}, scaled), InvalidInputError);
  Eigen::Matrix4d reflection = Eigen::Matrix4d::Identity();
  reflection(0, 0) = -1.0;
  EXPECT_THROW((void)align(cloud, cloud, SgdSettings{}, reflection), InvalidInputError);
  Eigen::Matrix4d nan = Eigen::Matrix4d::Identity();
  nan(0, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)align(cloud, cloud, SgdSettings{}, nan), InvalidInputError);
}

TEST(BadInput, AbsurdSettingsThrow) {
  const PointCloud cloud = synthetic_scene(21, 2000);
  const auto expect_invalid = [&](auto mutate) {
    SgdSettings s;
    mutate(s);
    EXPECT_THROW((void)align(cloud, cloud, s), InvalidSettingsError);
  };
  expect_invalid([](SgdSettings& s) { s.sampling.batch_size = 0; });
  expect_invalid([](SgdSettings& s) { s.optimizer.learning_rate = -1.0; });
  expect_invalid([](SgdSettings& s) { s.optimizer.learning_rate = std::nan(""); });
  expect_invalid(
      [](SgdSettings& s) { s.pairing.max_correspondence_distance = Distance::metres(0.0); });
  expect_invalid(
      [](SgdSettings& s) { s.pairing.max_correspondence_distance = Distance::scaled(INFINITY); });
  expect_invalid([](SgdSettings& s) { s.optimizer.damping = -1.0; });
  // The fixed rules outside the table are range-checked too.
  expect_invalid([](SgdSettings& s) { s.refinement.settle_tolerance = 1.0; });
  expect_invalid([](SgdSettings& s) { s.convergence.max_path_efficiency = 0.0; });
  expect_invalid([](SgdSettings& s) { s.uncertainty.block_size = Distance::scaled(0.0); });
  expect_invalid([](SgdSettings& s) { s.convergence.window = 3; });
  expect_invalid([](SgdSettings& s) { s.convergence.chi2 = 0.0; });
  expect_invalid([](SgdSettings& s) { s.refinement.step_decay = 0.0; });
  expect_invalid([](SgdSettings& s) { s.refinement.distance_factor = -2.0; });
  expect_invalid([](SgdSettings& s) { s.max_iterations = 0; });
}

// ---------------------------------------------------------------------------------------------
// One reference index, many registrations, several threads: the answers must be exactly those
// of sequential runs.

TEST(ReferenceReuse, ConcurrentRegistrationsMatchSequentialOnes) {
  const PointCloud reference = synthetic_scene(22);
  const ReferenceIndex index(reference);
  std::vector<PointCloud> sources;
  std::vector<Eigen::Matrix4d> truths;
  for (int i = 0; i < 4; ++i) {
    truths.push_back(make_transform(0, 0, 0.05 * i, {0.05 * i, -0.03 * i, 0}));
    sources.push_back(transformed(synthetic_scene(100 + i), truths.back().inverse()));
  }
  std::vector<RegistrationResult> sequential;
  for (const auto& s : sources) sequential.push_back(align(s, index));
  std::vector<RegistrationResult> parallel(sources.size());
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < sources.size(); ++i) {
    threads.emplace_back([&, i] { parallel[i] = align(sources[i], index); });
  }
  for (auto& t : threads) t.join();
  for (std::size_t i = 0; i < sources.size(); ++i) {
    EXPECT_EQ(parallel[i].T_reference_source, sequential[i].T_reference_source);
    EXPECT_LT(translation_error(parallel[i].T_reference_source, truths[i]), 0.01);
  }
}

// ---------------------------------------------------------------------------------------------
// Real data (shared/data). Tolerances are set from each dataset's ground-truth quality.

struct PairRun {
  double t_err, r_err_deg;
  RegistrationResult result;
};

// A pairs-file entry with its two clouds read.
struct LoadedPair {
  RegistrationPair pair;
  PointCloud source;
  PointCloud reference;
};

LoadedPair load_pair(const RegistrationPair& pair) {
  return {pair, read_point_cloud(pair.source).cloud, read_point_cloud(pair.reference).cloud};
}

PairRun run_pair(const RegistrationPair& pair, const SgdSettings& s) {
  const LoadedPair loaded = load_pair(pair);
  const RegistrationResult r = align(loaded.source, loaded.reference, s);
  return {translation_error(r.T_reference_source, pair.T_reference_source_gt),
          rotation_error_geodesic(r.T_reference_source, pair.T_reference_source_gt) / kDeg, r};
}

TEST(RealData, KittiMovedCopiesTableII) {
  // The paper's Table II protocol: a scan vs. a copy moved by up to 30 m / 30 deg. The ground
  // truth is exact and every point has its twin, so at full resolution only float storage
  // limits the answer (1e-7 relative on 80 m ranges = 0.01 mm); 5 mm / 0.01 deg leaves room and
  // still fails any wrong basin by three orders of magnitude. On the default voxel grid (~0.3 m)
  // the twins fall into differently placed voxels and their centroids differ by up to a voxel:
  // 2 cm / 0.03 deg there, still far from any wrong basin.
  const auto file = test::shared_data("pairs/kitti_seq00_moved_copies.txt");
  SKIP_WITHOUT(file);
  for (const auto& pair : read_pairs_file(file)) {
    SCOPED_TRACE(pair.reference.filename().string());
    const PairRun def = run_pair(pair, SgdSettings{});
    EXPECT_TRUE(def.result.converged);
    EXPECT_GT(def.result.voxel_size_m, 0.0);
    EXPECT_LT(def.t_err, 0.02);
    EXPECT_LT(def.r_err_deg, 0.03);
    // Every point, with the paper's cost (point-to-plane at full resolution lost one copy, 17 m
    // off: its basin is narrower there than on the voxel grid).
    SgdSettings full;
    full.downsampling.downsample_to = 0;
    full.cost = CostType::point_to_point;
    const PairRun every_point = run_pair(pair, full);
    EXPECT_TRUE(every_point.result.converged);
    EXPECT_EQ(every_point.result.voxel_size_m, 0.0);
    EXPECT_LT(every_point.t_err, 0.005);
    EXPECT_LT(every_point.r_err_deg, 0.01);
    const PairRun paper = run_pair(pair, SgdSettings::paper(OptimizerType::sgd));
    EXPECT_LT(paper.t_err, 0.005);
    EXPECT_LT(paper.r_err_deg, 0.01);
  }
}

TEST(RealData, LibpointmatcherCarPair) {
  // libpointmatcher's ground truth agrees with its own regression ICP to 7.8 mm / 0.08 deg, and
  // point-to-point ICP started at the ground truth drifts 1.8 cm / 0.08 deg (PROVENANCE.md): the
  // point-to-point optimum itself is a couple of cm and a few tenths of a degree away.
  const auto file = test::shared_data("pairs/libpointmatcher_car.txt");
  SKIP_WITHOUT(file);
  for (const auto& pair : read_pairs_file(file)) {
    SCOPED_TRACE(pair.source.filename().string());
    const PairRun run = run_pair(pair, SgdSettings{});
    EXPECT_TRUE(run.result.converged);
    EXPECT_LT(run.t_err, 0.05);
    EXPECT_LT(run.r_err_deg, 0.5);
  }
}

TEST(RealData, BunnyPair) {
  // Sub-mm ground truth, but 361 sparse points: PROVENANCE.md notes plain point-to-point ICP from
  // identity stops 3.9 deg short of it. We require 2 mm and better than that 3.9 deg.
  const auto file = test::shared_data("pairs/pcl_bunny.txt");
  SKIP_WITHOUT(file);
  const PairRun run = run_pair(read_pairs_file(file).front(), SgdSettings{});
  EXPECT_TRUE(run.result.converged);
  EXPECT_LT(run.t_err, 0.002);
  EXPECT_LT(run.r_err_deg, 3.9);
}

// Issue 13's rotation bar on the bunny: small_gicp's GICP on its voxels ends 0.242 deg off. With
// flat neighbourhoods of 10 the default's median over seeds is 0.18 deg (k = 20 everywhere:
// 0.34 deg, 5 seeds).
TEST(RealData, BunnyRotationMedianOverSeedsBeatsGicp) {
  const auto file = test::shared_data("pairs/pcl_bunny.txt");
  SKIP_WITHOUT(file);
  const auto [pair, source, reference] = load_pair(read_pairs_file(file).front());
  std::vector<double> errors_deg;
  for (std::uint64_t seed = 1; seed <= 9; ++seed) {
    SgdSettings s;
    s.sampling.seed = seed;
    const RegistrationResult r = align(source, reference, s);
    EXPECT_TRUE(r.converged) << r.message;
    errors_deg.push_back(rotation_error_geodesic(r.T_reference_source, pair.T_reference_source_gt) /
                         kDeg);
  }
  std::nth_element(errors_deg.begin(), errors_deg.begin() + 4, errors_deg.end());
  EXPECT_LT(errors_deg[4], 0.242);
}

// Nearly aligned dense frames: the third refinement stage's d_max is within 2 % of the
// second's, so the run ends there (RefinementSettings::settle_tolerance): a window of 20
// mini-batches fewer, as precise (rotation 0.191 -> 0.186 deg over 3 seeds).
TEST(RealData, KinectFramesEndWhenTheirPairsHaveSettled) {
  const auto file = test::shared_data("pairs/pcl_kinect_frames.txt");
  SKIP_WITHOUT(file);
  const auto [pair, source, reference] = load_pair(read_pairs_file(file).front());
  SgdSettings every_stage;
  every_stage.refinement.settle_tolerance = 0.0;
  const RegistrationResult settled = align(source, reference, SgdSettings{});
  const RegistrationResult full = align(source, reference, every_stage);
  EXPECT_TRUE(settled.converged) << settled.message;
  EXPECT_EQ(full.stages, 4U);
  EXPECT_LT(settled.stages, full.stages);
  EXPECT_LT(settled.iterations, full.iterations);
  for (const RegistrationResult* r : {&settled, &full}) {
    EXPECT_LT(translation_error(r->T_reference_source, pair.T_reference_source_gt), 0.01);
    EXPECT_LT(rotation_error_geodesic(r->T_reference_source, pair.T_reference_source_gt),
              0.3 * kDeg);
  }
}

TEST(RealData, KittiConsecutiveScans) {
  // Pseudo ground truth good to 2-9 cm (PROVENANCE.md); batch point-to-point ICP gets 0.5-3 cm.
  const auto file = test::shared_data("pairs/kitti_seq00.txt");
  SKIP_WITHOUT(file);
  const auto pairs = read_pairs_file(file);
  const PairRun run = run_pair(pairs.front(), SgdSettings{});
  EXPECT_TRUE(run.result.converged);
  EXPECT_LT(run.t_err, 0.05);
  EXPECT_LT(run.r_err_deg, 0.2);
}

// A small source caps the mini-batch at 2 x points / window (at least 32): the window still sees
// every point about twice, and the run finds the same pose with a quarter of the pairs.
TEST(SmallSource, CapsTheMiniBatch) {
  SgdSettings s;
  EXPECT_EQ(batch_size_for(s, 361), 37u);  // ceil(2 * 361 / 20)
  EXPECT_EQ(batch_size_for(s, 100), kMinCappedBatch);
  EXPECT_EQ(batch_size_for(s, 1600), 160u);
  EXPECT_EQ(batch_size_for(s, 100000), 160u);
  EXPECT_EQ(batch_size_for(SgdSettings::paper(), 361), 160u);
  EXPECT_EQ(min_source_points(s), kMinCappedBatch);
  EXPECT_EQ(min_source_points(SgdSettings::paper()), 160u);
  SgdSettings small_m;  // a batch below kMinCappedBatch is never raised by the cap
  small_m.sampling.batch_size = 16;
  EXPECT_EQ(batch_size_for(small_m, 100), 16u);

  const Eigen::Matrix4d T_gt = make_transform(3 * kDeg, -2 * kDeg, 10 * kDeg, {0.1, -0.05, 0.05});
  const PointCloud reference = synthetic_scene(51, 4000);
  const PointCloud source = transformed(synthetic_scene(52, 400), T_gt.inverse());
  SgdSettings uncapped;
  uncapped.adapt_small_sources = false;
  const RegistrationResult capped = align(source, reference, s);
  const RegistrationResult full = align(source, reference, uncapped);
  EXPECT_EQ(capped.points_processed, capped.iterations * 40);
  EXPECT_EQ(full.points_processed, full.iterations * 160);
  EXPECT_TRUE(capped.converged) << capped.message;
  EXPECT_LT(translation_error(capped.T_reference_source, T_gt), 0.02);
  EXPECT_LT(rotation_error_geodesic(capped.T_reference_source, T_gt), 1.0 * kDeg);
  EXPECT_LT(capped.points_processed, full.points_processed / 2);
}

// A small source is drawn many times, and the run's nearest-point memory answers most of the final
// statistics' queries: the same values as the tree's, to the bit.
TEST(SmallSource, FinalStatisticsFromTheRunsMemoryAreTheTrees) {
  const Eigen::Matrix4d T_gt = make_transform(3 * kDeg, -2 * kDeg, 10 * kDeg, {0.1, -0.05, 0.05});
  const PointCloud reference = synthetic_scene(51, 4000);
  const PointCloud source = transformed(synthetic_scene(52, 400), T_gt.inverse());
  const SgdSettings s;
  const ReferenceIndex index = reference_index_for(reference, s);
  const RegistrationResult r = align(source, index, s);
  ASSERT_TRUE(r.converged) << r.message;
  ASSERT_EQ(r.voxel_size_m, 0.0);  // the source as given: its point i is the run's
  ASSERT_GT(r.points_processed, 3 * source.size());  // drawn often enough for the memory
  RegistrationResult tree;
  tree.T_reference_source = r.T_reference_source;
  evaluate_alignment(source, index, r.final_max_distance_m, s.evaluation, 1, tree);
  EXPECT_EQ(r.evaluated_points, tree.evaluated_points);
  EXPECT_EQ(r.inliers, tree.inliers);
  EXPECT_EQ(r.inlier_rmse_m, tree.inlier_rmse_m);
}

// Small sources take Gauss-Newton steps in the coarse stage while the optimizer is the default;
// large sources, an optimizer set by the user and paper() keep theirs.
TEST(SmallSource, TakesGaussNewtonStepsWithTheDefaultOptimizer) {
  const SgdSettings s;
  EXPECT_TRUE(is_small_source(s, 1599));
  EXPECT_FALSE(is_small_source(s, 1600));
  EXPECT_EQ(optimizer_for(s, 361).type, OptimizerType::gauss_newton);
  EXPECT_EQ(optimizer_for(s, 361).learning_rate,
            default_learning_rate(OptimizerType::gauss_newton));
  EXPECT_EQ(optimizer_for(s, 1600), s.optimizer);
  EXPECT_EQ(optimizer_for(SgdSettings::paper(OptimizerType::adam), 361).type, OptimizerType::adam);
  SgdSettings chosen;
  chosen.optimizer.learning_rate = 0.02;
  EXPECT_EQ(optimizer_for(chosen, 361), chosen.optimizer);
  SgdSettings off;
  off.adapt_small_sources = false;
  EXPECT_EQ(optimizer_for(off, 361), off.optimizer);
  // The Gauss-Newton steps' damping chosen: those steps.
  SgdSettings damped;
  damped.optimizer.damping = 0.01;
  EXPECT_EQ(optimizer_for(damped, 361).type, OptimizerType::gauss_newton);
  EXPECT_EQ(optimizer_for(damped, 361).damping, 0.01);
}

// The real bunny (361 source points), its 34 deg start turned a further 25 deg about three
// axes: Gauss-Newton coarse steps solve every start with fewer mini-batches than Adam and at
// least its rotation accuracy (measured: 120 against 180-330 iterations, 0.25-0.27 deg against
// 0.35-0.42 deg over 20 random 30-60 deg starts; docs/design.md, *Small sources*).
TEST(SmallSource, GaussNewtonSolvesTheBunnyFasterThanAdam) {
  const auto file = test::shared_data("pairs/pcl_bunny.txt");
  SKIP_WITHOUT(file);
  const auto [pair, source, reference] = load_pair(read_pairs_file(file).front());
  // The two step rules compared over every stage (no early end once the pairs settle, which
  // would compare where each rule happened to stop); the default is checked as it runs.
  SgdSettings newton;
  newton.refinement.settle_tolerance = 0.0;
  SgdSettings adam = newton;
  adam.adapt_small_sources = false;
  const std::vector<Eigen::Vector3d> axes = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                             Eigen::Vector3d(1, 1, 1).normalized()};
  for (const Eigen::Vector3d& axis : axes) {
    Eigen::Matrix4d turn = Eigen::Matrix4d::Identity();
    turn.topLeftCorner<3, 3>() = Eigen::AngleAxisd(25 * kDeg, axis).toRotationMatrix();
    // T_init = turn^-1 starts the pose 25 deg farther from the truth than the identity would.
    const Eigen::Matrix4d T_init = turn.inverse();
    const RegistrationResult gn = align(source, reference, newton, T_init);
    const RegistrationResult ad = align(source, reference, adam, T_init);
    const RegistrationResult by_default = align(source, reference, SgdSettings{}, T_init);
    const Eigen::Matrix4d& T_gt = pair.T_reference_source_gt;
    EXPECT_TRUE(by_default.converged) << by_default.message;
    EXPECT_LT(translation_error(by_default.T_reference_source, T_gt), 0.002);
    EXPECT_LT(rotation_error_geodesic(by_default.T_reference_source, T_gt), 0.5 * kDeg);
    EXPECT_LE(by_default.iterations, gn.iterations);
    EXPECT_TRUE(gn.converged) << gn.message;
    EXPECT_LT(translation_error(gn.T_reference_source, T_gt), 0.002);
    EXPECT_LT(rotation_error_geodesic(gn.T_reference_source, T_gt), 0.5 * kDeg);
    EXPECT_LT(gn.iterations, ad.iterations);
    EXPECT_LE(rotation_error_geodesic(gn.T_reference_source, T_gt),
              rotation_error_geodesic(ad.T_reference_source, T_gt) + 0.05 * kDeg);
  }
}

// With the whole bunny as every mini-batch (m = N, Gauss-Newton steps) the iterates settle into
// a cycle between pairings that the gradient test alone never ends: the run must still stop
// (it took all 4,000 iterations before the deterministic-batch rule of convergence.hpp; now 200).
TEST(SmallSource, AWholeSourceBatchConvergesDespiteAPairingCycle) {
  const auto file = test::shared_data("pairs/pcl_bunny.txt");
  SKIP_WITHOUT(file);
  const auto [pair, source, reference] = load_pair(read_pairs_file(file).front());
  SgdSettings s;
  s.cost = CostType::point_to_plane;
  s.coarse_cost = CostType::point_to_plane;
  s.optimizer = {OptimizerType::gauss_newton, default_learning_rate(OptimizerType::gauss_newton)};
  s.sampling.batch_size = source.size();
  s.adapt_small_sources = false;
  const RegistrationResult r = align(source, reference, s);
  EXPECT_TRUE(r.converged) << r.message;
  EXPECT_LT(r.iterations, 1000U);
  EXPECT_LT(rotation_error_geodesic(r.T_reference_source, pair.T_reference_source_gt), 0.5 * kDeg);
}

}  // namespace
}  // namespace sgdicp
