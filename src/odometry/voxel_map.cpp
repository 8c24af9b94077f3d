#include "sgdicp/odometry/voxel_map.hpp"

#include <cmath>
#include <string>

#include "sgdicp/core/error.hpp"

namespace sgdicp {

VoxelMap::VoxelMap(double voxel_size_m, std::size_t max_points_per_voxel)
    : voxel_size_m_(voxel_size_m), max_points_(max_points_per_voxel) {
  if (!std::isfinite(voxel_size_m) || voxel_size_m <= 0.0) {
    throw InvalidSettingsError("voxel map: voxel size must be positive and finite, got " +
                               std::to_string(voxel_size_m));
  }
  if (max_points_per_voxel == 0) {
    throw InvalidSettingsError("voxel map: at least one point per voxel");
  }
}

std::size_t VoxelMap::KeyHash::operator()(const Key& k) const noexcept {
  // The spatial hash of Teschner et al. 2003: three large primes, xor-ed.
  return static_cast<std::size_t>((static_cast<std::uint64_t>(k.x) * 73856093U) ^
                                  (static_cast<std::uint64_t>(k.y) * 19349669U) ^
                                  (static_cast<std::uint64_t>(k.z) * 83492791U));
}

VoxelMap::Key VoxelMap::key_of(const Eigen::Vector3f& p) const {
  const auto cell = [&](float v) {
    return static_cast<std::int64_t>(std::floor(static_cast<double>(v) / voxel_size_m_));
  };
  return {cell(p.x()), cell(p.y()), cell(p.z())};
}

void VoxelMap::add(const PointCloud& cloud) {
  const bool normals = cloud.has_normals(), covariances = cloud.has_covariances();
  for (const std::uint32_t i : admitted(cloud)) {
    Voxel& voxel = voxels_[key_of(cloud.points[i])];
    voxel.points.push_back(cloud.points[i]);
    ++points_;
    if (normals) {
      voxel.normals.push_back(cloud.normals[i]);
      ++normals_;
    }
    if (covariances) {
      voxel.covariances.push_back(cloud.covariances[i]);
      ++covariances_;
    }
  }
}

// The one admission rule, which add() applies: a finite point enters while its voxel holds fewer
// than max_points_ points, counting those of `cloud` before it.
std::vector<std::uint32_t> VoxelMap::admitted(const PointCloud& cloud) const {
  std::vector<std::uint32_t> out;
  std::unordered_map<Key, std::size_t, KeyHash> added;  // by this cloud, per voxel
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!p.allFinite()) continue;
    const Key key = key_of(p);
    const auto it = voxels_.find(key);
    std::size_t& mine = added[key];
    if ((it == voxels_.end() ? 0 : it->second.points.size()) + mine >= max_points_) continue;
    ++mine;
    out.push_back(static_cast<std::uint32_t>(i));
  }
  return out;
}

void VoxelMap::remove_far_from(const Eigen::Vector3d& centre_m, double radius_m) {
  const double r2 = radius_m * radius_m;
  for (auto it = voxels_.begin(); it != voxels_.end();) {
    const Voxel& v = it->second;
    if ((v.points.front().cast<double>() - centre_m).squaredNorm() > r2) {
      points_ -= v.points.size();
      normals_ -= v.normals.size();
      covariances_ -= v.covariances.size();
      it = voxels_.erase(it);
    } else {
      ++it;
    }
  }
}

PointCloud VoxelMap::points() const {
  PointCloud out;
  const bool normals = points_ > 0 && normals_ == points_;
  const bool covariances = points_ > 0 && covariances_ == points_;
  out.points.reserve(points_);
  if (normals) out.normals.reserve(points_);
  if (covariances) out.covariances.reserve(points_);
  for (const auto& [key, voxel] : voxels_) {
    out.points.insert(out.points.end(), voxel.points.begin(), voxel.points.end());
    if (normals) out.normals.insert(out.normals.end(), voxel.normals.begin(), voxel.normals.end());
    if (covariances) {
      out.covariances.insert(out.covariances.end(), voxel.covariances.begin(),
                             voxel.covariances.end());
    }
  }
  return out;
}

void VoxelMap::clear() {
  voxels_.clear();
  points_ = normals_ = covariances_ = 0;
}

}  // namespace sgdicp
