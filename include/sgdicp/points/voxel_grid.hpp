#pragma once
// Thinning a cloud with a voxel grid: one centroid per occupied voxel, and the grid size that keeps
// a given number of points (how the registrations choose their grid from the data).
// See docs/preprocessing.md.
#include <cstddef>

#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp {

/// One point per occupied cubic voxel of side voxel_size_m (metres): the centroid of the input
/// points in it. Voxel (i, j, l) holds the points with floor(x / voxel_size_m) = i, etc.
/// Output order is the order of each voxel's first point in the input, so the result is
/// deterministic. Normals and covariances are not carried over (the output has none):
/// estimate them after downsampling. Times (PointCloud::times_s) are: each voxel's point gets the
/// mean time of its points (a voxel at a sweep's seam mixes its start and end: deskew before
/// thinning).
///
/// num_threads (0 = every core): clouds of 32,768 points or more are hashed and summed in two
/// fixed halves, merged in order, which two threads make at once; the result is the same for any
/// count.
///
/// An empty cloud gives an empty cloud. Throws InvalidSettingsError when voxel_size_m is not
/// positive and finite or so small that voxel indices would exceed 2^62 in magnitude, or
/// num_threads is above 1024, and InvalidInputError for a non-finite point.
[[nodiscard]] PointCloud voxel_downsample(const PointCloud& cloud, double voxel_size_m,
                                          std::size_t num_threads = 1);

/// The voxel size, metres, at which voxel_downsample keeps about `target_points` of the cloud
/// (within ~15 %; a few counting passes over the cloud, each cheaper than one voxel_downsample),
/// or 0 when there is nothing to thin: target_points is 0, the cloud has at most that many
/// points, they all lie in one place, or a point lies so far beyond the bulk (1e30 m) that no
/// grid fine enough for the bulk can index it. How the registrations choose their grid from the
/// data (SgdSettings::downsampling.downsample_to, docs/preprocessing.md). Throws InvalidInputError
/// for a non-finite point.
[[nodiscard]] double voxel_size_for_count(const PointCloud& cloud, std::size_t target_points);

/// The voxel grid a registration thins `cloud` with, metres (0 = none): voxel_size_m when
/// positive, else voxel_size_for_count(cloud, downsample_to), except for a cloud that carries
/// normals or covariances, which the automatic grid leaves as it is so that they are used.
[[nodiscard]] double registration_voxel_size(const PointCloud& cloud, double voxel_size_m,
                                             std::size_t downsample_to);

}  // namespace sgdicp
