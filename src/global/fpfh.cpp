// FPFH (Rusu et al. 2009): a simplified point feature histogram (SPFH) per point from the Darboux
// frame of each pair with its neighbours, then the FPFH as the point's SPFH plus its neighbours'
// weighted by inverse distance (eq. 4 of the paper), each sub-histogram normalised.
#include "sgdicp/global/fpfh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
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

// The directions of the inner edges of the angle bins over (-pi, pi], the lower half first:
// -pi + 2 pi k / kBins for k = 1 .. kBins - 1.
struct AngleEdges {
  std::array<float, kBins - 1> cos{}, sin{};
  AngleEdges() {
    for (int k = 1; k < kBins; ++k) {
      const double edge = std::numbers::pi * (2.0 * k / kBins - 1.0);
      cos[k - 1] = static_cast<float>(std::cos(edge));
      sin[k - 1] = static_cast<float>(std::sin(edge));
    }
  }
};

// bin_of(atan2(y, x), -pi, pi) without the atan2 (a third of the pair's work): the edges at or
// below the angle, counted by the side of each edge's direction the vector (x, y) lies on,
// within its half plane (where that side orders angles). The sign bit of y picks the half, as
// atan2 does for -0.
int angle_bin(float y, float x) {
  static_assert(kBins % 2 == 1, "no edge at 0: each half plane holds (kBins - 1) / 2 edges");
  if (x == 0.0F && y == 0.0F) {  // atan2's signed zeros
    return bin_of(std::atan2(y, x), -std::numbers::pi_v<float>, std::numbers::pi_v<float>);
  }
  static const AngleEdges edges;
  constexpr int kHalf = (kBins - 1) / 2;
  const int first = std::signbit(y) ? 0 : kHalf;
  int bin = first;
  for (int k = first; k < first + kHalf; ++k) {
    bin += edges.cos[k] * y - edges.sin[k] * x >= 0.0F ? 1 : 0;
  }
  return bin;
}

// The bins of a pair's three angles (eq. 1-3) for point 1's histogram, or none where the pair
// has no frame. The point whose normal makes the smaller angle with the line between them is
// the source of the frame, so that the angles do not depend on which point asks; on a tie, the
// asking point (point 1), and `tied` says so (then point 2's bins differ).
std::optional<std::array<int, 3>> pair_bins(const Eigen::Vector3f& p1, const Eigen::Vector3f& n1,
                                            const Eigen::Vector3f& p2, const Eigen::Vector3f& n2,
                                            bool& tied) {
  Eigen::Vector3f d = p2 - p1;
  const float length = d.norm();
  if (length <= 0.0F) return std::nullopt;
  d /= length;
  Eigen::Vector3f u = n1;
  Eigen::Vector3f target_normal = n2;
  const float cos1 = std::abs(n1.dot(d));
  const float cos2 = std::abs(n2.dot(d));
  tied = cos1 == cos2;
  if (cos1 < cos2) {  // acos is decreasing: larger |cos| wins
    u = n2;
    target_normal = n1;
    d = -d;
  }
  Eigen::Vector3f v = d.cross(u);
  const float v_norm = v.norm();
  if (v_norm <= 1e-12F) return std::nullopt;  // the line lies along the normal: no frame
  v /= v_norm;
  const Eigen::Vector3f w = u.cross(v);
  const float alpha = v.dot(target_normal);
  const float phi = u.dot(d);
  return std::array<int, 3>{
      bin_of(alpha, -1.0F, 1.0F), kBins + bin_of(phi, -1.0F, 1.0F),
      2 * kBins + angle_bin(w.dot(target_normal), u.dot(target_normal))};  // theta
}

void add(const std::array<int, 3>& bins, Fpfh& histogram) {
  for (const int b : bins) histogram[static_cast<std::size_t>(b)] += 1.0F;
}

// A point's neighbourhood: the nearest within the radius (itself excluded), closest first, ties
// by index, and the last of the search's list when the search was cut at its k (else none).
struct Neighborhood {
  std::vector<Neighbor> kept;
  std::optional<Neighbor> cut_at;

  // Whether point `index` at squared distance d (within the radius) is in it: the search keeps
  // every point within the radius up to its cut, in order of (distance, index).
  [[nodiscard]] bool holds(std::uint32_t index, float d) const {
    return !cut_at || d < cut_at->squared_distance ||
           (d == cut_at->squared_distance && index <= cut_at->index);
  }
};

std::vector<Neighborhood> neighborhoods_of(const PointCloud& cloud, const ReferenceIndex& index,
                                           const FpfhSettings& settings) {
  const auto radius2 = static_cast<float>(settings.radius_m * settings.radius_m);
  std::vector<Neighborhood> out(cloud.size());
  std::vector<Neighbor> found;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    index.nearest_within(cloud.points[i], radius2, settings.max_neighbors + 1, found);
    for (const Neighbor& nb : found) {
      if (nb.index != i) out[i].kept.push_back(nb);
    }
    if (found.size() == settings.max_neighbors + 1) out[i].cut_at = found.back();
  }
  return out;
}

// Every point's SPFH. A pair in both neighbourhoods is described once for both points (the
// angles do not depend on which point asks, but on a tie): half the angles of the plain loop.
std::vector<Fpfh> spfh_of(const PointCloud& cloud, const std::vector<Neighborhood>& around) {
  std::vector<Fpfh> spfh(cloud.size(), Fpfh{});
  for (std::uint32_t i = 0; i < cloud.size(); ++i) {
    if (cloud.normals[i].isZero()) continue;
    for (const Neighbor& nb : around[i].kept) {
      const std::uint32_t j = nb.index;
      if (cloud.normals[j].isZero()) continue;
      const bool mutual = around[j].holds(i, nb.squared_distance);
      if (j < i && mutual) continue;  // described when j's neighbours were
      bool tied = false;
      const auto bins =
          pair_bins(cloud.points[i], cloud.normals[i], cloud.points[j], cloud.normals[j], tied);
      if (bins) add(*bins, spfh[i]);
      if (!mutual) continue;
      const auto theirs = tied ? pair_bins(cloud.points[j], cloud.normals[j], cloud.points[i],
                                           cloud.normals[i], tied)
                               : bins;
      if (theirs) add(*theirs, spfh[j]);
    }
  }
  return spfh;
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
  const std::vector<Neighborhood> around = neighborhoods_of(cloud, index, settings);
  std::vector<Fpfh> spfh = spfh_of(cloud, around);
  for (Fpfh& h : spfh) normalise(h);
  std::vector<Fpfh> fpfh(n, Fpfh{});
  for (std::size_t i = 0; i < n; ++i) {
    Fpfh& out = fpfh[i];
    out = spfh[i];
    const auto& kept = around[i].kept;
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
