#pragma once
// PCL interoperability, header-only and templated: it needs PCL (pcl/point_cloud.h, the PCL
// include directory; no PCL library) only where it is included (docs/pcl.md).
//   - to_point_cloud(pcl_cloud): any pcl::PointCloud<PointT> with x, y, z (and normal_x/y/z when
//     PointT has them) as sgd-icp's PointCloud;
//   - SgdIcp<PointSource, PointTarget>: SGD-ICP with PCL's registration calls (setInputSource,
//     setInputTarget, align(output[, guess]), getFinalTransformation, hasConverged,
//     getFitnessScore, setMaximumIterations, setMaxCorrespondenceDistance), so that code written
//     for pcl::IterativeClosestPoint switches by changing the type.
#include <cmath>
#include <memory>
#include <type_traits>
#include <utility>

#include <pcl/point_cloud.h>
#include <Eigen/Core>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/registration/settings.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"

namespace sgdicp::pcl_support {

template <typename PointT, typename = void>
struct HasNormal : std::false_type {};
template <typename PointT>
struct HasNormal<PointT, std::void_t<decltype(std::declval<PointT>().normal_x),
                                     decltype(std::declval<PointT>().normal_y),
                                     decltype(std::declval<PointT>().normal_z)>> : std::true_type {
};

}  // namespace sgdicp::pcl_support

namespace sgdicp {

/// The finite points of a PCL cloud (PCL marks invalid points with NaN, as in organised clouds),
/// in metres. PointT with normal_x/y/z: their normals too, when every kept point's normal is
/// finite (otherwise none, and a plane cost estimates its own).
template <typename PointT>
[[nodiscard]] PointCloud to_point_cloud(const pcl::PointCloud<PointT>& cloud) {
  PointCloud out;
  out.points.reserve(cloud.size());
  bool normals_finite = pcl_support::HasNormal<PointT>::value;
  for (const PointT& p : cloud.points) {
    const Eigen::Vector3f xyz(p.x, p.y, p.z);
    if (!xyz.allFinite()) continue;
    out.points.push_back(xyz);
    if constexpr (pcl_support::HasNormal<PointT>::value) {
      const Eigen::Vector3f n(p.normal_x, p.normal_y, p.normal_z);
      normals_finite = normals_finite && n.allFinite();
      out.normals.push_back(n);
    }
  }
  if (!normals_finite) out.normals.clear();
  return out;
}

/// SGD-ICP (SgdSettings, registration.md) behind PCL's registration interface. The target's
/// KD-tree is built on the first align() after setInputTarget and reused by later ones.
template <typename PointSource, typename PointTarget, typename Scalar = float>
class SgdIcp {
 public:
  using PointCloudSource = pcl::PointCloud<PointSource>;
  using PointCloudSourceConstPtr = typename PointCloudSource::ConstPtr;
  using PointCloudTarget = pcl::PointCloud<PointTarget>;
  using PointCloudTargetConstPtr = typename PointCloudTarget::ConstPtr;
  using Matrix4 = Eigen::Matrix<Scalar, 4, 4>;

  SgdIcp() = default;
  explicit SgdIcp(const SgdSettings& settings) : settings_(settings) {}

  void setInputSource(const PointCloudSourceConstPtr& cloud) { source_ = cloud; }
  void setInputTarget(const PointCloudTargetConstPtr& cloud) {
    target_ = cloud;
    index_.reset();
  }
  [[nodiscard]] PointCloudSourceConstPtr getInputSource() const { return source_; }
  [[nodiscard]] PointCloudTargetConstPtr getInputTarget() const { return target_; }

  /// d_max in metres (the library's Distance::metres), as pcl::Registration's.
  void setMaxCorrespondenceDistance(double distance_m) {
    settings_.pairing.max_correspondence_distance = Distance::metres(distance_m);
  }
  /// Mini-batches at most (SgdSettings::max_iterations).
  void setMaximumIterations(int iterations) {
    if (iterations < 1) throw InvalidSettingsError("setMaximumIterations: must be at least 1");
    settings_.max_iterations = static_cast<std::size_t>(iterations);
  }
  [[nodiscard]] SgdSettings& settings() noexcept { return settings_; }
  [[nodiscard]] const SgdSettings& settings() const noexcept { return settings_; }

  /// Registers the source to the target from `guess` (T_target_source) and writes the source
  /// moved by the result (every field copied, x/y/z and normals transformed) to `output`.
  /// Throws the library's errors (InvalidInputError for a missing or empty cloud).
  void align(PointCloudSource& output, const Matrix4& guess = Matrix4::Identity()) {
    if (!source_ || !target_) {
      throw InvalidInputError("SgdIcp::align: call setInputSource and setInputTarget first");
    }
    if (!index_) {
      index_ = std::make_shared<ReferenceIndex>(to_point_cloud(*target_));
    }
    prepare_reference(*index_, settings_.cost, settings_.neighborhood);
    result_ =
        sgdicp::align(to_point_cloud(*source_), *index_, settings_, guess.template cast<double>());
    transformed_copy(*source_, result_.T_reference_source, output);
  }

  /// T_target_source of the last align() (PCL's final transformation).
  [[nodiscard]] Matrix4 getFinalTransformation() const {
    return result_.T_reference_source.template cast<Scalar>();
  }
  [[nodiscard]] bool hasConverged() const noexcept { return result_.converged; }
  /// Mean squared distance of the final inlier pairs, m^2 (inlier_rmse_m squared): PCL's
  /// fitness score, restricted to the inliers within the final d_max.
  [[nodiscard]] double getFitnessScore() const noexcept {
    return result_.inlier_rmse_m * result_.inlier_rmse_m;
  }
  /// Everything the last align() reported (registration.md).
  [[nodiscard]] const RegistrationResult& result() const noexcept { return result_; }

 private:
  static void transformed_copy(const PointCloudSource& in, const Eigen::Matrix4d& T,
                               PointCloudSource& out) {
    out = in;
    const Eigen::Matrix3f R = T.topLeftCorner<3, 3>().cast<float>();
    const Eigen::Vector3f t = T.topRightCorner<3, 1>().cast<float>();
    for (PointSource& p : out.points) {
      const Eigen::Vector3f xyz = R * Eigen::Vector3f(p.x, p.y, p.z) + t;
      p.x = xyz.x();
      p.y = xyz.y();
      p.z = xyz.z();
      if constexpr (pcl_support::HasNormal<PointSource>::value) {
        const Eigen::Vector3f n = R * Eigen::Vector3f(p.normal_x, p.normal_y, p.normal_z);
        p.normal_x = n.x();
        p.normal_y = n.y();
        p.normal_z = n.z();
      }
    }
  }

  SgdSettings settings_;
  PointCloudSourceConstPtr source_;
  PointCloudTargetConstPtr target_;
  std::shared_ptr<ReferenceIndex> index_;
  RegistrationResult result_;
};

}  // namespace sgdicp
