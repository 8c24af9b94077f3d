#include "sgdicp/nearest_neighbor.hpp"

#include <algorithm>
#include <mutex>
#include <string>

#include <nanoflann.hpp>

#include "sgdicp/error.hpp"
#include "sgdicp/preprocessing.hpp"

namespace sgdicp {
namespace {

// nanoflann's dataset adaptor over our cloud.
struct CloudAdaptor {
  const std::vector<Eigen::Vector3f>* points;
  const BoundingBox* box;
  [[nodiscard]] std::size_t kdtree_get_point_count() const { return points->size(); }
  [[nodiscard]] float kdtree_get_pt(std::size_t i, std::size_t dim) const {
    return (*points)[i][static_cast<Eigen::Index>(dim)];
  }
  // We keep the box anyway (scaling), so nanoflann need not make its own pass over the cloud.
  // The corners are coordinates of float points, so the conversion back is exact.
  template <class Box>
  bool kdtree_get_bbox(Box& bb) const {
    for (Eigen::Index d = 0; d < 3; ++d) {
      bb[static_cast<std::size_t>(d)].low = static_cast<float>(box->min[d]);
      bb[static_cast<std::size_t>(d)].high = static_cast<float>(box->max[d]);
    }
    return true;
  }
};

using KdTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, CloudAdaptor>,
                                        CloudAdaptor, 3, std::uint32_t>;

// A single-nearest result set whose initial radius is the rejection distance, so branches
// farther than d_max are never visited.
class NearestWithin {
 public:
  using DistanceType = float;
  using IndexType = std::uint32_t;
  using CountType = std::size_t;

  explicit NearestWithin(float max_squared_distance) : best_(max_squared_distance) {}
  [[nodiscard]] std::size_t size() const { return found_ ? 1 : 0; }
  [[nodiscard]] bool full() const { return found_; }
  bool addPoint(float dist, std::uint32_t index) {
    if (dist < best_) {
      best_ = dist;
      index_ = index;
      found_ = true;
    }
    return true;
  }
  [[nodiscard]] float worstDist() const { return best_; }
  [[nodiscard]] bool found() const { return found_; }
  [[nodiscard]] std::uint32_t index() const { return index_; }

 private:
  float best_;
  std::uint32_t index_ = 0;
  bool found_ = false;
};

}  // namespace

struct ReferenceIndex::Impl {
  PointCloud cloud;
  BoundingBox box;
  CloudAdaptor adaptor;
  KdTree tree;
  // The bulk box, for the registrations that scale robustly: once, on first use, from any thread.
  std::once_flag bulk_once;
  ScalingBox bulk;

  Impl(PointCloud reference, const KdTreeSettings& settings)
      : cloud(std::move(reference)),
        box(BoundingBox::of(cloud)),
        adaptor{&cloud.points, &box},
        tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(settings.leaf_size)) {}
};

namespace {
PointCloud checked_reference(PointCloud reference) {
  if (reference.empty()) throw InvalidInputError("reference cloud is empty");
  if (reference.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw InvalidInputError("reference cloud has more than 2^32-1 points");
  }
  for (std::size_t i = 0; i < reference.size(); ++i) {
    if (!reference.points[i].allFinite()) {
      throw InvalidInputError("reference cloud has a non-finite point at index " +
                              std::to_string(i));
    }
  }
  return reference;
}
}  // namespace

ReferenceIndex::ReferenceIndex(PointCloud reference, const KdTreeSettings& settings) {
  if (settings.leaf_size == 0) throw InvalidSettingsError("kd-tree leaf size must be at least 1");
  impl_ = std::make_unique<Impl>(checked_reference(std::move(reference)), settings);
}

ReferenceIndex::~ReferenceIndex() = default;
ReferenceIndex::ReferenceIndex(ReferenceIndex&&) noexcept = default;
ReferenceIndex& ReferenceIndex::operator=(ReferenceIndex&&) noexcept = default;

const PointCloud& ReferenceIndex::cloud() const noexcept {
  return impl_->cloud;
}
const BoundingBox& ReferenceIndex::bounding_box() const noexcept {
  return impl_->box;
}

const ScalingBox& ReferenceIndex::bulk_bounding_box() const {
  std::call_once(impl_->bulk_once,
                 [this] { impl_->bulk = sgdicp::bulk_bounding_box(impl_->cloud); });
  return impl_->bulk;
}

std::optional<Neighbor> ReferenceIndex::nearest(const Eigen::Vector3f& query,
                                                float max_squared_distance) const {
  NearestWithin result(max_squared_distance);
  impl_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  if (!result.found()) return std::nullopt;
  return Neighbor{result.index(), result.worstDist()};
}

void ReferenceIndex::set_normals_and_covariances(std::vector<Eigen::Vector3f> normals,
                                                 std::vector<Eigen::Matrix3f> covariances) {
  const std::size_t n = size();
  if ((!normals.empty() && normals.size() != n) ||
      (!covariances.empty() && covariances.size() != n)) {
    throw InvalidInputError("the reference has " + std::to_string(n) + " points but " +
                            std::to_string(normals.size()) + " normals and " +
                            std::to_string(covariances.size()) + " covariances were given");
  }
  impl_->cloud.normals = std::move(normals);
  impl_->cloud.covariances = std::move(covariances);
}

void ReferenceIndex::k_nearest(const Eigen::Vector3f& query, std::size_t k,
                               std::vector<Neighbor>& neighbors) const {
  neighbors.clear();
  k = std::min(k, size());
  if (k == 0) return;
  // Thread-local scratch: k-nearest queries run from many threads during normal estimation.
  thread_local std::vector<std::uint32_t> indices;
  thread_local std::vector<float> distances;
  indices.resize(k);
  distances.resize(k);
  nanoflann::KNNResultSet<float, std::uint32_t> result(k);
  result.init(indices.data(), distances.data());
  impl_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  for (std::size_t i = 0; i < result.size(); ++i) neighbors.push_back({indices[i], distances[i]});
}

}  // namespace sgdicp
