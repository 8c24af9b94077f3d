// Tests of the pose model (pose.hpp) against independent computations: Eigen's AngleAxis for the
// rotation, central finite differences for its derivatives.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "sgdicp/core/pose.hpp"
#include "test_support.hpp"

namespace {

using sgdicp::test::random_rigid;
using sgdicp::test::random_rotation;
using sgdicp::test::uniform;

using sgdicp::PoseVector;
constexpr double kPi = std::numbers::pi;

Eigen::Matrix3d eigen_rpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

double max_abs_diff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

TEST(Pose, RotationFromRpyMatchesAngleAxisComposition) {
  std::mt19937_64 rng(101);
  for (int i = 0; i < 1000; ++i) {
    // Angles beyond (-pi, pi] on purpose: the map is defined for any real angles.
    const double roll = uniform(rng, -4.0, 4.0);
    const double pitch = uniform(rng, -4.0, 4.0);
    const double yaw = uniform(rng, -4.0, 4.0);
    const Eigen::Matrix3d r = sgdicp::rotation_from_rpy(roll, pitch, yaw);
    ASSERT_LT(max_abs_diff(r, eigen_rpy(roll, pitch, yaw)), 1e-14)
        << "roll " << roll << " pitch " << pitch << " yaw " << yaw;
    ASSERT_LT(max_abs_diff(r.transpose() * r, Eigen::Matrix3d::Identity()), 1e-14);
    ASSERT_NEAR(r.determinant(), 1.0, 1e-14);
  }
}

TEST(Pose, RotationFromRpyElementaryAxes) {
  // Each angle alone is the elementary rotation about its axis (right-handed).
  const double a = 0.3;
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  // Roll about x moves y towards z.
  EXPECT_LT(max_abs_diff(sgdicp::rotation_from_rpy(a, 0, 0) * y,
                         Eigen::Vector3d(0, std::cos(a), std::sin(a))),
            1e-15);
  // Pitch about y moves z towards x.
  EXPECT_LT(max_abs_diff(sgdicp::rotation_from_rpy(0, a, 0) * Eigen::Vector3d::UnitZ(),
                         Eigen::Vector3d(std::sin(a), 0, std::cos(a))),
            1e-15);
  // Yaw about z moves x towards y.
  EXPECT_LT(max_abs_diff(sgdicp::rotation_from_rpy(0, 0, a) * x,
                         Eigen::Vector3d(std::cos(a), std::sin(a), 0)),
            1e-15);
}

TEST(Pose, RpyRoundTripAwayFromGimbalLock) {
  std::mt19937_64 rng(202);
  const double pitch_limit = kPi / 2 - 1e-3;
  for (int i = 0; i < 2000; ++i) {
    const double roll = uniform(rng, -kPi, kPi);
    const double pitch = uniform(rng, -pitch_limit, pitch_limit);
    const double yaw = uniform(rng, -kPi, kPi);
    const Eigen::Vector3d rpy =
        sgdicp::rpy_from_rotation(sgdicp::rotation_from_rpy(roll, pitch, yaw));
    // Compare modulo 2 pi: roll and yaw near +-pi may come back on the other side.
    ASSERT_NEAR(sgdicp::wrap_angle(rpy[0] - roll), 0.0, 1e-9) << i;
    ASSERT_NEAR(rpy[1], pitch, 1e-9) << i;
    ASSERT_NEAR(sgdicp::wrap_angle(rpy[2] - yaw), 0.0, 1e-9) << i;
    // The returned angles are in the documented ranges.
    ASSERT_LE(std::abs(rpy[0]), kPi);
    ASSERT_LE(std::abs(rpy[1]), kPi / 2);
    ASSERT_LE(std::abs(rpy[2]), kPi);
  }
}

TEST(Pose, RpyFromRandomRotationReproducesIt) {
  std::mt19937_64 rng(303);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Matrix3d r = random_rotation(rng);
    const Eigen::Vector3d rpy = sgdicp::rpy_from_rotation(r);
    ASSERT_LT(max_abs_diff(sgdicp::rotation_from_rpy(rpy[0], rpy[1], rpy[2]), r), 1e-9) << i;
  }
}

TEST(Pose, GimbalLockReproducesRotation) {
  std::mt19937_64 rng(404);
  for (const double pitch : {kPi / 2, -kPi / 2}) {
    for (int i = 0; i < 200; ++i) {
      const double roll = uniform(rng, -kPi, kPi);
      const double yaw = uniform(rng, -kPi, kPi);
      const Eigen::Matrix3d r = sgdicp::rotation_from_rpy(roll, pitch, yaw);
      const Eigen::Vector3d rpy = sgdicp::rpy_from_rotation(r);
      ASSERT_TRUE(rpy.allFinite());
      EXPECT_EQ(rpy[0], 0.0) << "documented: roll is set to 0 at gimbal lock";
      EXPECT_NEAR(rpy[1], pitch, 1e-12);
      ASSERT_LT(max_abs_diff(sgdicp::rotation_from_rpy(rpy[0], rpy[1], rpy[2]), r), 1e-12)
          << "pitch " << pitch << " roll " << roll << " yaw " << yaw;
    }
  }
}

TEST(Pose, NearGimbalLockReproducesRotation) {
  // Close to the lock but outside its special case (|r(2,0)| > 1 - 1e-12, i.e. within about
  // 1.4e-6 rad of the lock), where asin loses digits but atan2 of the scaled terms does not.
  std::mt19937_64 rng(405);
  for (const double offset : {1e-2, 1e-3, 1e-4, 1e-5}) {
    for (const double sign : {1.0, -1.0}) {
      const double pitch = sign * (kPi / 2 - offset);
      const double roll = uniform(rng, -kPi, kPi);
      const double yaw = uniform(rng, -kPi, kPi);
      const Eigen::Matrix3d r = sgdicp::rotation_from_rpy(roll, pitch, yaw);
      const Eigen::Vector3d rpy = sgdicp::rpy_from_rotation(r);
      EXPECT_LT(max_abs_diff(sgdicp::rotation_from_rpy(rpy[0], rpy[1], rpy[2]), r), 1e-10)
          << "pitch " << pitch;
      EXPECT_NEAR(sgdicp::wrap_angle(rpy[0] - roll), 0.0, 1e-9);
      EXPECT_NEAR(sgdicp::wrap_angle(rpy[2] - yaw), 0.0, 1e-9);
    }
  }
}

TEST(Pose, NearTheGimbalLockTheRotationIsReproduced) {
  // rpy_from_rotation takes pitch from atan2(-r20, hypot(r00, r10)) and treats only
  // cos(pitch) < 1e-10 as the lock (roll := 0), so the rotation comes back to ~1e-10 however
  // close to the lock it is.
  std::mt19937_64 rng(406);
  for (const double offset : {1e-6, 1e-7, 1e-9, 1e-12}) {
    for (const double sign : {1.0, -1.0}) {
      for (int i = 0; i < 20; ++i) {
        const double pitch = sign * (kPi / 2 - offset);
        const Eigen::Matrix3d r =
            sgdicp::rotation_from_rpy(uniform(rng, -kPi, kPi), pitch, uniform(rng, -kPi, kPi));
        const Eigen::Vector3d rpy = sgdicp::rpy_from_rotation(r);
        ASSERT_TRUE(rpy.allFinite());
        EXPECT_LT(max_abs_diff(sgdicp::rotation_from_rpy(rpy[0], rpy[1], rpy[2]), r), 1e-9)
            << "pitch " << pitch;
      }
    }
  }
}

TEST(Pose, RotationDerivativesMatchFiniteDifferences) {
  std::mt19937_64 rng(505);
  const double h = 1e-6;
  for (int i = 0; i < 500; ++i) {
    const double angles[3] = {uniform(rng, -kPi, kPi), uniform(rng, -kPi, kPi),
                              uniform(rng, -kPi, kPi)};
    const auto d = sgdicp::rotation_derivatives(angles[0], angles[1], angles[2]);
    for (int k = 0; k < 3; ++k) {
      double plus[3] = {angles[0], angles[1], angles[2]};
      double minus[3] = {angles[0], angles[1], angles[2]};
      plus[k] += h;
      minus[k] -= h;
      const Eigen::Matrix3d fd = (sgdicp::rotation_from_rpy(plus[0], plus[1], plus[2]) -
                                  sgdicp::rotation_from_rpy(minus[0], minus[1], minus[2])) /
                                 (2 * h);
      ASSERT_LT(max_abs_diff(d[static_cast<std::size_t>(k)], fd), 1e-8)
          << "angle " << k << " at (" << angles[0] << ", " << angles[1] << ", " << angles[2] << ")";
    }
  }
}

TEST(Pose, TransformFromPoseAndBack) {
  std::mt19937_64 rng(606);
  for (int i = 0; i < 1000; ++i) {
    PoseVector theta;
    theta << uniform(rng, -100, 100), uniform(rng, -100, 100), uniform(rng, -100, 100),
        uniform(rng, -kPi, kPi), uniform(rng, -(kPi / 2 - 1e-3), kPi / 2 - 1e-3),
        uniform(rng, -kPi, kPi);
    const Eigen::Matrix4d t = sgdicp::transform_from_pose(theta);
    // Independent construction of the same matrix.
    ASSERT_LT(max_abs_diff(t.topLeftCorner<3, 3>(), eigen_rpy(theta[3], theta[4], theta[5])),
              1e-14);
    ASSERT_EQ((t.topRightCorner<3, 1>()), theta.head<3>());
    ASSERT_EQ(t.row(3), Eigen::RowVector4d(0, 0, 0, 1));
    ASSERT_TRUE(sgdicp::is_rigid_transform(t, 1e-12));

    const PoseVector back = sgdicp::pose_from_transform(t);
    ASSERT_EQ(back.head<3>(), theta.head<3>());
    for (int k = 3; k < 6; ++k) ASSERT_NEAR(sgdicp::wrap_angle(back[k] - theta[k]), 0.0, 1e-9);

    // And from any rigid transform to a pose and back.
    const Eigen::Matrix4d m = random_rigid(rng, 50.0);
    ASSERT_LT(max_abs_diff(sgdicp::transform_from_pose(sgdicp::pose_from_transform(m)), m), 1e-9);
  }
}

TEST(Pose, WrapAngleRange) {
  std::mt19937_64 rng(707);
  for (int i = 0; i < 100000; ++i) {
    const double a = uniform(rng, -100.0, 100.0);
    const double w = sgdicp::wrap_angle(a);
    ASSERT_GT(w, -kPi) << a;
    ASSERT_LE(w, kPi) << a;
    // Same angle: the difference is a whole number of turns.
    const double turns = (a - w) / (2 * kPi);
    ASSERT_NEAR(turns, std::round(turns), 1e-12) << a;
  }
  EXPECT_DOUBLE_EQ(sgdicp::wrap_angle(kPi), kPi);
  EXPECT_DOUBLE_EQ(sgdicp::wrap_angle(-kPi), kPi);  // -pi is outside (-pi, pi]
  EXPECT_DOUBLE_EQ(sgdicp::wrap_angle(0.0), 0.0);
  EXPECT_DOUBLE_EQ(sgdicp::wrap_angle(0.5), 0.5);
  EXPECT_DOUBLE_EQ(sgdicp::wrap_angle(-0.5), -0.5);
  EXPECT_NEAR(sgdicp::wrap_angle(2 * kPi + 0.25), 0.25, 1e-15);
  EXPECT_NEAR(sgdicp::wrap_angle(-2 * kPi - 0.25), -0.25, 1e-15);
  EXPECT_NEAR(sgdicp::wrap_angle(3 * kPi / 2), -kPi / 2, 1e-15);
  for (const double a : {3 * kPi, -3 * kPi, 5 * kPi, -kPi - 1e-15}) {
    const double w = sgdicp::wrap_angle(a);
    EXPECT_GT(w, -kPi) << a;
    EXPECT_LE(w, kPi) << a;
    EXPECT_NEAR(std::abs(w), kPi, 1e-12) << a;
  }
}

TEST(Pose, IsRigidTransform) {
  std::mt19937_64 rng(808);
  EXPECT_TRUE(sgdicp::is_rigid_transform(Eigen::Matrix4d::Identity()));
  for (int i = 0; i < 100; ++i) {
    const Eigen::Matrix4d t = random_rigid(rng, 50.0);
    ASSERT_TRUE(sgdicp::is_rigid_transform(t));

    Eigen::Matrix4d scaled = t;
    scaled.topLeftCorner<3, 3>() *= 1.01;
    EXPECT_FALSE(sgdicp::is_rigid_transform(scaled));
    // Uniform scaling of the whole matrix also breaks the last row.
    EXPECT_FALSE(sgdicp::is_rigid_transform(2.0 * t));

    Eigen::Matrix4d reflected = t;
    reflected.col(0).head<3>() *= -1.0;  // orthonormal but determinant -1
    EXPECT_FALSE(sgdicp::is_rigid_transform(reflected));
    EXPECT_FALSE(sgdicp::is_rigid_transform(-t));

    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) {
        Eigen::Matrix4d bad = t;
        bad(r, c) = std::numeric_limits<double>::quiet_NaN();
        ASSERT_FALSE(sgdicp::is_rigid_transform(bad)) << r << ' ' << c;
        bad(r, c) = std::numeric_limits<double>::infinity();
        ASSERT_FALSE(sgdicp::is_rigid_transform(bad)) << r << ' ' << c;
      }
    }
    for (int c = 0; c < 4; ++c) {
      Eigen::Matrix4d bad_row = t;
      bad_row(3, c) += 0.5;
      EXPECT_FALSE(sgdicp::is_rigid_transform(bad_row)) << c;
    }
    // Shear.
    Eigen::Matrix4d sheared = t;
    sheared(0, 1) += 0.05;
    EXPECT_FALSE(sgdicp::is_rigid_transform(sheared));
  }
  // The tolerance is honoured in both directions.
  Eigen::Matrix4d almost = Eigen::Matrix4d::Identity();
  almost(0, 0) = 1.0 + 1e-6;
  EXPECT_TRUE(sgdicp::is_rigid_transform(almost, 1e-4));
  EXPECT_FALSE(sgdicp::is_rigid_transform(almost, 1e-9));
}

TEST(Pose, OrthonormalizedIsNearestRotation) {
  std::mt19937_64 rng(909);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Matrix4d t = random_rigid(rng, 50.0);
    // An exact rotation stays (numerically) where it is.
    const Eigen::Matrix4d same = sgdicp::orthonormalized(t);
    ASSERT_LT(max_abs_diff(same, t), 1e-13);

    Eigen::Matrix4d noisy = t;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) noisy(r, c) += uniform(rng, -1e-4, 1e-4);
    }
    noisy.row(3) << 1e-5, -1e-5, 0, 1 + 1e-5;  // a sloppy last row is reset
    const Eigen::Matrix4d o = sgdicp::orthonormalized(noisy);
    ASSERT_TRUE(sgdicp::is_rigid_transform(o, 1e-12));
    ASSERT_EQ(o.row(3), Eigen::RowVector4d(0, 0, 0, 1));
    ASSERT_EQ((o.topRightCorner<3, 1>()), (noisy.topRightCorner<3, 1>()));
    // Close to the input, and closer to it (Frobenius) than the rotation it was made from.
    const Eigen::Matrix3d rn = noisy.topLeftCorner<3, 3>();
    const Eigen::Matrix3d ro = o.topLeftCorner<3, 3>();
    ASSERT_LT(max_abs_diff(ro, t.topLeftCorner<3, 3>()), 1e-3);
    ASSERT_LE((ro - rn).norm(), (t.topLeftCorner<3, 3>() - rn).norm() + 1e-15);
  }
  // A 3x3 block with determinant -1 is mapped to a proper rotation, not a reflection.
  Eigen::Matrix4d reflection = Eigen::Matrix4d::Identity();
  reflection(2, 2) = -1.0;
  EXPECT_NEAR((sgdicp::orthonormalized(reflection).topLeftCorner<3, 3>().determinant()), 1.0,
              1e-12);
}

// Long runs: 10 000 transforms composed as a solver composes its steps stay rotations to within
// a few ulps per step, so no re-orthonormalisation is needed. Measured: max(|R^T R - I|,
// |det R - 1|) = 2.5e-14 over 10 000 steps of up to 0.1 rad and 1 m, left, right and exp map.
double orthonormality_error(const Eigen::Matrix4d& t) {
  const Eigen::Matrix3d r = t.topLeftCorner<3, 3>();
  return std::max((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(),
                  std::abs(r.determinant() - 1.0));
}

TEST(Pose, TenThousandComposedTransformsStayOrthonormal) {
  std::mt19937_64 rng(1010);
  Eigen::Matrix4d left = Eigen::Matrix4d::Identity(), right = left, angle_axis = left;
  double worst = 0.0;
  for (int i = 0; i < 10000; ++i) {
    PoseVector step;
    for (int k = 0; k < 6; ++k) step[k] = uniform(rng, -1.0, 1.0) * (k < 3 ? 1.0 : 0.1);
    const Eigen::Matrix4d delta = sgdicp::transform_from_pose(step);
    left = delta * left;  // the batch solvers' update T = delta * T
    right = right * delta;
    // The exponential map of a rotation vector, as align_batch() steps.
    Eigen::Matrix4d exp_step = Eigen::Matrix4d::Identity();
    exp_step.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(step.tail<3>().norm(), step.tail<3>().normalized()).toRotationMatrix();
    exp_step.topRightCorner<3, 1>() = step.head<3>();
    angle_axis = exp_step * angle_axis;
    worst = std::max({worst, orthonormality_error(left), orthonormality_error(right),
                      orthonormality_error(angle_axis)});
  }
  std::printf("worst orthonormality error after 10000 steps: %.3g\n", worst);
  EXPECT_LT(worst, 1e-13);
  for (const auto& t : {left, right, angle_axis}) {
    EXPECT_TRUE(sgdicp::is_rigid_transform(t, 1e-13));
    EXPECT_EQ(t.row(3), Eigen::RowVector4d(0, 0, 0, 1));
    // The pose round trip of a long-run transform stays a rotation as well.
    EXPECT_LT(orthonormality_error(sgdicp::transform_from_pose(sgdicp::pose_from_transform(t))),
              1e-14);
  }
}

}  // namespace
