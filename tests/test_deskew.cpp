// Registration of a sweep measured while the sensor moved (align_deskewed): the twist's
// exponential, a synthetic sweep under a known velocity compensated back to its shape, a rigid
// sweep left as it is, bad input, and the three skewed Newer College sweeps.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "sgdicp/core/error.hpp"
#include "sgdicp/registration/deskew.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Exp of a twist is the motion of that constant velocity: the product of many small steps.
TEST(Deskew, TheTwistsExponentialIsTheMotionOfItsConstantVelocity) {
  Twist xi;
  xi << 1.5, -0.4, 0.2, 0.3, -0.8, 1.9;
  Eigen::Matrix4d product = Eigen::Matrix4d::Identity();
  const int steps = 20000;
  Eigen::Matrix4d small = Eigen::Matrix4d::Identity();
  const Twist d = xi / steps;
  small.topLeftCorner<3, 3>() =
      Eigen::AngleAxisd(d.tail<3>().norm(), d.tail<3>().normalized()).toRotationMatrix();
  small.topRightCorner<3, 1>() = d.head<3>();
  for (int k = 0; k < steps; ++k) product = product * small;
  EXPECT_LT((exp_twist(xi) - product).cwiseAbs().maxCoeff(), 1e-4);
  Twist pure = Twist::Zero();
  pure.head<3>() << 1.0, 2.0, 3.0;
  const Eigen::Vector3d moved = exp_twist(pure).topRightCorner<3, 1>();
  EXPECT_EQ(moved, Eigen::Vector3d(1.0, 2.0, 3.0));
}

// A room 12 x 9 x 3 m (walls, floor, ceiling, a pillar) sampled at random.
std::vector<Eigen::Vector3d> room(std::mt19937_64& rng, int points) {
  std::vector<Eigen::Vector3d> out;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  while (static_cast<int>(out.size()) < points) {
    const double a = u(rng), b = u(rng);
    switch (static_cast<int>(u(rng) * 7)) {
      case 0:
        out.emplace_back(-6.0, -4.5 + 9 * a, 3 * b);
        break;
      case 1:
        out.emplace_back(6.0, -4.5 + 9 * a, 3 * b);
        break;
      case 2:
        out.emplace_back(-6 + 12 * a, -4.5, 3 * b);
        break;
      case 3:
        out.emplace_back(-6 + 12 * a, 4.5, 3 * b);
        break;
      case 4:
        out.emplace_back(-6 + 12 * a, -4.5 + 9 * b, 0.0);
        break;
      case 5:
        out.emplace_back(-6 + 12 * a, -4.5 + 9 * b, 3.0);
        break;
      default:
        out.emplace_back(2.0 + 0.5 * std::cos(2 * std::numbers::pi * a),
                         1.0 + 0.5 * std::sin(2 * std::numbers::pi * a), 3 * b);
    }
  }
  return out;
}

struct Sweep {
  PointCloud points;  // in the sensor's frame at each point's time
  std::vector<float> times_s;
  std::vector<Eigen::Vector3d> world;  // where each point is
};

// A 0.1 s sweep from T_mid under the velocity xi: each world point gets the time of its azimuth
// seen from T_mid, and is measured from the pose of that time.
Sweep sweep_of(const std::vector<Eigen::Vector3d>& world, const Eigen::Matrix4d& T_mid,
               const Twist& xi) {
  Sweep s;
  const Eigen::Matrix4d mid_inverse = T_mid.inverse();
  for (const Eigen::Vector3d& w : world) {
    const Eigen::Vector3d local =
        mid_inverse.topLeftCorner<3, 3>() * w + mid_inverse.topRightCorner<3, 1>();
    const double t =
        0.1 * (std::atan2(local.y(), local.x()) + std::numbers::pi) / (2 * std::numbers::pi);
    const Eigen::Matrix4d T = T_mid * exp_twist((t - 0.05) * xi);
    const Eigen::Matrix4d inverse = T.inverse();
    s.points.points.push_back(
        (inverse.topLeftCorner<3, 3>() * w + inverse.topRightCorner<3, 1>()).cast<float>());
    s.times_s.push_back(static_cast<float>(t));
    s.world.push_back(w);
  }
  return s;
}

// Moving at 2 m/s and turning at 120 deg/s, the sweep is 20 cm and 12 deg out of shape; the
// registration from the rigid pose finds the velocity and puts every point back within a few mm.
TEST(Deskew, ASyntheticSweepUnderAKnownVelocityIsCompensatedBackToItsShape) {
  std::mt19937_64 rng(7);
  PointCloud reference;
  for (const auto& p : room(rng, 60000)) reference.points.push_back(p.cast<float>());
  ReferenceIndex index = reference_index_for(reference, SgdSettings{});
  prepare_reference(index, CostType::point_to_plane);
  Twist xi;
  xi << 2.0, 0.3, 0.0, 0.05, -0.1, 120.0 * std::numbers::pi / 180.0;
  const Eigen::Matrix4d T_mid = test::make_transform(0.02, -0.01, 0.4, {0.5, -0.3, 1.2});
  const Sweep s = sweep_of(room(rng, 20000), T_mid, xi);
  const RegistrationResult rigid = align(s.points, index, SgdSettings{}, T_mid);
  const DeskewedRegistration r =
      align_deskewed(s.points, s.times_s, index, rigid.T_reference_source);
  EXPECT_TRUE(r.converged) << r.message;
  const PointCloud out = deskewed_in_reference(s.points, s.times_s, r);
  std::vector<double> before, after;
  for (std::size_t i = 0; i < out.size(); ++i) {
    after.push_back((out.points[i].cast<double>() - s.world[i]).norm());
    const Eigen::Matrix4d& T = rigid.T_reference_source;
    before.push_back((T.topLeftCorner<3, 3>() * s.points.points[i].cast<double>() +
                      T.topRightCorner<3, 1>() - s.world[i])
                         .norm());
  }
  std::cout << "synthetic sweep: rigid " << median(before) * 1000 << " mm, deskewed "
            << median(after) * 1000 << " mm, velocity " << r.velocity.transpose() << '\n';
  EXPECT_GT(median(before), 0.05);
  EXPECT_LT(median(after), 0.005);
  EXPECT_LT((r.velocity - xi).head<3>().norm(), 0.1);
  EXPECT_LT((r.velocity - xi).tail<3>().norm(), 0.02);
}

TEST(Deskew, LogIsTheInverseOfExp) {
  Twist xi;
  xi << 0.7, -1.2, 0.4, 0.9, 0.3, -1.4;
  EXPECT_LT((log_twist(exp_twist(xi)) - xi).norm(), 1e-9);
  EXPECT_LT(log_twist(Eigen::Matrix4d::Identity()).norm(), 1e-12);
}

// With the exact motion over the sweep (the sensor's motion from the sweep's first time to its
// last), the constant-velocity deskewing puts the sweep back into its shape at the middle pose.
TEST(Deskew, ASweepUnderAKnownMotionIsCompensatedByThatMotion) {
  std::mt19937_64 rng(9);
  Twist xi;
  xi << 3.0, -0.5, 0.1, 0.02, 0.04, 1.5;
  const Eigen::Matrix4d T_mid = test::make_transform(0.0, 0.0, -0.3, {0.2, 0.1, 1.0});
  const Sweep s = sweep_of(room(rng, 5000), T_mid, xi);
  PointCloud frame = s.points;
  frame.times_s = s.times_s;
  const auto [lo, hi] = std::minmax_element(s.times_s.begin(), s.times_s.end());
  const Eigen::Matrix4d sweep_motion = exp_twist((*hi - *lo) * xi);
  const PointCloud out = deskewed_by_motion(frame, sweep_motion);
  ASSERT_EQ(out.times_s, frame.times_s);
  // The sweep's middle time is 0.05 s only to the float times' precision: the mid pose of the
  // times' own span.
  const double mid = 0.5 * (static_cast<double>(*lo) + static_cast<double>(*hi));
  const Eigen::Matrix4d T = (T_mid * exp_twist((mid - 0.05) * xi)).inverse();
  std::vector<double> before, after;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const Eigen::Vector3d truth = T.topLeftCorner<3, 3>() * s.world[i] + T.topRightCorner<3, 1>();
    after.push_back((out.points[i].cast<double>() - truth).norm());
    before.push_back((frame.points[i].cast<double>() - truth).norm());
  }
  EXPECT_GT(median(before), 0.05);
  EXPECT_LT(*std::max_element(after.begin(), after.end()), 1e-4);
  PointCloud without = s.points;  // no times: as it is
  EXPECT_EQ(deskewed_by_motion(without, sweep_motion).points, without.points);
}

// KITTI's Velodyne turns clockwise seen from above: behind, left, ahead, right, behind.
TEST(Deskew, AzimuthTimesTurnClockwiseFromBehind) {
  PointCloud c;
  c.points = {{-1.0F, 1e-6F, 0.0F},
              {0.0F, 1.0F, 0.0F},
              {1.0F, 0.0F, 0.0F},
              {0.0F, -1.0F, 0.0F},
              {-1.0F, -1e-6F, 0.0F}};
  const std::vector<float> t = azimuth_times_s(c, 0.1);
  const std::vector<float> expected{0.0F, 0.025F, 0.05F, 0.075F, 0.1F};
  for (std::size_t i = 0; i < t.size(); ++i) EXPECT_NEAR(t[i], expected[i], 1e-6) << i;
}

TEST(Deskew, ARigidSweepIsLeftAsItIsAndBadInputIsRefused) {
  std::mt19937_64 rng(8);
  PointCloud reference;
  for (const auto& p : room(rng, 20000)) reference.points.push_back(p.cast<float>());
  ReferenceIndex index = reference_index_for(reference, SgdSettings{});
  prepare_reference(index, CostType::point_to_plane);
  PointCloud source;
  for (const auto& p : room(rng, 3000)) source.points.push_back(p.cast<float>());
  const Eigen::Matrix4d T = test::make_transform(0.0, 0.0, 0.1, {0.2, 0.0, 0.0});
  const std::vector<float> same(source.size(), 0.03F);
  const DeskewedRegistration r = align_deskewed(source, same, index, T);
  EXPECT_TRUE(r.T_reference_source == T);
  EXPECT_TRUE(r.velocity == Twist::Zero());
  EXPECT_EQ(r.iterations, 0U);
  EXPECT_THROW((void)align_deskewed(source, std::vector<float>(5, 0.0F), index, T),
               InvalidInputError);
  std::vector<float> nan = same;
  nan[3] = std::nanf("");
  EXPECT_THROW((void)align_deskewed(source, nan, index, T), InvalidInputError);
  const ReferenceIndex no_normals(reference);
  std::vector<float> spread(source.size());
  for (std::size_t i = 0; i < spread.size(); ++i) spread[i] = 1e-5F * static_cast<float>(i);
  EXPECT_THROW((void)align_deskewed(source, spread, no_normals, T), InvalidInputError);
}

std::vector<float> read_floats(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<float> out;
  float v = 0.0F;
  while (in.read(reinterpret_cast<char*>(&v), sizeof v)) out.push_back(v);
  return out;
}

PointCloud read_xyz_f32(const std::filesystem::path& path) {
  const std::vector<float> f = read_floats(path);
  PointCloud c;
  for (std::size_t i = 0; i + 2 < f.size(); i += 3) c.points.emplace_back(f[i], f[i + 1], f[i + 2]);
  return c;
}

// The Newer College sweeps, taken while the rig was turned quickly: each raw sweep with its
// times registered to its motion-compensated copy (from the 180 deg turn between their frames,
// PROVENANCE.md), point i to point i. The best rigid fit leaves 22 / 23 / 68 cm (median), the
// best constant velocity 4.1 / 0.7 / 2.8 cm; at most 6 cm each.
TEST(Deskew, NewerCollegeSweepsCompensatedToTheirCopies) {
  const auto folder = std::filesystem::path(SGDICP_SHARED_DATA) / "newer_college_ouster_skewed";
  if (!std::filesystem::exists(folder / "raw_00.bin")) GTEST_SKIP() << "no " << folder;
  for (const char* k : {"00", "01", "02"}) {
    const PointCloud raw = read_xyz_f32(folder / (std::string("raw_") + k + ".bin"));
    const std::vector<float> times = read_floats(folder / (std::string("times_") + k + ".bin"));
    const PointCloud copy = read_xyz_f32(folder / (std::string("deskewed_") + k + ".bin"));
    ASSERT_EQ(raw.size(), times.size());
    ReferenceIndex index = reference_index_for(copy, SgdSettings{});
    prepare_reference(index, CostType::point_to_plane);
    const Eigen::Matrix4d turn = test::make_transform(0.0, 0.0, std::numbers::pi, {0, 0, 0});
    const RegistrationResult rigid = align(raw, index, SgdSettings{}, turn);
    const DeskewedRegistration r = align_deskewed(raw, times, index, rigid.T_reference_source);
    const PointCloud out = deskewed_in_reference(raw, times, r);
    std::vector<double> rigid_m, ours_m;
    const Eigen::Matrix4d& T = rigid.T_reference_source;
    for (std::size_t i = 0; i < raw.size(); ++i) {
      const Eigen::Vector3d target = copy.points[i].cast<double>();
      ours_m.push_back((out.points[i].cast<double>() - target).norm());
      rigid_m.push_back((T.topLeftCorner<3, 3>() * raw.points[i].cast<double>() +
                         T.topRightCorner<3, 1>() - target)
                            .norm());
    }
    std::cout << "sweep " << k << ": rigid registration " << median(rigid_m) * 100
              << " cm, deskewed " << median(ours_m) * 100 << " cm (" << r.iterations
              << " iterations, " << r.message << "), velocity " << r.velocity.transpose() << '\n';
    EXPECT_TRUE(r.converged) << k << ": " << r.message;
    EXPECT_LT(median(ours_m), 0.06) << k;
  }
}

}  // namespace
}  // namespace sgdicp
