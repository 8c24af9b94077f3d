// RANSAC with early exit and a short list of distinct hypotheses.
#include "global/consensus.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "core/rigid_fit.hpp"
#include "sgdicp/metrics/metrics.hpp"

namespace sgdicp::detail {
namespace {

// The rigid T minimising sum |to_k - T from_k|^2 over the listed pairs (core/rigid_fit.hpp).
Eigen::Matrix4d fit_listed(const std::vector<Eigen::Vector3f>& from,
                           const std::vector<Eigen::Vector3f>& to,
                           const std::vector<std::uint32_t>& which) {
  return rigid_fit(which.size(), [&](std::size_t i) {
    return FitPair{from[which[i]].cast<double>(), to[which[i]].cast<double>(), 1.0};
  });
}

std::vector<std::uint32_t> inliers_of(const Eigen::Matrix4d& T,
                                      const std::vector<Eigen::Vector3f>& from,
                                      const std::vector<Eigen::Vector3f>& to, float distance2) {
  const Eigen::Matrix3f R = T.topLeftCorner<3, 3>().cast<float>();
  const Eigen::Vector3f t = T.topRightCorner<3, 1>().cast<float>();
  std::vector<std::uint32_t> out;
  for (std::uint32_t k = 0; k < from.size(); ++k) {
    if ((R * from[k] + t - to[k]).squaredNorm() <= distance2) out.push_back(k);
  }
  return out;
}

std::size_t count_inliers(const Eigen::Matrix4d& T, const std::vector<Eigen::Vector3f>& from,
                          const std::vector<Eigen::Vector3f>& to, float distance2) {
  const Eigen::Matrix3f R = T.topLeftCorner<3, 3>().cast<float>();
  const Eigen::Vector3f t = T.topRightCorner<3, 1>().cast<float>();
  std::size_t n = 0;
  for (std::size_t k = 0; k < from.size(); ++k) {
    n += (R * from[k] + t - to[k]).squaredNorm() <= distance2 ? 1 : 0;
  }
  return n;
}

// A rigid motion keeps lengths: the three edges of the sample agree, and are long enough to fix
// a rotation. Compared squared: most samples stop here, so no square roots.
bool edges_agree(const std::vector<Eigen::Vector3f>& from, const std::vector<Eigen::Vector3f>& to,
                 const std::array<std::uint32_t, 3>& s, const ConsensusSettings& settings) {
  const double min_edge2 = settings.min_edge_m * settings.min_edge_m;
  const double ratio2 = settings.edge_ratio * settings.edge_ratio;
  for (std::size_t a = 0; a < 3; ++a) {
    const std::size_t b = (a + 1) % 3;
    const double lf2 = (from[s[a]] - from[s[b]]).cast<double>().squaredNorm();
    const double lt2 = (to[s[a]] - to[s[b]]).cast<double>().squaredNorm();
    if (lf2 < min_edge2 || lt2 < min_edge2) return false;
    if (std::min(lf2, lt2) < ratio2 * std::max(lf2, lt2)) return false;
  }
  return true;
}

// Three indices in [0, n) from two 64-bit draws, each 32 bits scaled by multiply and shift (no
// division, no rejection: a bias below n / 2^32, nothing beside RANSAC's own randomness).
std::array<std::uint32_t, 3> draw_three(std::mt19937_64& rng, std::uint32_t n) {
  const std::uint64_t a = rng();
  const std::uint64_t b = rng();
  const auto scale = [n](std::uint64_t bits32) {
    return static_cast<std::uint32_t>((bits32 * n) >> 32U);
  };
  return {scale(a >> 32U), scale(a & 0xffffffffU), scale(b >> 32U)};
}

// Samples still needed for `confidence` at an inlier ratio w (3 points per sample).
double samples_needed(double w, double confidence) {
  const double good = w * w * w;
  if (good <= 0.0) return std::numeric_limits<double>::infinity();
  if (good >= 1.0) return 1.0;
  return std::log(1.0 - confidence) / std::log(1.0 - good);
}

// Keeps `list` the `keep` best distinct hypotheses, most consensus first.
void offer(std::vector<Hypothesis>& list, const Hypothesis& h, const ConsensusSettings& settings) {
  for (Hypothesis& other : list) {
    if (distinct(other.T_to_from, h.T_to_from, settings)) continue;
    if (h.consensus > other.consensus) other = h;
    std::stable_sort(list.begin(), list.end(), [](const Hypothesis& a, const Hypothesis& b) {
      return a.consensus > b.consensus;
    });
    return;
  }
  if (list.size() == settings.keep && h.consensus <= list.back().consensus) return;
  if (list.size() == settings.keep) list.pop_back();
  const auto at = std::find_if(list.begin(), list.end(),
                               [&](const Hypothesis& o) { return o.consensus < h.consensus; });
  list.insert(at, h);
}

}  // namespace

bool distinct(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b,
              const ConsensusSettings& settings) {
  return rotation_error_geodesic(a, b) > settings.distinct_rotation_rad ||
         translation_error(a, b) > settings.distinct_translation_m;
}

Consensus find_consensus(const std::vector<Eigen::Vector3f>& from,
                         const std::vector<Eigen::Vector3f>& to, const ConsensusSettings& settings,
                         std::uint64_t seed) {
  Consensus out;
  const std::size_t n = from.size();
  if (n < 3 || settings.keep == 0) return out;
  const auto distance2 =
      static_cast<float>(settings.inlier_distance_m * settings.inlier_distance_m);
  std::mt19937_64 rng(seed);
  std::size_t best = 0;
  double needed = samples_needed(0.0, settings.confidence);  // changes only with `best`
  while (out.iterations < settings.max_iterations && static_cast<double>(out.iterations) < needed) {
    ++out.iterations;
    const std::array<std::uint32_t, 3> s = draw_three(rng, static_cast<std::uint32_t>(n));
    if (s[0] == s[1] || s[1] == s[2] || s[0] == s[2] || !edges_agree(from, to, s, settings))
      continue;
    const Hypothesis h{fit_listed(from, to, {s[0], s[1], s[2]}), 0};
    const std::size_t c = count_inliers(h.T_to_from, from, to, distance2);
    if (c < 3) continue;
    if (c > best) {
      best = c;
      needed =
          samples_needed(static_cast<double>(best) / static_cast<double>(n), settings.confidence);
    }
    offer(out.hypotheses, {h.T_to_from, c}, settings);
  }
  // Refit each on its inliers (twice: the fit moves the inlier set a little).
  std::vector<Hypothesis> refitted;
  for (Hypothesis h : out.hypotheses) {
    for (int round = 0; round < 2; ++round) {
      const std::vector<std::uint32_t> in = inliers_of(h.T_to_from, from, to, distance2);
      if (in.size() < 3) break;
      h = {fit_listed(from, to, in), in.size()};
    }
    h.consensus = count_inliers(h.T_to_from, from, to, distance2);
    if (std::none_of(refitted.begin(), refitted.end(), [&](const Hypothesis& o) {
          return !distinct(o.T_to_from, h.T_to_from, settings);
        })) {
      refitted.push_back(h);
    }
  }
  std::stable_sort(refitted.begin(), refitted.end(), [](const Hypothesis& a, const Hypothesis& b) {
    return a.consensus > b.consensus;
  });
  out.hypotheses = std::move(refitted);
  return out;
}

}  // namespace sgdicp::detail
