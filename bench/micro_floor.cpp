// The floor of one default registration (issue 53; docs/performance.md, "Time budget per
// stage"): one O(n) pass that bins the thinned reference into a hash of voxels, plus the
// nearest-neighbour queries the run makes, answered from the 27 voxels around each query; and
// for comparison the same queries answered by the project's indexes. The queries are the run's
// own: the default run of each pair is made once with its trace, and its mini-batches are drawn
// again by the same sampler and seed and moved by the pose each iteration started from, each
// with the d_max of its iteration; then the final statistics' sample at the final pose.
//   floor/bin/D                 the hash built over the thinned reference (cell = its voxel)
//   floor/hash_queries/D        the run's queries, 27 voxels each, within min(d_max, cell)
//   floor/tree_queries/D        the same queries in the run's KD-tree, within the run's d_max
//   floor/tree_queries_in_cell/D  ... within min(d_max, cell), as the hash
//   floor/voxel_hash/D/cell:K   ReferenceIndex::with_voxel_hash (cell K x the voxel) built ...
//   floor/voxel_hash_queries/D/cell:K  ... and queried within the run's d_max
// The tree's build is budget/tree (micro_stage_budget.cpp). The run itself pays less than
// tree_queries for its queries: from the second epoch on, NearestMemory certifies many of them
// without the tree.
//   build-bench/bench/sgdicp_micro_floor --benchmark_repetitions=15
//     --benchmark_enable_random_interleaving=true --benchmark_format=json > floor.json
#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include <sgdicp/solver/sampler.hpp>

#include "budget_run.hpp"

namespace {

using sgdicp::Neighbor;
using sgdicp::ReferenceIndex;
using sgdicp::bench::Dataset;
using sgdicp::bench::default_run;

// The simplest honest voxel hash: the points sorted by cell into one array (a counting sort: one
// hashing pass, one scatter), an open-addressing table from a cell's packed index to its range.
// O(n): no sort, no tree; the scatter is the price of contiguous cells for the queries.
class FlatVoxelHash {
 public:
  FlatVoxelHash(const std::vector<Eigen::Vector3f>& points, float cell_m)
      : inverse_cell_(1.0F / cell_m) {
    const std::size_t capacity = std::bit_ceil(2 * points.size() + 2);
    mask_ = capacity - 1;
    shift_ = 64 - std::countr_zero(capacity);
    slots_.assign(capacity, Slot{kEmpty, 0, 0});
    std::vector<Slot*> slot_of(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      const std::uint64_t key = key_of(points[i]);
      Slot& slot = find(key);
      slot.key = key;
      ++slot.count;
      slot_of[i] = &slot;
    }
    // Each cell's range in the sorted array, in the order of the table.
    std::uint32_t begin = 0;
    for (Slot& slot : slots_) {
      if (slot.key == kEmpty) continue;
      slot.begin = begin;
      begin += slot.count;
      slot.count = 0;
      ++cells_;
    }
    points_.resize(points.size());
    indices_.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      const std::uint32_t at = slot_of[i]->begin + slot_of[i]->count++;
      points_[at] = points[i];
      indices_[at] = static_cast<std::uint32_t>(i);
    }
  }

  // The nearest point within sqrt(max_sq) among the 27 cells around the query's: exact for an
  // answer within one cell; a farther one may be missed. The query's own cell first; a
  // neighbour whose box lies farther than the best so far is not looked up.
  [[nodiscard]] std::optional<Neighbor> nearest(const Eigen::Vector3f& q, float max_sq) const {
    const auto c = cell_of(q);
    const float cell_m = 1.0F / inverse_cell_;
    // Per axis, the squared distance from q to the box of the neighbour at -1, 0, +1.
    std::array<std::array<float, 3>, 3> gap_sq{};
    for (int a = 0; a < 3; ++a) {
      const float below = (q[a] * inverse_cell_ - static_cast<float>(c[a])) * cell_m;
      const float above = cell_m - below;
      gap_sq[a] = {below * below, 0.0F, above * above};
    }
    float best = max_sq;
    std::uint32_t best_index = kNone;
    const auto scan = [&](int dx, int dy, int dz) {
      const Slot& slot = find(pack(c[0] + dx, c[1] + dy, c[2] + dz));
      if (slot.key == kEmpty) return;
      for (std::uint32_t k = slot.begin; k < slot.begin + slot.count; ++k) {
        const float d = (points_[k] - q).squaredNorm();
        if (d < best) {
          best = d;
          best_index = indices_[k];
        }
      }
    };
    scan(0, 0, 0);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          if (gap_sq[0][dx + 1] + gap_sq[1][dy + 1] + gap_sq[2][dz + 1] >= best) continue;
          scan(dx, dy, dz);
        }
      }
    }
    if (best_index == kNone) return std::nullopt;
    return Neighbor{best_index, best};
  }

  [[nodiscard]] std::size_t cells() const { return cells_; }

 private:
  // 16 bytes: a cell's key and its range of points_, found with one look-up.
  struct Slot {
    std::uint64_t key;
    std::uint32_t begin;
    std::uint32_t count;
  };
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  static constexpr std::int64_t kOffset = std::int64_t{1} << 20;  // 21 bits per axis

  [[nodiscard]] std::array<std::int64_t, 3> cell_of(const Eigen::Vector3f& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x() * inverse_cell_)),
            static_cast<std::int64_t>(std::floor(p.y() * inverse_cell_)),
            static_cast<std::int64_t>(std::floor(p.z() * inverse_cell_))};
  }
  static std::uint64_t pack(std::int64_t x, std::int64_t y, std::int64_t z) {
    const auto field = [](std::int64_t v) {
      return static_cast<std::uint64_t>(v + kOffset) & ((std::uint64_t{1} << 21) - 1);
    };
    return field(x) << 42 | field(y) << 21 | field(z);
  }
  [[nodiscard]] std::uint64_t key_of(const Eigen::Vector3f& p) const {
    const auto c = cell_of(p);
    return pack(c[0], c[1], c[2]);
  }
  // Linear probing from a multiplicative hash: the slot of `key`, or the empty one it would take.
  [[nodiscard]] const Slot& find(std::uint64_t key) const {
    std::size_t i = (key * 0x9E3779B97F4A7C15ULL) >> shift_;
    while (slots_[i].key != key && slots_[i].key != kEmpty) i = (i + 1) & mask_;
    return slots_[i];
  }
  Slot& find(std::uint64_t key) {
    return const_cast<Slot&>(static_cast<const FlatVoxelHash*>(this)->find(key));
  }

  float inverse_cell_;
  std::size_t mask_ = 0;
  int shift_ = 0;  // the multiplicative hash's top bits index the table
  std::vector<Slot> slots_;
  std::size_t cells_ = 0;
  std::vector<Eigen::Vector3f> points_;
  std::vector<std::uint32_t> indices_;  // into the reference cloud
};

struct Query {
  Eigen::Vector3f point_m;
  float max_sq_m2;
};

// The run's queries: its mini-batches again (same sampler, seed and m), each point moved by the
// pose its iteration started from, within that iteration's d_max; then the final statistics'
// sample (golden-ratio spread, as evaluation.cpp) at the final pose and d_max.
const std::vector<Query>& run_queries(const Dataset& ds) {
  static std::map<std::string, std::vector<Query>> cache;
  auto& out = cache[ds.name];
  if (!out.empty()) return out;
  const auto& run = default_run(ds);
  const auto& source = run.thinned_source.points;
  const auto n = static_cast<std::uint32_t>(source.size());
  const std::size_t m = sgdicp::batch_size_for(run.settings, n);
  sgdicp::EpochSampler sampler(n, run.settings.sampling.seed);
  std::vector<std::uint32_t> batch;
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  const auto moved = [&](const Eigen::Vector3f& p) {
    return (T.topLeftCorner<3, 3>() * p.cast<double>() + T.topRightCorner<3, 1>()).cast<float>();
  };
  for (const auto& entry : run.result.trace) {
    sampler.next_batch(m, batch);
    const auto d = static_cast<float>(entry.max_distance_m);
    for (const std::uint32_t i : batch) out.push_back({moved(source[i]), d * d});
    T = entry.T_reference_source;
  }
  T = run.result.T_reference_source;
  const auto d = static_cast<float>(run.result.final_max_distance_m);
  const std::size_t samples = run.result.evaluated_points;
  for (std::size_t k = 0; k < samples; ++k) {
    const double phase = std::fmod(static_cast<double>(k) * 0.6180339887498949, 1.0);
    const std::size_t i =
        samples >= n ? k : std::min<std::size_t>(n - 1, static_cast<std::size_t>(phase * n));
    out.push_back({moved(source[i]), d * d});
  }
  return out;
}

void query_counters(benchmark::State& state, const Dataset& ds, std::size_t found) {
  const auto& run = default_run(ds);
  const auto queries = static_cast<double>(run_queries(ds).size());
  state.counters["queries"] = queries;
  state.counters["points_processed"] = static_cast<double>(run.result.points_processed);
  state.counters["found"] = static_cast<double>(found) / queries;
  state.counters["ns_per_query"] = benchmark::Counter(
      queries, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void bin(benchmark::State& state, const Dataset& ds) {
  const auto& run = default_run(ds);
  std::size_t cells = 0;
  for (auto _ : state) {
    const FlatVoxelHash hash(run.index->cloud().points, static_cast<float>(run.voxel_m));
    cells = hash.cells();
    benchmark::DoNotOptimize(cells);
  }
  state.counters["points"] = static_cast<double>(run.index->size());
  state.counters["cells"] = static_cast<double>(cells);
}

void hash_queries(benchmark::State& state, const Dataset& ds) {
  const auto& run = default_run(ds);
  const auto cell = static_cast<float>(run.voxel_m);
  const FlatVoxelHash hash(run.index->cloud().points, cell);
  const auto& queries = run_queries(ds);
  std::size_t found = 0;
  for (auto _ : state) {
    found = 0;
    for (const Query& q : queries) {
      found += hash.nearest(q.point_m, std::min(q.max_sq_m2, cell * cell)).has_value();
    }
    benchmark::DoNotOptimize(found);
  }
  query_counters(state, ds, found);
  // How often the hash's answer is the tree's (both within the run's d_max), overall and where
  // the tree's answer lies within one cell (there the 27 voxels must hold it: a check).
  std::size_t same = 0;
  std::size_t near = 0;
  std::size_t near_same = 0;
  for (const Query& q : queries) {
    const auto a = hash.nearest(q.point_m, q.max_sq_m2);
    const auto b = run.index->nearest(q.point_m, q.max_sq_m2);
    // The tree sums the squares in another order: equal up to rounding.
    const bool agree = a.has_value() == b.has_value() &&
                       (!a || std::abs(a->squared_distance - b->squared_distance) <=
                                  1e-5F * b->squared_distance + 1e-12F);
    same += agree;
    if (b && b->squared_distance <= cell * cell) {
      ++near;
      near_same += agree;
    }
  }
  const auto n = static_cast<double>(queries.size());
  state.counters["same_as_tree"] = static_cast<double>(same) / n;
  state.counters["tree_within_cell"] = static_cast<double>(near) / n;
  state.counters["same_within_cell"] =
      near == 0 ? 1.0 : static_cast<double>(near_same) / static_cast<double>(near);
}

// The run's queries in one of the project's indexes, within the run's d_max or, as the hash,
// within min(d_max, cell).
void index_queries(benchmark::State& state, const Dataset& ds, const ReferenceIndex& index,
                   bool within_cell = false) {
  const auto& queries = run_queries(ds);
  const auto cell = static_cast<float>(default_run(ds).voxel_m);
  const float cap_sq = within_cell ? cell * cell : std::numeric_limits<float>::max();
  std::size_t found = 0;
  for (auto _ : state) {
    found = 0;
    for (const Query& q : queries) {
      found += index.nearest(q.point_m, std::min(q.max_sq_m2, cap_sq)).has_value();
    }
    benchmark::DoNotOptimize(found);
  }
  query_counters(state, ds, found);
}

void tree_queries(benchmark::State& state, const Dataset& ds, bool within_cell) {
  index_queries(state, ds, *default_run(ds).index, within_cell);
}

double cell_of(const benchmark::State& state, const Dataset& ds) {
  return static_cast<double>(state.range(0)) * default_run(ds).voxel_m;
}

void voxel_hash(benchmark::State& state, const Dataset& ds) {
  const auto& run = default_run(ds);
  for (auto _ : state) {
    sgdicp::PointCloud copy = run.index->cloud();
    const auto t0 = std::chrono::steady_clock::now();
    const auto index = ReferenceIndex::with_voxel_hash(std::move(copy), cell_of(state, ds));
    benchmark::DoNotOptimize(&index);
    state.SetIterationTime(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
}

void voxel_hash_queries(benchmark::State& state, const Dataset& ds) {
  const auto index =
      ReferenceIndex::with_voxel_hash(default_run(ds).index->cloud(), cell_of(state, ds));
  index_queries(state, ds, index);
}

}  // namespace

int main(int argc, char** argv) {
  for (const Dataset& ds : sgdicp::bench::budget_datasets()) {
    const auto add = [&](const std::string& what, auto&& fn) {
      return benchmark::RegisterBenchmark(("floor/" + what + "/" + ds.name).c_str(),
                                          std::forward<decltype(fn)>(fn))
          ->Unit(benchmark::kMillisecond)
          ->MinTime(0.3);
    };
    add("bin", [ds](benchmark::State& s) { bin(s, ds); });
    add("hash_queries", [ds](benchmark::State& s) { hash_queries(s, ds); });
    add("tree_queries", [ds](benchmark::State& s) { tree_queries(s, ds, false); });
    add("tree_queries_in_cell", [ds](benchmark::State& s) { tree_queries(s, ds, true); });
    add("voxel_hash", [ds](benchmark::State& s) { voxel_hash(s, ds); })
        ->UseManualTime()
        ->ArgName("cell")
        ->Arg(1)
        ->Arg(2);
    add("voxel_hash_queries", [ds](benchmark::State& s) { voxel_hash_queries(s, ds); })
        ->ArgName("cell")
        ->Arg(1)
        ->Arg(2);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
