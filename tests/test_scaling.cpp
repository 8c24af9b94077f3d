// Tests of the paper's unit-cube scaling (scaling.hpp): one common map for both clouds into
// [0, 1] (lower corner) or [-0.5, 0.5] (centre), and the exact correspondence between a
// transform in scaled space and its metric version.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "core/checks.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/points/scaling.hpp"
#include "test_support.hpp"

namespace {

using sgdicp::test::random_rigid;
using sgdicp::test::uniform;

using sgdicp::BoundingBox;
using sgdicp::PointCloud;
using sgdicp::ScalingOrigin;
using sgdicp::UnitCubeScaling;

// A cloud inside a random box: corner anywhere in [-1000, 1000]^3, sides in [0.01, 100] m.
PointCloud random_cloud(std::mt19937_64& rng, std::size_t n) {
  const Eigen::Vector3d corner(uniform(rng, -1000, 1000), uniform(rng, -1000, 1000),
                               uniform(rng, -1000, 1000));
  const Eigen::Vector3d sides(uniform(rng, 0.01, 100), uniform(rng, 0.01, 100),
                              uniform(rng, 0.01, 100));
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p =
        corner + Eigen::Vector3d(uniform(rng, 0, 1), uniform(rng, 0, 1), uniform(rng, 0, 1))
                     .cwiseProduct(sides);
    cloud.points.push_back(p.cast<float>());
  }
  return cloud;
}

BoundingBox box_of(const PointCloud& cloud) {
  BoundingBox b;
  b.extend(cloud);
  return b;
}

Eigen::Vector3d apply(const Eigen::Matrix4d& t, const Eigen::Vector3d& p) {
  return t.topLeftCorner<3, 3>() * p + t.topRightCorner<3, 1>();
}

void check_cube(ScalingOrigin origin, double lo, double hi) {
  std::mt19937_64 rng(origin == ScalingOrigin::lower_corner ? 21 : 22);
  for (int trial = 0; trial < 50; ++trial) {
    const PointCloud a = random_cloud(rng, 500);
    const PointCloud b = random_cloud(rng, 700);
    const UnitCubeScaling scaling = UnitCubeScaling::from_boxes(box_of(a), box_of(b), origin);
    BoundingBox scaled;
    for (const PointCloud* cloud : {&a, &b}) {
      for (const auto& p : cloud->points) {
        const Eigen::Vector3d q = scaling.to_scaled(Eigen::Vector3d(p.cast<double>()));
        for (int k = 0; k < 3; ++k) {
          ASSERT_GE(q[k], lo - 1e-12) << "trial " << trial;
          ASSERT_LE(q[k], hi + 1e-12) << "trial " << trial;
        }
        scaled.extend(q);
        // to_metric undoes to_scaled.
        ASSERT_LT((scaling.to_metric(q) - p.cast<double>()).norm(), 1e-12 * scaling.scale() + 1e-9);
      }
    }
    const Eigen::Vector3d sides = scaled.max - scaled.min;
    EXPECT_NEAR(sides.maxCoeff(), 1.0, 1e-12) << "the largest side of the joint box must be 1";
    // The scale is the largest side of the joint box, independently computed.
    BoundingBox joint = box_of(a);
    joint.extend(b);
    EXPECT_DOUBLE_EQ(scaling.scale(), (joint.max - joint.min).maxCoeff());
    if (origin == ScalingOrigin::lower_corner) {
      EXPECT_EQ(scaled.min, Eigen::Vector3d::Zero()) << "the lower corner maps exactly to 0";
      EXPECT_EQ(scaling.offset(), joint.min);
    } else {
      // Centred: the box is symmetric about 0 in every axis.
      EXPECT_LT((scaled.min + scaled.max).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LT((scaling.offset() - 0.5 * (joint.min + joint.max)).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
}

// BoundingBox::of reads the points twelve coordinates at a time: every size (tails of 0-3
// points), the extremes in any point and any axis, negative coordinates and one point.
TEST(BoundingBox, OfEqualsThePointByPointBox) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> coordinate(-50.0f, 30.0f);
  for (std::size_t n = 0; n <= 41; ++n) {
    PointCloud cloud;
    BoundingBox expected;
    for (std::size_t i = 0; i < n; ++i) {
      cloud.points.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
      expected.extend(cloud.points.back().cast<double>());
    }
    const BoundingBox box = BoundingBox::of(cloud);
    EXPECT_EQ(box.min, expected.min) << n << " points";
    EXPECT_EQ(box.max, expected.max) << n << " points";
    EXPECT_EQ(box.valid(), n > 0);
  }
}

// extent_of gives BoundingBox::of and largest_coordinate from one pass, and a non-finite point,
// in the twelve-float lanes or in the tail, anywhere and of any kind, is refused by its index.
TEST(CloudExtent, IsTheBoxAndTheLargestAndRefusesANonFinitePoint) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> coordinate(-50.0f, 30.0f);
  for (std::size_t n = 0; n <= 17; ++n) {
    PointCloud cloud;
    for (std::size_t i = 0; i < n; ++i) {
      cloud.points.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
    }
    const sgdicp::detail::CloudExtent extent = sgdicp::detail::extent_of(cloud);
    const BoundingBox box = BoundingBox::of(cloud);
    EXPECT_EQ(extent.box.min, box.min) << n << " points";
    EXPECT_EQ(extent.box.max, box.max) << n << " points";
    EXPECT_EQ(extent.largest, sgdicp::detail::largest_coordinate(cloud)) << n << " points";
    for (std::size_t i = 0; i < n; ++i) {
      for (const float bad :
           {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
            -std::numeric_limits<float>::infinity()}) {
        PointCloud broken = cloud;
        broken.points[i][static_cast<Eigen::Index>(i % 3)] = bad;
        try {
          (void)sgdicp::detail::extent_of(broken, "source cloud");
          ADD_FAILURE() << n << " points, " << bad << " at " << i << " accepted";
        } catch (const sgdicp::InvalidInputError& e) {
          EXPECT_EQ(std::string(e.what()),
                    "source cloud has a non-finite point at index " + std::to_string(i));
        }
      }
    }
  }
}

TEST(UnitCubeScaling, LowerCornerMapsBothCloudsIntoUnitCube) {
  check_cube(ScalingOrigin::lower_corner, 0.0, 1.0);
}

TEST(UnitCubeScaling, CenterMapsBothCloudsIntoCenteredCube) {
  check_cube(ScalingOrigin::center, -0.5, 0.5);
}

TEST(UnitCubeScaling, DefaultOriginIsThePapersLowerCorner) {
  BoundingBox a;
  a.extend(Eigen::Vector3d(1, 2, 3));
  a.extend(Eigen::Vector3d(3, 3, 4));
  BoundingBox b;
  b.extend(Eigen::Vector3d(-1, 2, 3));
  const UnitCubeScaling s = UnitCubeScaling::from_boxes(a, b);
  EXPECT_EQ(s.offset(), Eigen::Vector3d(-1, 2, 3));
  EXPECT_EQ(s.scale(), 4.0);
  EXPECT_EQ(s.to_scaled(Eigen::Vector3d(3, 3, 4)), Eigen::Vector3d(1.0, 0.25, 0.25));
}

TEST(UnitCubeScaling, TransformRoundTrip) {
  std::mt19937_64 rng(23);
  for (const ScalingOrigin origin : {ScalingOrigin::lower_corner, ScalingOrigin::center}) {
    for (int trial = 0; trial < 200; ++trial) {
      const PointCloud a = random_cloud(rng, 20);
      const PointCloud b = random_cloud(rng, 20);
      const UnitCubeScaling s = UnitCubeScaling::from_boxes(box_of(a), box_of(b), origin);
      const Eigen::Matrix4d t = random_rigid(rng, 100.0);
      const Eigen::Matrix4d back = s.to_metric(s.to_scaled(t));
      const double scale = 1.0 + t.cwiseAbs().maxCoeff() + s.offset().cwiseAbs().maxCoeff();
      ASSERT_LT((back - t).cwiseAbs().maxCoeff(), 1e-12 * scale) << trial;
      ASSERT_EQ((back.topLeftCorner<3, 3>()), (t.topLeftCorner<3, 3>())) << "rotations stay";
      ASSERT_EQ(back.row(3), Eigen::RowVector4d(0, 0, 0, 1));
      const Eigen::Matrix4d back2 = s.to_scaled(s.to_metric(t));
      ASSERT_LT((back2 - t).cwiseAbs().maxCoeff(), 1e-12 * scale) << trial;
    }
  }
}

TEST(UnitCubeScaling, ScaledTransformMovesPointsLikeTheMetricOne) {
  // p'_s = T_scaled * to_scaled(p) with T_scaled = to_scaled(T_metric) must be the scaled image
  // of T_metric * p: to_metric(p'_s) == T_metric * p.
  std::mt19937_64 rng(24);
  for (const ScalingOrigin origin : {ScalingOrigin::lower_corner, ScalingOrigin::center}) {
    for (int trial = 0; trial < 200; ++trial) {
      const PointCloud a = random_cloud(rng, 20);
      const PointCloud b = random_cloud(rng, 20);
      const UnitCubeScaling s = UnitCubeScaling::from_boxes(box_of(a), box_of(b), origin);
      const Eigen::Matrix4d t_metric = random_rigid(rng, 100.0);
      const Eigen::Matrix4d t_scaled = s.to_scaled(t_metric);
      for (int i = 0; i < 20; ++i) {
        const Eigen::Vector3d p = a.points[static_cast<std::size_t>(i)].cast<double>();
        const Eigen::Vector3d expected = apply(t_metric, p);
        const Eigen::Vector3d got = s.to_metric(apply(t_scaled, s.to_scaled(p)));
        const double tol = 1e-9 * std::max(1.0, expected.norm() + p.norm());
        ASSERT_LT((got - expected).norm(), tol) << "trial " << trial;
      }
      // The reverse direction: a transform found in scaled space, undone to metric.
      const Eigen::Matrix4d found_scaled = random_rigid(rng, 0.5);
      const Eigen::Matrix4d found_metric = s.to_metric(found_scaled);
      for (int i = 0; i < 20; ++i) {
        const Eigen::Vector3d p = b.points[static_cast<std::size_t>(i)].cast<double>();
        const Eigen::Vector3d via_scaled = s.to_metric(apply(found_scaled, s.to_scaled(p)));
        const Eigen::Vector3d direct = apply(found_metric, p);
        ASSERT_LT((via_scaled - direct).norm(), 1e-9 * std::max(1.0, direct.norm() + p.norm()));
      }
    }
  }
}

TEST(UnitCubeScaling, ZeroExtentThrows) {
  BoundingBox single;
  single.extend(Eigen::Vector3d(1, 2, 3));
  EXPECT_THROW((void)UnitCubeScaling::from_boxes(single, single), sgdicp::InvalidInputError);
  EXPECT_THROW((void)UnitCubeScaling::from_boxes(single, single, ScalingOrigin::center),
               sgdicp::InvalidInputError);
  // Both empty.
  EXPECT_THROW((void)UnitCubeScaling::from_boxes(BoundingBox{}, BoundingBox{}),
               sgdicp::InvalidInputError);
  // One empty, one a single point.
  EXPECT_THROW((void)UnitCubeScaling::from_boxes(BoundingBox{}, single), sgdicp::InvalidInputError);
  // Infinite extent.
  BoundingBox infinite = single;
  infinite.extend(Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0));
  EXPECT_THROW((void)UnitCubeScaling::from_boxes(infinite, single), sgdicp::InvalidInputError);
}

TEST(UnitCubeScaling, FlatCloudsAreFine) {
  // Zero extent in some axes (a planar or linear cloud) is not zero extent.
  BoundingBox a;
  a.extend(Eigen::Vector3d(0, 0, 5));
  a.extend(Eigen::Vector3d(2, 0, 5));
  BoundingBox b;
  b.extend(Eigen::Vector3d(1, 0, 5));
  const UnitCubeScaling s = UnitCubeScaling::from_boxes(a, b);
  EXPECT_EQ(s.scale(), 2.0);
  EXPECT_EQ(s.to_scaled(Eigen::Vector3d(2, 0, 5)), Eigen::Vector3d(1, 0, 0));
}

}  // namespace
