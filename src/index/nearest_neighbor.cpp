#include "sgdicp/index/nearest_neighbor.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <nanoflann.hpp>

#include "index/voxel_hash.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/core/format_number.hpp"
#include "sgdicp/core/threads.hpp"
#include "sgdicp/points/voxel_grid.hpp"

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

// Every point closer than a radius, unordered: the search prunes at the radius from the start
// (a k-nearest set prunes only once it holds k points, and keeps them sorted as it goes).
class AllWithin {
 public:
  using DistanceType = float;
  using IndexType = std::uint32_t;
  using CountType = std::size_t;

  AllWithin(float squared_radius, std::vector<Neighbor>& found)
      : radius2_(squared_radius), found_(found) {}
  [[nodiscard]] std::size_t size() const { return found_.size(); }
  [[nodiscard]] bool full() const { return true; }
  bool addPoint(float dist, std::uint32_t index) {
    if (dist < radius2_) found_.push_back({index, dist});
    return true;
  }
  [[nodiscard]] float worstDist() const { return radius2_; }

 private:
  float radius2_;
  std::vector<Neighbor>& found_;
};

// The nearest and second-nearest within the rejection distance. The nearest is NearestWithin's:
// the tree is walked in the same order, so the first point at the least distance wins in both.
class TwoNearestWithin {
 public:
  using DistanceType = float;
  using IndexType = std::uint32_t;
  using CountType = std::size_t;

  explicit TwoNearestWithin(float max_squared_distance)
      : best_(max_squared_distance), second_(max_squared_distance) {}
  [[nodiscard]] std::size_t size() const { return found_ ? 1 : 0; }
  [[nodiscard]] bool full() const { return found_; }
  bool addPoint(float dist, std::uint32_t index) {
    if (dist < best_) {
      second_ = best_;
      best_ = dist;
      index_ = index;
      found_ = true;
    } else if (dist < second_) {
      second_ = dist;
    }
    return true;
  }
  [[nodiscard]] float worstDist() const { return second_; }
  [[nodiscard]] float best() const { return best_; }
  [[nodiscard]] bool found() const { return found_; }
  [[nodiscard]] std::uint32_t index() const { return index_; }

 private:
  float best_;
  float second_;
  std::uint32_t index_ = 0;
  bool found_ = false;
};

// nanoflann 1.4 builds its tree on one thread. Below its top splits the subtrees cover disjoint
// ranges of the index array, so they can be built at once, each on a thread of its own, into the
// node pool of a helper tree (nanoflann's pool is not thread-safe) that works on a copy of the
// index array and hands its range back. The splits are nanoflann's own (middleSplit_), made in
// the same order on the same data, and the epilogue is divideTree's: the tree is the one
// buildIndex() makes, node for node (test: ReferenceIndex.ThreadedBuildGivesTheSameTree).
class ThreadedBuild {
 public:
  using Node = KdTree::Node;
  using Box = KdTree::BoundingBox;
  using Offset = KdTree::Offset;

  ThreadedBuild(KdTree& tree, const CloudAdaptor& adaptor, std::size_t leaf_size)
      : tree_(tree), adaptor_(adaptor), leaf_size_(leaf_size) {}

  // buildIndex() with the subtrees below `levels` top splits built on `threads` threads; the
  // helper trees that own their nodes go into `pools`, which must outlive the tree.
  void run(std::size_t levels, std::size_t threads, std::vector<std::unique_ptr<KdTree>>& pools) {
    tree_.m_size = adaptor_.kdtree_get_point_count();
    tree_.init_vind();
    tree_.freeIndex(tree_);
    tree_.m_size_at_index_build = tree_.m_size;
    tree_.computeBoundingBox(tree_.root_bbox);
    Part root(0, tree_.m_size, tree_.root_bbox);
    std::vector<Part*> subtrees;
    split(root, levels, subtrees);
    build(subtrees, threads);
    for (Part* part : subtrees) {
      std::copy(part->pool->vAcc.begin() + static_cast<std::ptrdiff_t>(part->left),
                part->pool->vAcc.begin() + static_cast<std::ptrdiff_t>(part->right),
                tree_.vAcc.begin() + static_cast<std::ptrdiff_t>(part->left));
      pools.push_back(std::move(part->pool));
    }
    finish(root);
    tree_.root_node = root.node;
    tree_.root_bbox = root.box;
  }

 private:
  // A node of the top levels (with children) or a subtree below them (with a helper pool).
  struct Part {
    Part(Offset first, Offset last, const Box& cell) : left(first), right(last), box(cell) {}
    Offset left, right;
    Box box;  // in: the cell of the split; out: the tight box of the points (divideTree's)
    Node* node = nullptr;
    std::unique_ptr<Part> child1, child2;
    std::unique_ptr<KdTree> pool;
  };

  // divideTree's prologue for the top levels: the split, without descending.
  void split(Part& part, std::size_t levels, std::vector<Part*>& subtrees) {
    if (levels == 0 || part.right - part.left <= leaf_size_) {
      subtrees.push_back(&part);
      return;
    }
    part.node = tree_.pool.template allocate<Node>();
    Offset idx = 0;
    int cutfeat = 0;
    float cutval = 0.0F;
    tree_.middleSplit_(tree_, part.left, part.right - part.left, idx, cutfeat, cutval, part.box);
    part.node->node_type.sub.divfeat = cutfeat;
    part.child1 = std::make_unique<Part>(part.left, part.left + idx, part.box);
    part.child1->box[static_cast<std::size_t>(cutfeat)].high = cutval;
    part.child2 = std::make_unique<Part>(part.left + idx, part.right, part.box);
    part.child2->box[static_cast<std::size_t>(cutfeat)].low = cutval;
    split(*part.child1, levels - 1, subtrees);
    split(*part.child2, levels - 1, subtrees);
  }

  // The subtrees, largest first, each on the least loaded of `threads` threads (the caller's is
  // the first).
  void build(std::vector<Part*> subtrees, std::size_t threads) {
    std::sort(subtrees.begin(), subtrees.end(),
              [](const Part* a, const Part* b) { return a->right - a->left > b->right - b->left; });
    std::vector<std::vector<Part*>> work(threads);
    std::vector<Offset> load(threads, 0);
    for (Part* part : subtrees) {
      const auto t =
          static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
      work[t].push_back(part);
      load[t] += part->right - part->left;
    }
    const auto build_all = [this](const std::vector<Part*>& parts) {
      for (Part* part : parts) build_subtree(*part);
    };
    {
      std::vector<std::jthread> workers;
      for (std::size_t t = 1; t < threads; ++t) workers.emplace_back(build_all, work[t]);
      build_all(work[0]);
    }
  }

  void build_subtree(Part& part) const {
    part.pool = std::make_unique<KdTree>(
        3, adaptor_,
        nanoflann::KDTreeSingleIndexAdaptorParams(
            leaf_size_, nanoflann::KDTreeSingleIndexAdaptorFlags::SkipInitialBuildIndex));
    part.pool->vAcc = tree_.vAcc;  // read-only for every thread until all have joined
    part.node = part.pool->divideTree(*part.pool, part.left, part.right, part.box);
  }

  // divideTree's epilogue for the top levels, once their subtrees exist.
  static void finish(Part& part) {
    if (!part.child1) return;
    finish(*part.child1);
    finish(*part.child2);
    Node& node = *part.node;
    node.child1 = part.child1->node;
    node.child2 = part.child2->node;
    const auto cutfeat = static_cast<std::size_t>(node.node_type.sub.divfeat);
    node.node_type.sub.divlow = part.child1->box[cutfeat].high;
    node.node_type.sub.divhigh = part.child2->box[cutfeat].low;
    for (std::size_t i = 0; i < 3; ++i) {
      part.box[i].low = std::min(part.child1->box[i].low, part.child2->box[i].low);
      part.box[i].high = std::max(part.child1->box[i].high, part.child2->box[i].high);
    }
  }

  KdTree& tree_;
  const CloudAdaptor& adaptor_;
  std::size_t leaf_size_;
};

// Fewer points than this per thread do not repay a thread start (~50 microseconds).
constexpr std::size_t kMinPointsPerBuildThread = 16384;

std::size_t build_threads(std::size_t requested, std::size_t points) {
  return std::clamp<std::size_t>(points / kMinPointsPerBuildThread, 1,
                                 resolve_thread_count(requested));
}

}  // namespace

struct ReferenceIndex::Impl {
  PointCloud cloud;  // the tree's (a voxel hash holds its own)
  BoundingBox box;
  CloudAdaptor adaptor;
  std::optional<KdTree> tree;                          // one backend or the other
  std::vector<std::unique_ptr<KdTree>> subtree_pools;  // nodes of a threaded build
  std::optional<detail::VoxelHash> own_hash;
  const detail::VoxelHash* hash = nullptr;  // own_hash, or one viewed (an odometry map's)
  bool first_per_voxel = false;             // a coarse view: the hash's first point per voxel
  std::unique_ptr<ReferenceIndex> coarse;   // a map view's coarse view (coarse_view())
  double voxel_size_m = 0.0;
  // The bulk box, for the registrations that scale robustly: once, on first use, from any thread.
  std::once_flag bulk_once;
  ScalingBox bulk;

  Impl(PointCloud reference, const KdTreeSettings& settings)
      : cloud(std::move(reference)), box(BoundingBox::of(cloud)), adaptor{&cloud.points, &box} {
    tree.emplace(
        3, adaptor,
        nanoflann::KDTreeSingleIndexAdaptorParams(
            settings.leaf_size, nanoflann::KDTreeSingleIndexAdaptorFlags::SkipInitialBuildIndex));
    const std::size_t threads = build_threads(settings.num_threads, cloud.size());
    if (threads == 1) {
      tree->buildIndex();
      return;
    }
    // Two subtrees per thread even the load out: the middle splits are not median splits.
    const auto levels = static_cast<std::size_t>(std::bit_width(2 * threads - 1));
    ThreadedBuild(*tree, adaptor, settings.leaf_size).run(levels, threads, subtree_pools);
  }

  Impl(const PointCloud& reference, double cell_m) : own_hash(std::in_place, cell_m) {
    own_hash->add(reference);
    hash = &*own_hash;
  }

  Impl(const detail::VoxelHash& viewed, bool first_only)
      : hash(&viewed), first_per_voxel(first_only) {}

  [[nodiscard]] const PointCloud& points() const { return hash ? hash->cloud() : cloud; }
  [[nodiscard]] const BoundingBox& bounds() const { return hash ? hash->box() : box; }

  // Offers the candidates of `query` to a nanoflann result set, from either backend.
  template <class Result>
  void search(const Eigen::Vector3f& query, Result& result) const {
    if (hash) {
      hash->search(query, result, first_per_voxel);
    } else {
      tree->findNeighbors(result, query.data(), nanoflann::SearchParams());
    }
  }
};

namespace {
// Cells along an axis of a reference indexed by with_voxel_hash at most.
constexpr double kMaxVoxelHashCellsPerAxis = 0x1p21;

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
  settings.validate();
  PointCloud checked = checked_reference(std::move(reference));
  if (settings.voxel_size_m > 0.0) checked = voxel_downsample(checked, settings.voxel_size_m);
  impl_ = std::make_unique<Impl>(std::move(checked), settings);
  impl_->voxel_size_m = settings.voxel_size_m;
}

ReferenceIndex ReferenceIndex::with_voxel_hash(PointCloud reference, double cell_m) {
  if (!std::isfinite(cell_m) || cell_m <= 0.0) {
    throw InvalidSettingsError("voxel hash: cell size must be positive and finite, got " +
                               std::to_string(cell_m) + " m");
  }
  const PointCloud checked = checked_reference(std::move(reference));
  // A cell given in the wrong unit (millimetres for metres) would make a grid of billions of
  // cells a side, and the shells' cell arithmetic stays far from overflow.
  const BoundingBox box = BoundingBox::of(checked);
  if (!(((box.max - box.min) / cell_m).maxCoeff() < kMaxVoxelHashCellsPerAxis)) {
    throw InvalidSettingsError("voxel hash: cell size " + format_number(cell_m) +
                               " m is too small for a reference " +
                               format_number((box.max - box.min).maxCoeff()) +
                               " m across (more than 2^21 cells along an axis)");
  }
  ReferenceIndex index;
  index.impl_ = std::make_unique<Impl>(checked, cell_m);
  return index;
}

ReferenceIndex ReferenceIndex::viewing(const detail::VoxelHash& hash) {
  if (hash.cloud().empty()) throw InvalidInputError("reference cloud is empty");
  ReferenceIndex index;
  index.impl_ = std::make_unique<Impl>(hash, false);
  if (hash.max_points_per_voxel() > 1) {
    index.impl_->coarse.reset(new ReferenceIndex());
    index.impl_->coarse->impl_ = std::make_unique<Impl>(hash, true);
  }
  return index;
}

ReferenceIndex ReferenceIndex::on_voxel_grid(PointCloud thinned, double voxel_size_m,
                                             const KdTreeSettings& settings) {
  if (!std::isfinite(voxel_size_m) || voxel_size_m <= 0.0) {
    throw InvalidSettingsError(
        "voxel size of a thinned reference must be positive and finite, got " +
        std::to_string(voxel_size_m) + " m");
  }
  if (settings.voxel_size_m != 0.0) {
    throw InvalidSettingsError(
        "an index over a thinned reference thins it no further: "
        "settings.voxel_size_m must be 0");
  }
  ReferenceIndex index(std::move(thinned), settings);
  index.impl_->voxel_size_m = voxel_size_m;
  return index;
}

void KdTreeSettings::validate() const {
  if (leaf_size == 0) throw InvalidSettingsError("kd-tree leaf size must be at least 1");
  if (num_threads > kMaxThreads) {
    throw InvalidSettingsError("kd-tree build threads must be at most " +
                               std::to_string(kMaxThreads) + " (0 = all cores), got " +
                               std::to_string(num_threads));
  }
  if (!std::isfinite(voxel_size_m) || voxel_size_m < 0.0) {
    throw InvalidSettingsError("kd-tree voxel size must be 0 (none) or positive and finite, got " +
                               std::to_string(voxel_size_m) + " m");
  }
}

ReferenceIndex::~ReferenceIndex() = default;
ReferenceIndex::ReferenceIndex(ReferenceIndex&&) noexcept = default;
ReferenceIndex& ReferenceIndex::operator=(ReferenceIndex&&) noexcept = default;

const PointCloud& ReferenceIndex::cloud() const noexcept {
  return impl_->points();
}
double ReferenceIndex::voxel_size_m() const noexcept {
  return impl_->voxel_size_m;
}
const ReferenceIndex* ReferenceIndex::coarse_view() const noexcept {
  return impl_->coarse.get();
}

double ReferenceIndex::voxel_hash_cell_m() const noexcept {
  return impl_->hash ? impl_->hash->cell_m() : 0.0;
}
const BoundingBox& ReferenceIndex::bounding_box() const noexcept {
  return impl_->bounds();
}

const ScalingBox& ReferenceIndex::bulk_bounding_box() const {
  std::call_once(impl_->bulk_once,
                 [this] { impl_->bulk = sgdicp::bulk_bounding_box(impl_->points()); });
  return impl_->bulk;
}

std::optional<Neighbor> ReferenceIndex::nearest(const Eigen::Vector3f& query,
                                                float max_squared_distance) const {
  NearestWithin result(max_squared_distance);
  impl_->search(query, result);
  if (!result.found()) return std::nullopt;
  return Neighbor{result.index(), result.worstDist()};
}

std::optional<Neighbor> ReferenceIndex::nearest_and_bound(const Eigen::Vector3f& query,
                                                          float max_squared_distance,
                                                          float& others_squared_distance) const {
  TwoNearestWithin result(max_squared_distance);
  impl_->search(query, result);
  others_squared_distance = result.worstDist();
  if (!result.found()) return std::nullopt;
  return Neighbor{result.index(), result.best()};
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
  if (impl_->own_hash) {
    impl_->own_hash->set_surfaces(std::move(normals), std::move(covariances));
  } else if (impl_->hash) {
    throw InvalidInputError(
        "an index viewing a voxel map holds no surfaces of its own: add them with the points");
  } else {
    impl_->cloud.normals = std::move(normals);
    impl_->cloud.covariances = std::move(covariances);
  }
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
  impl_->search(query, result);
  for (std::size_t i = 0; i < result.size(); ++i) neighbors.push_back({indices[i], distances[i]});
}

void ReferenceIndex::nearest_within(const Eigen::Vector3f& query, float squared_radius,
                                    std::size_t k, std::vector<Neighbor>& neighbors) const {
  neighbors.clear();
  if (k == 0 || !(squared_radius > 0.0F)) return;
  AllWithin result(squared_radius, neighbors);
  impl_->search(query, result);
  // Closest first, ties by index: the same order whichever structure walked the points.
  const auto closer = [](const Neighbor& a, const Neighbor& b) {
    return a.squared_distance < b.squared_distance ||
           (a.squared_distance == b.squared_distance && a.index < b.index);
  };
  if (neighbors.size() > k) {
    std::nth_element(neighbors.begin(), neighbors.begin() + static_cast<std::ptrdiff_t>(k),
                     neighbors.end(), closer);
    neighbors.resize(k);
  }
  std::sort(neighbors.begin(), neighbors.end(), closer);
}

}  // namespace sgdicp
