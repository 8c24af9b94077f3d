#pragma once
// A picture of a registration for a quick look: reference and aligned source drawn in two colours,
// seen from above (x-y) and from the side (x-z), written as PNG.
#include <filesystem>

#include <Eigen/Core>

#include "sgdicp/point_cloud.hpp"

namespace sgdicp {

struct RenderSettings {
  int width = 1200;                 ///< pixels of the whole picture (both views side by side)
  int height = 600;                 ///< pixels
  std::size_t max_points = 200000;  ///< per cloud; larger clouds are drawn strided
};

/// Writes a PNG with the reference (grey-blue) and source moved by T_reference_source (orange):
/// left the top view (x right, y up), right the side view (x right, z up), sharing one metric scale
/// and with a scale bar. Throws IoError when the file cannot be written.
void render_alignment_png(const std::filesystem::path& path, const PointCloud& reference,
                          const PointCloud& source, const Eigen::Matrix4d& T_reference_source,
                          const RenderSettings& settings = {});

}  // namespace sgdicp
