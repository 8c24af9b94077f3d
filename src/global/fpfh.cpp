// FPFH (Rusu et al. 2009): a simplified point feature histogram (SPFH) per point from the Darboux
// frame of each pair with its neighbours, then the FPFH as the point's SPFH plus its neighbours'
// weighted by inverse distance (eq. 4 of the paper), each sub-histogram normalised.
#include "sgdicp/global/fpfh.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <Eigen/Geometry>

#include "sgdicp/core/error.hpp"

namespace sgdicp {
namespace {

constexpr int kBins = 11;

int bin_of(float value, float low, float high) {
  const float t = (value - low) / (high - low);
  return std::clamp(static_cast<int>(t * kBins), 0, kBins - 1);
}

// The three angles of a pair (eq. 1-3): the point whose normal makes the smaller angle with the
// line between them is the source of the frame, so that the features do not depend on order.
void add_pair(const Eigen::Vector3f& p1, const Eigen::Vector3f& n1, const Eigen::Vector3f& p2,
              const Eigen::Vector3f& n2, Fpfh& histogram) {
  Eigen::Vector3f d = p2 - p1;
  const float length = d.norm();
  if (length <= 0.0F) return;
  d /= length;
  Eigen::Vector3f u = n1;
  Eigen::Vector3f target_normal = n2;
  if (std::abs(n1.dot(d)) < std::abs(n2.dot(d))) {  // acos is decreasing: larger |cos| wins
    u = n2;
    target_normal = n1;
    d = -d;
  }
  Eigen::Vector3f v = d.cross(u);
  const float v_norm = v.norm();
  if (v_norm <= 1e-12F) return;  // the line lies along the normal: no frame
  v /= v_norm;
  const Eigen::Vector3f w = u.cross(v);
  const float alpha = v.dot(target_normal);
  const float phi = u.dot(d);
  const float theta = std::atan2(w.dot(target_normal), u.dot(target_normal));
  const auto pi = std::numbers::pi_v<float>;
  histogram[bin_of(alpha, -1.0F, 1.0F)] += 1.0F;
  histogram[kBins + bin_of(phi, -1.0F, 1.0F)] += 1.0F;
  histogram[2 * kBins + bin_of(theta, -pi, pi)] += 1.0F;
}

void normalise(Fpfh& h) {
  for (int part = 0; part < 3; ++part) {
    float sum = 0.0F;
    for (int b = 0; b < kBins; ++b) sum += h[part * kBins + b];
    if (sum <= 0.0F) continue;
    for (int b = 0; b < kBins; ++b) h[part * kBins + b] /= sum;
  }
}

void check(const PointCloud& cloud, const ReferenceIndex& index, const FpfhSettings& settings) {
  if (!(std::isfinite(settings.radius_m) && settings.radius_m > 0.0)) {
    throw InvalidSettingsError("FPFH radius " + std::to_string(settings.radius_m) +
                               " m: must be positive and finite");
  }
  if (settings.max_neighbors == 0) throw InvalidSettingsError("FPFH max_neighbors: must be > 0");
  if (!cloud.has_normals()) throw InvalidInputError("FPFH: the cloud has no normals");
  if (index.size() != cloud.size()) {
    throw InvalidInputError("FPFH: the index holds " + std::to_string(index.size()) +
                            " points, the cloud " + std::to_string(cloud.size()));
  }
}

}  // namespace

std::vector<Fpfh> compute_fpfh(const PointCloud& cloud, const ReferenceIndex& index,
                               const FpfhSettings& settings) {
  check(cloud, index, settings);
  const std::size_t n = cloud.size();
  const auto radius2 = static_cast<float>(settings.radius_m * settings.radius_m);
  // Neighbours within the radius (the point itself excluded), kept for the weighting pass.
  std::vector<std::vector<Neighbor>> neighborhoods(n);
  std::vector<Fpfh> spfh(n, Fpfh{});
  std::vector<Neighbor> found;
  for (std::size_t i = 0; i < n; ++i) {
    index.nearest_within(cloud.points[i], radius2, settings.max_neighbors + 1, found);
    auto& kept = neighborhoods[i];
    for (const Neighbor& nb : found) {
      if (nb.index != i) kept.push_back(nb);
    }
    if (cloud.normals[i].isZero()) continue;
    for (const Neighbor& nb : kept) {
      if (cloud.normals[nb.index].isZero()) continue;
      add_pair(cloud.points[i], cloud.normals[i], cloud.points[nb.index], cloud.normals[nb.index],
               spfh[i]);
    }
    normalise(spfh[i]);
  }
  std::vector<Fpfh> fpfh(n, Fpfh{});
  for (std::size_t i = 0; i < n; ++i) {
    Fpfh& out = fpfh[i];
    out = spfh[i];
    const auto& kept = neighborhoods[i];
    if (kept.empty()) continue;
    float weight_sum = 0.0F;
    Fpfh others{};
    for (const Neighbor& nb : kept) {
      const float w = 1.0F / std::max(std::sqrt(nb.squared_distance), 1e-9F);
      weight_sum += w;
      for (std::size_t b = 0; b < others.size(); ++b) others[b] += w * spfh[nb.index][b];
    }
    for (std::size_t b = 0; b < out.size(); ++b) out[b] += others[b] / weight_sum;
    normalise(out);
  }
  return fpfh;
}

}  // namespace sgdicp
