#include "sgdicp/voxel_map.hpp"

#include <cmath>
#include <string>

#include "sgdicp/error.hpp"

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
  for (const Eigen::Vector3f& p : cloud.points) {
    if (!p.allFinite()) continue;
    auto& voxel = voxels_[key_of(p)];
    if (voxel.size() >= max_points_) continue;
    if (voxel.empty()) voxel.reserve(max_points_);
    voxel.push_back(p);
    ++points_;
  }
}

void VoxelMap::remove_far_from(const Eigen::Vector3d& centre_m, double radius_m) {
  const double r2 = radius_m * radius_m;
  for (auto it = voxels_.begin(); it != voxels_.end();) {
    if ((it->second.front().cast<double>() - centre_m).squaredNorm() > r2) {
      points_ -= it->second.size();
      it = voxels_.erase(it);
    } else {
      ++it;
    }
  }
}

PointCloud VoxelMap::points() const {
  PointCloud out;
  out.points.reserve(points_);
  for (const auto& [key, voxel] : voxels_) {
    out.points.insert(out.points.end(), voxel.begin(), voxel.end());
  }
  return out;
}

void VoxelMap::clear() {
  voxels_.clear();
  points_ = 0;
}

}  // namespace sgdicp
