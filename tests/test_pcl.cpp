// The PCL adaptor (sgdicp/adapters/pcl.hpp) on the bundled demo pair: pcl::PointCloud<PointT>
// converts point for point, SgdIcp gives the transform of sgdicp::align (what the CLI runs) bit for
// bit, near the ground truth, and moves the output cloud by it; normals of PointNormal reach the
// point-to-plane cost.
#include <cmath>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "sgdicp/adapters/pcl.hpp"
#include "sgdicp/io/io.hpp"
#include "sgdicp/io/transform_io.hpp"
#include "sgdicp/metrics/metrics.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/surfaces/normals.hpp"

namespace sgdicp {
namespace {

const std::filesystem::path kDemo = SGDICP_DEMO_DATA;

template <typename PointT>
typename pcl::PointCloud<PointT>::Ptr to_pcl(const PointCloud& cloud) {
  auto out = std::make_shared<pcl::PointCloud<PointT>>();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    PointT p;
    p.x = cloud.points[i].x();
    p.y = cloud.points[i].y();
    p.z = cloud.points[i].z();
    if constexpr (pcl_support::HasNormal<PointT>::value) {
      p.normal_x = cloud.normals[i].x();
      p.normal_y = cloud.normals[i].y();
      p.normal_z = cloud.normals[i].z();
    }
    out->push_back(p);
  }
  return out;
}

struct DemoPair {
  PointCloud source = read_point_cloud(kDemo / "car_cloud401.csv").cloud;
  PointCloud reference = read_point_cloud(kDemo / "car_cloud400.csv").cloud;
  Eigen::Matrix4d T_gt = read_transform(kDemo / "T_gt.txt");
};

TEST(Pcl, ConvertsFinitePointsAndNormals) {
  pcl::PointCloud<pcl::PointNormal> cloud;
  pcl::PointNormal p;
  p.x = 1.0F, p.y = 2.0F, p.z = 3.0F, p.normal_x = 0.0F, p.normal_y = 0.0F, p.normal_z = 1.0F;
  cloud.push_back(p);
  p.x = std::numeric_limits<float>::quiet_NaN();  // an invalid point of an organised cloud
  cloud.push_back(p);
  const PointCloud c = to_point_cloud(cloud);
  ASSERT_EQ(c.size(), 1U);
  EXPECT_EQ(c.points[0], Eigen::Vector3f(1, 2, 3));
  ASSERT_TRUE(c.has_normals());
  EXPECT_EQ(c.normals[0], Eigen::Vector3f(0, 0, 1));
  cloud.points[0].normal_x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(to_point_cloud(cloud).has_normals());  // estimated by a plane cost instead
}

TEST(Pcl, SgdIcpMatchesTheLibraryOnTheDemoPair) {
  const DemoPair pair;
  SgdIcp<pcl::PointXYZ, pcl::PointXYZ> icp;
  icp.setInputSource(to_pcl<pcl::PointXYZ>(pair.source));
  icp.setInputTarget(to_pcl<pcl::PointXYZ>(pair.reference));
  pcl::PointCloud<pcl::PointXYZ> output;
  icp.align(output);
  ASSERT_TRUE(icp.hasConverged()) << icp.result().message;

  const RegistrationResult expected = align(pair.source, pair.reference, SgdSettings{});
  EXPECT_EQ(icp.result().T_reference_source, expected.T_reference_source);
  EXPECT_EQ(icp.getFinalTransformation(), expected.T_reference_source.cast<float>());
  EXPECT_LT(translation_error(icp.result().T_reference_source, pair.T_gt), 0.05);
  EXPECT_LT(rotation_error_geodesic(icp.result().T_reference_source, pair.T_gt), 0.01);
  EXPECT_NEAR(icp.getFitnessScore(), expected.inlier_rmse_m * expected.inlier_rmse_m, 1e-12);

  ASSERT_EQ(output.size(), pair.source.size());
  const Eigen::Matrix4f T = icp.getFinalTransformation();
  const Eigen::Vector3f moved =
      T.topLeftCorner<3, 3>() * pair.source.points[7] + T.topRightCorner<3, 1>();
  EXPECT_LT((output.points[7].getVector3fMap() - moved).norm(), 1e-5F);

  // A second align() reuses the target's tree and starts from the guess.
  icp.align(output, pair.T_gt.cast<float>());
  EXPECT_LT(translation_error(icp.result().T_reference_source, pair.T_gt), 0.05);
}

TEST(Pcl, TargetNormalsReachThePointToPlaneCost) {
  DemoPair pair;
  const PointCloud without_normals = pair.reference;
  NeighborhoodSettings few;  // not the neighbourhood the cost would estimate its normals with
  few.k = 6;
  estimate_normals(pair.reference, few);
  SgdSettings settings;
  settings.cost = CostType::point_to_plane;
  SgdIcp<pcl::PointXYZ, pcl::PointNormal> icp(settings);
  icp.setInputSource(to_pcl<pcl::PointXYZ>(pair.source));
  icp.setInputTarget(to_pcl<pcl::PointNormal>(pair.reference));
  pcl::PointCloud<pcl::PointXYZ> output;
  icp.align(output);
  const RegistrationResult expected = align(pair.source, pair.reference, settings);
  EXPECT_EQ(icp.result().T_reference_source, expected.T_reference_source);
  const RegistrationResult estimated = align(pair.source, without_normals, settings);
  EXPECT_NE(icp.result().T_reference_source, estimated.T_reference_source);  // the given ones
  EXPECT_LT(translation_error(icp.result().T_reference_source, pair.T_gt), 0.05);
}

TEST(Pcl, ErrorsAreTheLibrarys) {
  SgdIcp<pcl::PointXYZ, pcl::PointXYZ> icp;
  pcl::PointCloud<pcl::PointXYZ> output;
  EXPECT_THROW(icp.align(output), InvalidInputError);
  EXPECT_THROW(icp.setMaximumIterations(0), InvalidSettingsError);
}

}  // namespace
}  // namespace sgdicp
