// Micro-benchmarks of the registrations' voxel grid (issue 13): choosing
// the size that keeps 20,000 points (voxel_size_for_count), thinning a cloud on it
// (voxel_downsample), with its surfaces from the voxel blocks or from k nearest centroids, and
// the whole reference preparation of the default (reference_index_for: size, thinning, KD-tree)
// per dataset, with the points kept and the time per input point.
//   build/.../sgdicp_micro_voxel_grid [--benchmark_repetitions=5 --benchmark_format=json ...]
#include <algorithm>
#include <vector>

#include <benchmark/benchmark.h>

#include <sgdicp/points/voxel_grid.hpp>
#include <sgdicp/registration/registration.hpp>
#include <sgdicp/surfaces/voxel_surfaces.hpp>

#include "bench_data.hpp"

namespace {

using sgdicp::PointCloud;

constexpr std::size_t kTarget = 20000;  // SgdSettings{}.downsampling.downsample_to

void per_input_point(benchmark::State& state, const PointCloud& cloud) {
  state.counters["points"] = static_cast<double>(cloud.size());
  state.counters["ns_per_point"] = benchmark::Counter(
      static_cast<double>(cloud.size()),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void size_search(benchmark::State& state, const sgdicp::bench::Dataset& ds) {
  const PointCloud& cloud = sgdicp::bench::cloud(ds.reference);
  double size = 0.0;
  for (auto _ : state) {
    size = sgdicp::voxel_size_for_count(cloud, kTarget);
    benchmark::DoNotOptimize(size);
  }
  per_input_point(state, cloud);
  state.counters["voxel_m"] = size;
}

// The voxel size that keeps kTarget points, or 0 with the benchmark skipped when the cloud is
// smaller than that.
double grid_or_skip(benchmark::State& state, const PointCloud& cloud) {
  const double size = sgdicp::voxel_size_for_count(cloud, kTarget);
  if (size <= 0.0) state.SkipWithError("cloud smaller than the target: nothing to thin");
  return size;
}

// Surfaces estimated on one thread, as a registration with the default num_threads = 1.
const sgdicp::NeighborhoodSettings kOneThread = [] {
  sgdicp::NeighborhoodSettings s;
  s.num_threads = 1;
  return s;
}();

void thinning(benchmark::State& state, const sgdicp::bench::Dataset& ds) {
  const PointCloud& cloud = sgdicp::bench::cloud(ds.reference);
  const double size = grid_or_skip(state, cloud);
  if (size <= 0.0) return;
  std::size_t kept = 0;
  for (auto _ : state) {
    const PointCloud thinned = sgdicp::voxel_downsample(cloud, size);
    kept = thinned.size();
    benchmark::DoNotOptimize(kept);
  }
  per_input_point(state, cloud);
  state.counters["kept"] = static_cast<double>(kept);
}

// The grid's centroids with their surfaces, two ways: from the voxel blocks
// (voxel_downsample_with_surfaces) or from the k nearest centroids (estimate_normals over them;
// about twice the blocks' time on KITTI scans and Kinect frames).
void thinning_with_block_surfaces(benchmark::State& state, const sgdicp::bench::Dataset& ds) {
  const PointCloud& cloud = sgdicp::bench::cloud(ds.reference);
  const double size = grid_or_skip(state, cloud);
  if (size <= 0.0) return;
  for (auto _ : state) {
    const PointCloud thinned = sgdicp::voxel_downsample_with_surfaces(cloud, size, kOneThread);
    benchmark::DoNotOptimize(thinned.normals.data());
  }
  per_input_point(state, cloud);
}

void thinning_with_nearest_normals(benchmark::State& state, const sgdicp::bench::Dataset& ds) {
  const PointCloud& cloud = sgdicp::bench::cloud(ds.reference);
  const double size = grid_or_skip(state, cloud);
  if (size <= 0.0) return;
  for (auto _ : state) {
    PointCloud thinned = sgdicp::voxel_downsample(cloud, size);
    sgdicp::estimate_normals(thinned, kOneThread);
    benchmark::DoNotOptimize(thinned.normals.data());
  }
  per_input_point(state, cloud);
}

// What a registration with the defaults spends on its reference before the first mini-batch.
void reference_preparation(benchmark::State& state, const sgdicp::bench::Dataset& ds) {
  const PointCloud& cloud = sgdicp::bench::cloud(ds.reference);
  const sgdicp::SgdSettings settings;
  std::size_t kept = 0;
  for (auto _ : state) {
    const sgdicp::ReferenceIndex index = sgdicp::reference_index_for(cloud, settings);
    kept = index.size();
    benchmark::DoNotOptimize(kept);
  }
  per_input_point(state, cloud);
  state.counters["kept"] = static_cast<double>(kept);
}

// The fastest repetition: on a shared, noisy machine the best estimate of the intrinsic cost.
double min_of(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
}

}  // namespace

int main(int argc, char** argv) {
  for (const auto& ds : sgdicp::bench::available_datasets()) {
    for (const auto& [name, function] :
         {std::pair{"voxel_size_for_count/", &size_search},
          std::pair{"voxel_downsample/", &thinning},
          std::pair{"voxel_downsample_with_surfaces/", &thinning_with_block_surfaces},
          std::pair{"voxel_downsample+estimate_normals/", &thinning_with_nearest_normals},
          std::pair{"reference_index_for/", &reference_preparation}}) {
      benchmark::RegisterBenchmark((name + ds.name).c_str(), function, ds)
          ->ComputeStatistics("min", min_of)
          ->Unit(benchmark::kMillisecond);
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
