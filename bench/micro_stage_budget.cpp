// The time budget of one default registration per stage (issue 53; docs/performance.md, "Time
// budget per stage"), on one thread, through the public API in the order reference_index_for()
// and align() run them, for a KITTI, a Kinect and a hand-held LiDAR pair:
//   budget/grid_search/D      the voxel size that keeps 20,000 reference points
//   budget/thin_reference/D   the reference's centroids on that grid
//   budget/thin_source/D      the source's centroids on it (align() thins its source)
//   budget/thin_surfaces/D    the reference's centroids with their 3x3x3 block surfaces
//                             (surfaces = this - thin_reference)
//   budget/tree/D             the KD-tree over the centroids (ReferenceIndex::on_voxel_grid)
//   budget/reference_index/D  reference_index_for() as a whole (the four above, the counting
//                             pass of the size search reused, BALM's coarser block surfaces)
//   budget/box_source/D, box_reference/D  the bulk box of each thinned cloud (the unit-cube
//                             scaling)
//   budget/align/D            align() on the built index: source thinning, boxes, SGD stages,
//                             evaluation
//   budget/align_coarse/D     the same run stopped after its coarse stage: no refinement stages,
//                             the coarse cost throughout (the same mini-batches until then)
//   budget/evaluation/D       evaluate_alignment() at the default run's pose and d_max ...
//   budget/evaluation_coarse/D  ... and at the coarse-only run's
//   budget/end_to_end/D       reference_index_for() + align(), what `sgdicp register` times
// bench/stage_budget.py turns the medians into the table (coarse stage = align_coarse -
// thin_source - source box - evaluation_coarse; refinement = align - align_coarse - evaluation
// + evaluation_coarse). The copies handed to an index are made outside the timed region.
//   build-bench/bench/sgdicp_micro_stage_budget --benchmark_repetitions=15
//     --benchmark_enable_random_interleaving=true --benchmark_format=json > budget.json
#include <chrono>
#include <string>
#include <utility>

#include <benchmark/benchmark.h>

#include <sgdicp/points/scaling.hpp>
#include <sgdicp/registration/evaluation.hpp>
#include <sgdicp/surfaces/voxel_surfaces.hpp>

#include "budget_run.hpp"

namespace {

using sgdicp::PointCloud;
using sgdicp::ReferenceIndex;
using sgdicp::RegistrationResult;
using sgdicp::SgdSettings;
using sgdicp::bench::Dataset;
using sgdicp::bench::default_run;

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The run stopped where the default one starts refining: the coarse stage's cost, and its first
// stationary window ends the run.
SgdSettings coarse_only(SgdSettings s) {
  s.refinement.stages = 0;
  s.cost = s.coarse_cost;
  return s;
}

// The iterations of the default run's coarse stage: until d_max first changes (trace).
std::size_t coarse_iterations(const RegistrationResult& r) {
  for (std::size_t i = 1; i < r.trace.size(); ++i) {
    if (r.trace[i].max_distance_m != r.trace[0].max_distance_m) return i;
  }
  return r.trace.size();
}

void grid_search(benchmark::State& state, const Dataset& ds) {
  const PointCloud& reference = sgdicp::bench::cloud(ds.reference);
  const auto& run = default_run(ds);
  double voxel_m = 0.0;
  for (auto _ : state) {
    voxel_m = sgdicp::registration_voxel_size(reference, run.settings.downsampling.voxel_size_m,
                                              run.settings.downsampling.downsample_to);
    benchmark::DoNotOptimize(voxel_m);
  }
  state.counters["voxel_m"] = voxel_m;
  state.counters["points"] = static_cast<double>(reference.size());
}

void thin(benchmark::State& state, const Dataset& ds, bool source) {
  const PointCloud& cloud = sgdicp::bench::cloud(source ? ds.source : ds.reference);
  const double voxel_m = default_run(ds).voxel_m;
  std::size_t kept = 0;
  for (auto _ : state) {
    const PointCloud thinned = sgdicp::voxel_downsample(cloud, voxel_m);
    kept = thinned.size();
    benchmark::DoNotOptimize(thinned.points.data());
  }
  state.counters["kept"] = static_cast<double>(kept);
}

void thin_surfaces(benchmark::State& state, const Dataset& ds) {
  const PointCloud& reference = sgdicp::bench::cloud(ds.reference);
  const auto& run = default_run(ds);
  sgdicp::NeighborhoodSettings neighborhood = run.settings.neighborhood;
  neighborhood.num_threads = run.settings.num_threads;  // as grid_index() passes it
  for (auto _ : state) {
    const PointCloud thinned =
        sgdicp::voxel_downsample_with_surfaces(reference, run.voxel_m, neighborhood);
    benchmark::DoNotOptimize(thinned.normals.data());
  }
}

void tree(benchmark::State& state, const Dataset& ds) {
  const auto& run = default_run(ds);
  const sgdicp::KdTreeSettings settings{.num_threads = run.settings.num_threads};
  for (auto _ : state) {
    PointCloud copy = run.index->cloud();
    const auto t0 = Clock::now();
    const ReferenceIndex index =
        ReferenceIndex::on_voxel_grid(std::move(copy), run.voxel_m, settings);
    benchmark::DoNotOptimize(&index);
    state.SetIterationTime(seconds_since(t0));
  }
  state.counters["points"] = static_cast<double>(run.index->size());
}

void reference_index(benchmark::State& state, const Dataset& ds) {
  const PointCloud& reference = sgdicp::bench::cloud(ds.reference);
  const auto& run = default_run(ds);
  for (auto _ : state) {
    PointCloud copy = reference;
    const auto t0 = Clock::now();
    const ReferenceIndex index = sgdicp::reference_index_for(std::move(copy), run.settings);
    benchmark::DoNotOptimize(&index);
    state.SetIterationTime(seconds_since(t0));
  }
}

// One cloud's bulk box (the unit-cube scaling reads both clouds').
void scaling_box(benchmark::State& state, const Dataset& ds, bool source) {
  const auto& run = default_run(ds);
  const PointCloud& cloud = source ? run.thinned_source : run.index->cloud();
  for (auto _ : state) {
    const auto box = sgdicp::bulk_bounding_box(cloud);
    benchmark::DoNotOptimize(&box);
  }
}

// align() on the index built once: its bulk box, computed by the first run, is then kept
// (end_to_end pays it, box_reference times it).
void align_on_index(benchmark::State& state, const Dataset& ds, bool coarse) {
  const PointCloud& source = sgdicp::bench::cloud(ds.source);
  const auto& run = default_run(ds);
  const SgdSettings settings = coarse ? coarse_only(run.settings) : run.settings;
  RegistrationResult r;
  for (auto _ : state) {
    r = sgdicp::align(source, *run.index, settings);
    benchmark::DoNotOptimize(r.T_reference_source.data());
  }
  state.counters["iterations"] = static_cast<double>(r.iterations);
  state.counters["points_processed"] = static_cast<double>(r.points_processed);
  state.counters["coarse_iterations"] = static_cast<double>(coarse_iterations(run.result));
  state.counters["final_d_max_m"] = r.final_max_distance_m;
}

void evaluation(benchmark::State& state, const Dataset& ds, bool coarse) {
  const auto& run = default_run(ds);
  RegistrationResult at = run.result;
  if (coarse)
    at = sgdicp::align(sgdicp::bench::cloud(ds.source), *run.index, coarse_only(run.settings));
  for (auto _ : state) {
    RegistrationResult r;
    r.T_reference_source = at.T_reference_source;
    sgdicp::evaluate_alignment(run.thinned_source, *run.index, at.final_max_distance_m,
                               run.settings.evaluation, run.settings.num_threads, r);
    benchmark::DoNotOptimize(r.inliers);
  }
  state.counters["evaluated_points"] = static_cast<double>(at.evaluated_points);
}

void end_to_end(benchmark::State& state, const Dataset& ds) {
  const PointCloud& source = sgdicp::bench::cloud(ds.source);
  const PointCloud& reference = sgdicp::bench::cloud(ds.reference);
  const SgdSettings settings;
  RegistrationResult r;
  for (auto _ : state) {
    PointCloud copy = reference;
    const auto t0 = Clock::now();
    const ReferenceIndex index = sgdicp::reference_index_for(std::move(copy), settings);
    r = sgdicp::align(source, index, settings);
    state.SetIterationTime(seconds_since(t0));
    benchmark::DoNotOptimize(r.T_reference_source.data());
  }
  state.counters["iterations"] = static_cast<double>(r.iterations);
  state.counters["points_processed"] = static_cast<double>(r.points_processed);
  state.counters["source_points"] = static_cast<double>(r.source_points);
  state.counters["reference_points"] = static_cast<double>(r.reference_points);
}

}  // namespace

int main(int argc, char** argv) {
  for (const Dataset& ds : sgdicp::bench::budget_datasets()) {
    const auto add = [&](const std::string& stage, auto&& fn, bool manual_time = false) {
      auto* b = benchmark::RegisterBenchmark(("budget/" + stage + "/" + ds.name).c_str(),
                                             std::forward<decltype(fn)>(fn));
      b->Unit(benchmark::kMillisecond)->MinTime(0.3);
      if (manual_time) b->UseManualTime();
    };
    add("grid_search", [ds](benchmark::State& s) { grid_search(s, ds); });
    add("thin_reference", [ds](benchmark::State& s) { thin(s, ds, false); });
    add("thin_source", [ds](benchmark::State& s) { thin(s, ds, true); });
    add("thin_surfaces", [ds](benchmark::State& s) { thin_surfaces(s, ds); });
    add(
        "tree", [ds](benchmark::State& s) { tree(s, ds); }, true);
    add(
        "reference_index", [ds](benchmark::State& s) { reference_index(s, ds); }, true);
    add("box_source", [ds](benchmark::State& s) { scaling_box(s, ds, true); });
    add("box_reference", [ds](benchmark::State& s) { scaling_box(s, ds, false); });
    add("align", [ds](benchmark::State& s) { align_on_index(s, ds, false); });
    add("align_coarse", [ds](benchmark::State& s) { align_on_index(s, ds, true); });
    add("evaluation", [ds](benchmark::State& s) { evaluation(s, ds, false); });
    add("evaluation_coarse", [ds](benchmark::State& s) { evaluation(s, ds, true); });
    add(
        "end_to_end", [ds](benchmark::State& s) { end_to_end(s, ds); }, true);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
