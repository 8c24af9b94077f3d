#pragma once
// A voxel grid's centroids with their normals and covariances from the points of each voxel's
// 3x3x3 block: the surfaces of a thinned reference at the cost of a few table look-ups.
// See docs/preprocessing.md.
#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/surfaces/normals.hpp"

namespace sgdicp {

/// voxel_downsample (same points, same order), with each centroid's normal and covariance
/// estimated as estimate_covariances does (settings: regularize, epsilon, viewpoint,
/// num_threads; the same degenerate cases) but over the input points of its 3x3x3 block of
/// voxels instead of its k nearest neighbours (settings.k is only validated). On a grid that
/// holds several points per voxel this summarises every input point at the cost of 26 table
/// look-ups per centroid, about half of a k-nearest estimate over the centroids
/// (docs/preprocessing.md); the registrations use it for their reference grid when the grid
/// holds at least k/9 points per voxel. Throws as voxel_downsample and estimate_covariances.
[[nodiscard]] PointCloud voxel_downsample_with_surfaces(const PointCloud& cloud,
                                                        double voxel_size_m,
                                                        const NeighborhoodSettings& settings = {});

}  // namespace sgdicp
