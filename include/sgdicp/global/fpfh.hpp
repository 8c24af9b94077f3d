#pragma once
// Fast Point Feature Histograms (Rusu, Blodow and Beetz, "Fast Point Feature Histograms (FPFH)
// for 3D registration", ICRA 2009): a 33-bin descriptor of the surface around a point, invariant
// to rigid motion, which global registration matches between clouds that have no initial guess.
#include <array>
#include <cstddef>
#include <vector>

#include "sgdicp/core/point_cloud.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"

namespace sgdicp {

/// Three histograms of 11 bins (alpha, phi, theta of the Darboux frame), each summing to 1.
using Fpfh = std::array<float, 33>;

struct FpfhSettings {
  double radius_m = 1.0;           ///< neighbourhood of a point's histogram, metres
  std::size_t max_neighbors = 64;  ///< the nearest this many within the radius (bounded work)
};

/// The FPFH of every point of `cloud`, which must carry normals (estimate_normals) and be the
/// cloud `index` was built over (same points, same order). A point without neighbours or with a
/// zero normal gets a zero descriptor. Throws InvalidInputError when the cloud lacks normals or
/// does not match the index, InvalidSettingsError for a radius that is not positive and finite or
/// max_neighbors 0.
[[nodiscard]] std::vector<Fpfh> compute_fpfh(const PointCloud& cloud, const ReferenceIndex& index,
                                             const FpfhSettings& settings);

}  // namespace sgdicp
