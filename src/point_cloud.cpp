#include "sgdicp/point_cloud.hpp"

#include <Eigen/Core>

namespace sgdicp {

PointCloud rebased(const PointCloud& cloud, const Eigen::Vector3d& origin_m) {
  // The identity between the frames: only the origin the points are stored from changes.
  return transformed(cloud, Eigen::Matrix4d::Identity(), origin_m);
}

PointCloud transformed(const PointCloud& cloud, const Eigen::Matrix4d& T,
                       const Eigen::Vector3d& origin_m) {
  const Eigen::Matrix4d T_stored = between_stored(T, cloud.origin_m, origin_m);
  const Eigen::Matrix3d r = T_stored.topLeftCorner<3, 3>();
  const Eigen::Vector3d t = T_stored.topRightCorner<3, 1>();
  const Eigen::Matrix3f r_f = r.cast<float>();
  PointCloud out = cloud;
  out.origin_m = origin_m;
  for (auto& p : out.points) {
    const Eigen::Vector3d moved = r * p.cast<double>() + t;
    p = {to_float_saturating(moved.x()), to_float_saturating(moved.y()),
         to_float_saturating(moved.z())};
  }
  for (auto& n : out.normals) n = r_f * n;
  for (auto& c : out.covariances) c = r_f * c * r_f.transpose();
  return out;
}

}  // namespace sgdicp
