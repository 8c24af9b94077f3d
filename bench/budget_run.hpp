#pragma once
// The three pairs of the time budget (docs/performance.md, "Time budget per stage"): a KITTI
// scan, a Kinect frame and a hand-held LiDAR scan, each with what one default registration
// (`sgdicp register SOURCE REFERENCE`: SgdSettings{}, one thread) makes of it. Shared by
// micro_stage_budget.cpp and micro_floor.cpp; built once per process, never timed.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <sgdicp/index/nearest_neighbor.hpp>
#include <sgdicp/points/voxel_grid.hpp>
#include <sgdicp/registration/registration.hpp>

#include "bench_data.hpp"

namespace sgdicp::bench {

/// KITTI seq 00 1 -> 0, the PCL Kinect frames and BALM scans 101 -> 100 (the first pair of each
/// pairs file).
inline std::vector<Dataset> budget_datasets() {
  return datasets({
      {"kitti", "kitti_seq00.txt"},
      {"kinect", "pcl_kinect_frames.txt"},
      {"balm", "balm_handheld_lidar.txt"},
  });
}

struct DefaultRun {
  SgdSettings settings;                   ///< SgdSettings{} (num_threads 1, as the CLI's default)
  double voxel_m = 0.0;                   ///< the grid both clouds are thinned on
  PointCloud thinned_source;              ///< the source on that grid, as align() thins it
  std::unique_ptr<ReferenceIndex> index;  ///< reference_index_for(reference, settings)
  RegistrationResult result;              ///< align(source, index, settings), with its trace
};

/// The default registration of `ds`, made once per process. The trace is recorded only here
/// (record_trace changes no pose): it gives the poses at which the run queried the index.
inline const DefaultRun& default_run(const Dataset& ds) {
  static std::map<std::string, DefaultRun> runs;
  auto it = runs.find(ds.name);
  if (it != runs.end()) return it->second;
  DefaultRun run;
  const PointCloud& reference = cloud(ds.reference);
  run.voxel_m = registration_voxel_size(reference, run.settings.downsampling.voxel_size_m,
                                        run.settings.downsampling.downsample_to);
  run.thinned_source = voxel_downsample(cloud(ds.source), run.voxel_m);
  run.index = std::make_unique<ReferenceIndex>(reference_index_for(reference, run.settings));
  SgdSettings traced = run.settings;
  traced.record_trace = true;
  run.result = align(cloud(ds.source), *run.index, traced);
  return runs.emplace(ds.name, std::move(run)).first->second;
}

}  // namespace sgdicp::bench
