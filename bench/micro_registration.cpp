// Micro-benchmarks of the registration (issue 6):
//   align/DATASET/iters:N   sgdicp::align() stopped after N = 1, 10, 100 mini-batches (batch 160,
//                           index prebuilt): per iteration = (t(100) - t(10)) / 90; t(1) is the
//                           fixed cost (input checks, bounding box, final inlier statistics).
//   register/DATASET        one full registration with the default settings from identity:
//                           KD-tree build + align(), as `sgdicp bench` times it (file I/O
//                           excluded).
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <string>

#include <algorithm>

#include <benchmark/benchmark.h>

#include <sgdicp/index/nearest_neighbor.hpp>
#include <sgdicp/metrics/metrics.hpp>
#include <sgdicp/registration/registration.hpp>

#include "bench_data.hpp"

namespace {

using sgdicp::PointCloud;
using sgdicp::ReferenceIndex;

const ReferenceIndex& index_of(const sgdicp::bench::Dataset& ds) {
  static std::map<std::string, std::unique_ptr<ReferenceIndex>> indices;
  auto& index = indices[ds.name];
  if (!index) index = std::make_unique<ReferenceIndex>(sgdicp::bench::cloud(ds.reference));
  return *index;
}

void align_n(benchmark::State& state, const sgdicp::bench::Dataset& ds) {
  const PointCloud& source = sgdicp::bench::cloud(ds.source);
  const ReferenceIndex& index = index_of(ds);
  sgdicp::SgdSettings settings;
  settings.max_iterations = static_cast<std::size_t>(state.range(0));
  std::size_t iterations = 0;
  for (auto _ : state) {
    const auto r = sgdicp::align(source, index, settings);
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.T_reference_source.data());
  }
  state.counters["iterations"] = static_cast<double>(iterations);
  state.counters["source_points"] = static_cast<double>(source.size());
}

void register_pair(benchmark::State& state, const sgdicp::bench::Dataset& ds) {
  const PointCloud& source = sgdicp::bench::cloud(ds.source);
  const PointCloud& reference = sgdicp::bench::cloud(ds.reference);
  const sgdicp::SgdSettings settings;
  double build_s = 0, align_s = 0, t_err = 0, r_err = 0;
  std::size_t iterations = 0;
  for (auto _ : state) {
    PointCloud copy = reference;  // the copy the index takes is not timed
    const auto t0 = std::chrono::steady_clock::now();
    const ReferenceIndex index(std::move(copy));
    const auto t1 = std::chrono::steady_clock::now();
    const auto r = sgdicp::align(source, index, settings);
    const auto t2 = std::chrono::steady_clock::now();
    build_s += std::chrono::duration<double>(t1 - t0).count();
    align_s += std::chrono::duration<double>(t2 - t1).count();
    state.SetIterationTime(std::chrono::duration<double>(t2 - t0).count());
    iterations = r.iterations;
    t_err = sgdicp::translation_error(r.T_reference_source, ds.T_gt);
    r_err = sgdicp::rotation_error_geodesic(r.T_reference_source, ds.T_gt) * 180 / std::numbers::pi;
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["build_ms"] = 1e3 * build_s / n;
  state.counters["align_ms"] = 1e3 * align_s / n;
  state.counters["iterations"] = static_cast<double>(iterations);
  state.counters["t_err_m"] = t_err;
  state.counters["r_err_deg"] = r_err;
}

// The fastest repetition: on a shared, noisy machine the best estimate of the intrinsic cost.
double min_of(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
}

}  // namespace

int main(int argc, char** argv) {
  for (const auto& ds : sgdicp::bench::available_datasets()) {
    benchmark::RegisterBenchmark(("align/" + ds.name).c_str(), align_n, ds)
        ->ArgName("iters")
        ->Arg(1)
        ->Arg(10)
        ->Arg(100)
        ->ComputeStatistics("min", min_of)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("register/" + ds.name).c_str(), register_pair, ds)
        ->UseManualTime()
        ->ComputeStatistics("min", min_of)
        ->Unit(benchmark::kMillisecond)
        ->MinTime(2.0);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
