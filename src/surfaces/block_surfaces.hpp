#pragma once
// The surfaces of a voxel grid's centroids from the moments of each voxel's 3x3x3 block of
// voxels (voxel_surfaces.cpp; private to the library).
#include <cstddef>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "points/voxel_table.hpp"
#include "sgdicp/surfaces/normals.hpp"

namespace sgdicp::detail {

/// The block surface of every voxel of an accumulated table into `normals` and `covariances` (by
/// slot); `stored` from in_stored_frame. When `linearities` is given it receives, by slot, each
/// block's linearity (lambda_2 - lambda_1) / lambda_2 (describe_covariance: NaN for fewer than 3
/// points), which costs no more than the eigen-solve already made. `side` runs on a second
/// thread while the first sorts the keys, and that thread then joins the sweep: the sweep is
/// claimed in chunks by whichever thread is free. Each voxel's surface is a pure function of its
/// block, so the values are the same for any thread count and split.
void sweep_surfaces(const VoxelTable<Moments>& table, const NeighborhoodSettings& stored,
                    std::size_t threads, std::vector<Eigen::Vector3f>& normals,
                    std::vector<Eigen::Matrix3f>& covariances, const std::function<void()>& side,
                    std::vector<double>* linearities = nullptr);

}  // namespace sgdicp::detail
