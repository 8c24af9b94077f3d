#pragma once
// Pictures for a quick look, written as PNG: a registration (reference and aligned source in two
// colours) or a trajectory (estimate and ground truth), each seen along z (x-y) and along y (x-z).
#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "sgdicp/core/point_cloud.hpp"

namespace sgdicp {

struct RenderSettings {
  int width = 1200;                 ///< pixels of the whole picture (both views side by side)
  int height = 600;                 ///< pixels
  std::size_t max_points = 200000;  ///< per cloud (strided beyond) or dots along a trajectory
};

/// Writes a PNG with the reference (grey-blue) and source moved by T_reference_source (orange):
/// left the top view (x right, y up), right the side view (x right, z up), sharing one metric scale
/// and with a scale bar. Throws IoError when the file cannot be written.
void render_alignment_png(const std::filesystem::path& path, const PointCloud& reference,
                          const PointCloud& source, const Eigen::Matrix4d& T_reference_source,
                          const RenderSettings& settings = {});

/// Writes a PNG of trajectories, the positions of their poses joined by lines: the ground truth
/// (grey-blue; empty: none) and the estimate (orange) mapped into the ground truth's frame by
/// T_truth_estimate (e.g. AbsoluteTrajectoryError::T_truth_estimate; identity without a ground
/// truth), in the same two views, scale and scale bar as render_alignment_png. Throws
/// InvalidInputError for an empty estimate or a non-finite pose, IoError when the file cannot be
/// written.
void render_trajectories_png(const std::filesystem::path& path,
                             const std::vector<Eigen::Matrix4d>& estimate,
                             const std::vector<Eigen::Matrix4d>& truth,
                             const Eigen::Matrix4d& T_truth_estimate,
                             const RenderSettings& settings = {});

}  // namespace sgdicp
