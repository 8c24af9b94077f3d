#include "sgdicp/odometry/whole_map.hpp"

#include <cmath>
#include <vector>

#include "points/voxel_table.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/core/format_number.hpp"

namespace sgdicp {

// The voxel grids' own table (first-seen slots, open addressing) and their centroid sums: a voxel
// costs its table entry and 32 bytes of sums, in double so that a voxel that thousands of frames
// fall into keeps its centroid to the float's resolution.
struct WholeMap::Voxels {
  detail::VoxelSlots slots{1024};
  std::vector<detail::Centroid> centroids;

  // The voxel of a point (map frame, metres), or none for a point that is no place.
  [[nodiscard]] static bool key_of(const Eigen::Vector3d& p, double inverse_size,
                                   detail::VoxelKey& key) {
    if (!(p.cwiseAbs().maxCoeff() <= kLargestCoordinate_m)) return false;  // NaN too
    const Eigen::Vector3d q = (p * inverse_size).array().floor();
    if (!(q.cwiseAbs().maxCoeff() < detail::kMaxVoxelIndex)) return false;
    key = {static_cast<std::int64_t>(q.x()), static_cast<std::int64_t>(q.y()),
           static_cast<std::int64_t>(q.z())};
    return true;
  }

  void add(const Eigen::Vector3d& p, double weight, const Eigen::Vector3d& weighted_sum,
           double inverse_size) {
    detail::VoxelKey key;
    if (!key_of(p, inverse_size, key)) return;
    const std::size_t slot = slots.slot(key);
    if (slot == centroids.size()) centroids.emplace_back();
    centroids[slot].sum += weighted_sum;
    centroids[slot].count += weight;
  }
};

WholeMap::WholeMap(double voxel_size_m)
    : voxel_size_m_(voxel_size_m), voxels_(std::make_unique<Voxels>()) {
  if (!std::isfinite(voxel_size_m) || voxel_size_m <= 0.0) {
    throw InvalidSettingsError("whole map: voxel size must be positive and finite, got " +
                               format_number(voxel_size_m) + " m");
  }
}

WholeMap::~WholeMap() = default;
WholeMap::WholeMap(const WholeMap& other)
    : voxel_size_m_(other.voxel_size_m_), voxels_(std::make_unique<Voxels>(*other.voxels_)) {}
WholeMap& WholeMap::operator=(const WholeMap& other) {
  if (this != &other) {
    voxel_size_m_ = other.voxel_size_m_;
    voxels_ = std::make_unique<Voxels>(*other.voxels_);
  }
  return *this;
}
WholeMap::WholeMap(WholeMap&&) noexcept = default;
WholeMap& WholeMap::operator=(WholeMap&&) noexcept = default;

void WholeMap::add(const PointCloud& frame, const Eigen::Matrix4d& T_map_frame) {
  const Eigen::Matrix3d R = T_map_frame.topLeftCorner<3, 3>();
  const Eigen::Vector3d t = T_map_frame.topRightCorner<3, 1>() + R * frame.origin_m;
  const double inverse_size = 1.0 / voxel_size_m_;
  for (const Eigen::Vector3f& point : frame.points) {
    const Eigen::Vector3d p = R * point.cast<double>() + t;
    voxels_->add(p, 1.0, p, inverse_size);
  }
}

void WholeMap::regrid(double voxel_size_m) {
  if (!std::isfinite(voxel_size_m) || voxel_size_m < voxel_size_m_) {
    throw InvalidSettingsError("whole map: regridded to " + format_number(voxel_size_m) +
                               " m, finer than its " + format_number(voxel_size_m_) +
                               " m (only a coarser grid can be made of its centroids)");
  }
  Voxels coarser;
  const double inverse_size = 1.0 / voxel_size_m;
  for (const detail::Centroid& c : voxels_->centroids) {
    coarser.add(c.sum / c.count, c.count, c.sum, inverse_size);
  }
  *voxels_ = std::move(coarser);
  voxel_size_m_ = voxel_size_m;
}

PointCloud WholeMap::cloud() const {
  PointCloud out;
  const auto& centroids = voxels_->centroids;
  if (centroids.empty()) return out;
  out.origin_m = georeferencing_origin(centroids.front().sum / centroids.front().count);
  out.points.reserve(centroids.size());
  for (const detail::Centroid& c : centroids) {
    out.points.push_back((c.sum / c.count - out.origin_m).cast<float>());
  }
  return out;
}

std::size_t WholeMap::size() const noexcept {
  return voxels_->centroids.size();
}

std::size_t WholeMap::memory_bytes() const noexcept {
  return voxels_->slots.bytes() + voxels_->centroids.capacity() * sizeof(detail::Centroid);
}

}  // namespace sgdicp
