#include "sgdicp/odometry/voxel_map.hpp"

#include <cmath>
#include <string>

#include "index/voxel_hash.hpp"
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
  // Cells of two voxels a side: measured fastest for the map's queries (docs/design.md).
  hash_ = std::make_unique<detail::VoxelHash>(2.0 * voxel_size_m, max_points_per_voxel);
}

VoxelMap::~VoxelMap() = default;
VoxelMap::VoxelMap(const VoxelMap& other)
    : voxel_size_m_(other.voxel_size_m_),
      max_points_(other.max_points_),
      hash_(std::make_unique<detail::VoxelHash>(*other.hash_)) {}
VoxelMap& VoxelMap::operator=(const VoxelMap& other) {
  if (this != &other) *this = VoxelMap(other);
  return *this;
}
VoxelMap::VoxelMap(VoxelMap&&) noexcept = default;
VoxelMap& VoxelMap::operator=(VoxelMap&&) noexcept = default;

void VoxelMap::add(const PointCloud& cloud) {
  hash_->add(cloud);
}

std::vector<std::uint32_t> VoxelMap::admitted(const PointCloud& cloud) const {
  return hash_->admitted(cloud);
}

void VoxelMap::remove_far_from(const Eigen::Vector3d& centre_m, double radius_m) {
  hash_->remove_far_from(centre_m, radius_m);
}

const PointCloud& VoxelMap::points() const {
  return hash_->cloud();
}

ReferenceIndex VoxelMap::index() const {
  return ReferenceIndex::viewing(*hash_);
}

std::size_t VoxelMap::size() const noexcept {
  return hash_->cloud().size();
}

double VoxelMap::spacing_m() const noexcept {
  return hash_->spacing_m();
}

std::size_t VoxelMap::voxels() const noexcept {
  return hash_->voxels();
}

void VoxelMap::clear() {
  hash_->clear();
}

}  // namespace sgdicp
