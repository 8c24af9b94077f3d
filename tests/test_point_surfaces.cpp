// PointSurfaces on its own: a point's normal and covariance estimated on first use are exactly
// what estimate_covariances gives for it, only the points asked for are estimated, each once,
// and a cloud's own normals or covariances are used as they are.
#include <gtest/gtest.h>

#include "sgdicp/surfaces/normals.hpp"
#include "surfaces/point_surfaces.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

using test::synthetic_scene;

TEST(PointSurfaces, EstimatesOnFirstUseWhatEstimateCovariancesGives) {
  NeighborhoodSettings settings;
  settings.viewpoint = Eigen::Vector3f(0.3F, -2.0F, 1.0F);
  PointCloud cloud = synthetic_scene(51, 3000);
  cloud.origin_m = Eigen::Vector3d(100.0, 0.0, 0.0);  // the viewpoint is in the cloud's frame
  const ReferenceIndex index(cloud);
  PointCloud expected = cloud;
  estimate_covariances(expected, settings);

  detail::PointSurfaces surfaces(index, settings);
  for (const std::uint32_t i : {7U, 2999U, 7U, 1500U}) {
    EXPECT_EQ(surfaces.normal(i), expected.normals[i]) << i;
    EXPECT_EQ(surfaces.covariance(i), expected.covariances[i]) << i;
  }
  EXPECT_EQ(surfaces.estimated_count(), 3U);
}

TEST(PointSurfaces, UsesTheCloudsOwnNormalsAndCovariances) {
  PointCloud cloud = synthetic_scene(52, 500);
  cloud.normals.assign(cloud.size(), Eigen::Vector3f(0.0F, 0.0F, 1.0F));
  cloud.covariances.assign(cloud.size(), 2.0F * Eigen::Matrix3f::Identity());
  // No KD-tree at all: nothing may be estimated.
  detail::PointSurfaces surfaces(cloud, nullptr, NeighborhoodSettings{});
  EXPECT_EQ(surfaces.normal(10), Eigen::Vector3f(0.0F, 0.0F, 1.0F));
  EXPECT_EQ(surfaces.covariance(499), 2.0F * Eigen::Matrix3f::Identity());
  EXPECT_EQ(surfaces.estimated_count(), 0U);
}

}  // namespace
}  // namespace sgdicp
