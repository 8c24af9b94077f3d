#pragma once
// The reference of a registration, thinned and indexed (private to the library).
#include <cstddef>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/registration/settings.hpp"
#include "sgdicp/surfaces/normals.hpp"

namespace sgdicp::detail {

/// The index over the reference of a registration: on the grid of the downsampling settings,
/// registration_voxel_size(cloud, voxel_size_m, downsample_to) (the search's last counting pass
/// doubles as the thinning's), or over the cloud as given when that is 0. On a grid: the
/// centroids (voxel_downsample) and, when `surfaces` and the cloud holds at least k/9 points per
/// occupied voxel (a 3x3 patch of voxels across a surface then holds about k), each centroid's
/// normal and covariance from the points of its 3x3x3 block (voxel_downsample_with_surfaces);
/// otherwise the centroids alone, whose surfaces come from their k nearest centroids
/// (PointSurfaces). `tree`: the KD-tree's settings (its voxel_size_m must be 0). A cloud on a grid
/// is only read: it is copied only to be used as it is.
[[nodiscard]] ReferenceIndex registration_index(const PointCloud& cloud,
                                                const DownsamplingSettings& downsampling,
                                                const NeighborhoodSettings& settings, bool surfaces,
                                                const KdTreeSettings& tree);
/// The same, moving the cloud into the index when it is used as it is.
[[nodiscard]] ReferenceIndex registration_index(PointCloud&& cloud,
                                                const DownsamplingSettings& downsampling,
                                                const NeighborhoodSettings& settings, bool surfaces,
                                                const KdTreeSettings& tree);

}  // namespace sgdicp::detail
