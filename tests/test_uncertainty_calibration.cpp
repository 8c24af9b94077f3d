// laplace's calibration against Monte-Carlo errors (uncertainty.hpp, docs/uncertainty.md,
// *Calibration*): problems cut from one scene into random halves with known noise and motions,
// the predicted variance of each block against the errors' second moment, and the mean NEES.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numeric>
#include <random>
#include <vector>

#include "sgdicp/io/io.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/registration/settings.hpp"
#include "sgdicp/uncertainty/uncertainty.hpp"
#include "test_support.hpp"

namespace {

using namespace sgdicp;
using sgdicp::test::box_surface;
using sgdicp::test::make_transform;
using sgdicp::test::uniform;

// laplace against the Monte-Carlo errors of `trials` problems cut from `scene`: each trial splits
// it into two random halves with `noise_m` of Gaussian noise per coordinate, moves the source by
// a random motion (up to `max_translation_m` per axis, `max_angle_rad` per angle), registers it
// with the defaults as a user would (the reference thinned as reference_index_for does) and
// keeps the error and the covariance; also the independent-residual Laplace's (temper false).
struct Calibration {
  double ratio_t = 0.0, ratio_r = 0.0;              // laplace's variance / errors' second moment
  double naive_ratio_t = 0.0, naive_ratio_r = 0.0;  // the same, temper = false
  double nees = 0.0;                                // laplace's mean NEES
};

Calibration calibrate(const PointCloud& scene, int trials, double noise_m, double max_translation_m,
                      double max_angle_rad, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<PoseVector> errors;
  std::vector<PoseMatrix> laplace, naive;
  for (int trial = 0; trial < trials; ++trial) {
    std::vector<std::size_t> order(scene.size());
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), rng);
    const double a = max_angle_rad, t = max_translation_m;
    const Eigen::Matrix4d T =
        make_transform(uniform(rng, -a, a), uniform(rng, -a, a), uniform(rng, -a, a),
                       {uniform(rng, -t, t), uniform(rng, -t, t), uniform(rng, -t, t)});
    std::normal_distribution<double> noise(0.0, noise_m);
    PointCloud reference, source;
    const Eigen::Matrix4d T_inv = T.inverse();
    for (std::size_t i = 0; i < order.size(); ++i) {
      const Eigen::Vector3d p = scene.points[order[i]].cast<double>();
      const Eigen::Vector3d n(noise(rng), noise(rng), noise(rng));
      if (i % 2 == 0) {
        reference.points.push_back((p + n).cast<float>());
      } else {
        source.points.push_back(((T_inv * p.homogeneous()).head<3>() + n).cast<float>());
      }
    }
    SgdSettings s;
    s.sampling.seed = static_cast<std::uint64_t>(trial);
    s.uncertainty.method = UncertaintyType::laplace;
    const ReferenceIndex index = reference_index_for(reference, s);
    const RegistrationResult r = align(source, index, s);
    s.uncertainty.temper = false;
    const RegistrationResult n = align(source, index, s);
    EXPECT_TRUE(r.converged) << r.message;
    PoseVector e = pose_from_transform(r.T_reference_source) - pose_from_transform(T);
    for (int k = 3; k < 6; ++k) e[k] = wrap_angle(e[k]);
    errors.push_back(e);
    laplace.push_back(r.covariance);
    naive.push_back(n.covariance);
  }
  PoseMatrix second = PoseMatrix::Zero();
  for (const PoseVector& e : errors) second += e * e.transpose() / static_cast<double>(trials);
  const auto ratio = [&](const std::vector<PoseMatrix>& covs, int block) {
    PoseMatrix mean = PoseMatrix::Zero();
    for (const PoseMatrix& c : covs) mean += c / static_cast<double>(covs.size());
    return mean.block<3, 3>(3 * block, 3 * block).trace() /
           second.block<3, 3>(3 * block, 3 * block).trace();
  };
  Calibration c{ratio(laplace, 0), ratio(laplace, 1), ratio(naive, 0), ratio(naive, 1), 0.0};
  for (std::size_t k = 0; k < errors.size(); ++k) {
    c.nees += errors[k].dot(laplace[k].ldlt().solve(errors[k])) / static_cast<double>(trials);
  }
  std::cout << "variance ratio t " << c.ratio_t << " r " << c.ratio_r << ", NEES " << c.nees
            << "; independent residuals " << c.naive_ratio_t << " / " << c.naive_ratio_r << "\n";
  return c;
}

// A dense scene as noisy as a third of its grid's voxel (the inside of a 2 x 3 x 1.4 m box, 120k
// points, 1 cm noise), split into two random halves that are thinned on the default grid: the
// nearest neighbours change as the pose moves and the voxels cut the noise's thickness, so the
// error of the optimum is several times what independent residuals with pairs held fixed say.
// Over 16 problems (random halves, noise, motions up to 5 cm / 2 deg), laplace's predicted
// variance of each block is within [0.5, 2] of the errors' second moment and its mean NEES in
// [3, 12] (the targets, with room for 16 trials); the independent-residual Laplace
// (temper = false, what the peers report) is below 0.4 on both blocks.
TEST(Laplace, CalibratedOnADenseNoisySceneThinnedOnTheGrid) {
  PointCloud scene = box_surface(120000, 30);
  for (auto& p : scene.points) p = 2.0F * p;
  const Calibration c = calibrate(scene, 16, 0.01, 0.05, 0.03, 31);
  for (const double ratio : {c.ratio_t, c.ratio_r}) {
    EXPECT_GT(ratio, 0.5);
    EXPECT_LT(ratio, 2.0);
  }
  EXPECT_LT(c.naive_ratio_t, 0.4);
  EXPECT_LT(c.naive_ratio_r, 0.4);
  EXPECT_GT(c.nees, 3.0);
  EXPECT_LT(c.nees, 12.0);
}

#ifdef SGDICP_SHARED_DATA
// The outdoor laser car, a sparse scan (25k points, used as given: no grid), at 1 cm: its secant
// measures the softening of re-pairing from few pairing jumps, its six eigenvalues scattered
// from 0.02 to 0.7, and per direction laplace's variance came out 4-6x the errors' (mean NEES
// 9.6, the error often along a direction measured stiff). One softening for every direction
// (softened_curvature) keeps it within [0.5, 3] and the NEES in [3, 12] over 16 problems.
TEST(Laplace, OneSofteningForEveryDirectionOnASparseLaserScan) {
  const auto file = test::shared_data("libpointmatcher_car/car_cloud400.csv");
  SKIP_WITHOUT(file);
  const PointCloud scene = read_point_cloud(file.string()).cloud;
  const Calibration c = calibrate(scene, 16, 0.01, 0.1, 2.0 * test::kDeg, 7);
  for (const double ratio : {c.ratio_t, c.ratio_r}) {
    EXPECT_GT(ratio, 0.5);
    EXPECT_LT(ratio, 3.0);
  }
  EXPECT_GT(c.nees, 3.0);
  EXPECT_LT(c.nees, 12.0);
}
#endif

}  // namespace
