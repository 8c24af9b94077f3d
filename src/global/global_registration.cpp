// Global registration: features propose (FPFH + RANSAC), the overlap against the reference
// index verifies, SGD-ICP refines (global_registration.hpp, docs/global.md).
#include "sgdicp/global/global_registration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>

#include "global/consensus.hpp"
#include "global/feature_matching.hpp"
#include "registration/align_unless.hpp"
#include "sgdicp/core/format_number.hpp"
#include "sgdicp/global/fpfh.hpp"
#include "sgdicp/points/voxel_grid.hpp"
#include "sgdicp/registration/evaluation.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "util/stopwatch.hpp"

namespace sgdicp {
namespace {

constexpr std::size_t kScorePoints = 2000;    // source points that score a hypothesis
constexpr std::size_t kMaxSourceFactor = 10;  // source grid points at most this x feature_points

// The spacing of a cloud too small to thin: the median distance to the nearest other point.
double median_spacing(const ReferenceIndex& index) {
  std::vector<float> d2;
  std::vector<Neighbor> found;
  const std::size_t stride = std::max<std::size_t>(1, index.size() / 500);
  for (std::size_t i = 0; i < index.size(); i += stride) {
    index.k_nearest(index.cloud().points[i], 2, found);
    if (found.size() == 2) d2.push_back(found[1].squared_distance);
  }
  if (d2.empty()) return 0.0;
  std::nth_element(d2.begin(), d2.begin() + static_cast<std::ptrdiff_t>(d2.size() / 2), d2.end());
  return std::sqrt(static_cast<double>(d2[d2.size() / 2]));
}

// A cloud of the points alone (its normals, if any, belong to another grid).
PointCloud points_only(const PointCloud& cloud, double voxel_m) {
  if (voxel_m > 0.0) return voxel_downsample(cloud, voxel_m);
  PointCloud out;
  out.points = cloud.points;
  return out;
}

struct Features {
  PointCloud cloud;
  std::vector<Fpfh> fpfh;
};

Features features_of(PointCloud cloud, const GlobalSettings& global, double voxel_m) {
  const ReferenceIndex index(cloud);
  estimate_normals(cloud, index, {.k = global.normal_neighbors, .num_threads = 1});
  std::vector<Fpfh> fpfh =
      compute_fpfh(cloud, index, {.radius_m = global.feature_radius_voxels * voxel_m});
  return {std::move(cloud), std::move(fpfh)};
}

detail::ConsensusSettings consensus_settings(const GlobalSettings& g, double voxel_m) {
  return {.inlier_distance_m = g.inlier_distance_voxels * voxel_m,
          .edge_ratio = 0.9,
          .min_edge_m = 3.0 * voxel_m,
          .max_iterations = g.max_iterations,
          .confidence = g.confidence,
          .keep = g.hypotheses,
          .distinct_rotation_rad = g.distinct_rotation_deg * std::numbers::pi / 180.0,
          .distinct_translation_m = g.distinct_translation_voxels * voxel_m};
}

// Scores the hypotheses (stored coordinates) by their overlap, best first.
void verify(GlobalEstimate& e, const detail::Consensus& consensus, const PointCloud& source,
            const ReferenceIndex& reference, const GlobalSettings& g) {
  const double distance_m = g.inlier_distance_voxels * e.feature_voxel_m;
  for (std::size_t rank = 0; rank < consensus.hypotheses.size(); ++rank) {
    const detail::Hypothesis& h = consensus.hypotheses[rank];
    e.hypotheses.push_back(
        {h.T_to_from, h.consensus, rank,
         overlap_fraction(source, reference, h.T_to_from, distance_m, kScorePoints)});
  }
  std::stable_sort(
      e.hypotheses.begin(), e.hypotheses.end(),
      [](const GlobalHypothesis& a, const GlobalHypothesis& b) { return a.score > b.score; });
}

// The winner and runner-up of hypotheses sorted by score, and whether to trust the winner.
void decide(GlobalEstimate& e, const GlobalSettings& g) {
  e.reliable = false;
  if (e.hypotheses.empty()) {
    e.message = "no reliable global solution: no pose agrees with 3 or more feature matches";
    return;
  }
  e.winner_rank = e.hypotheses.front().consensus_rank;
  e.score = e.hypotheses.front().score;
  e.runner_up_score = e.hypotheses.size() > 1 ? e.hypotheses[1].score : 0.0;
  e.ambiguous = e.runner_up_score >= g.ambiguity_ratio * e.score;
  if (e.ambiguous) {
    e.message = "no reliable global solution: ambiguous scene (the runner-up overlaps " +
                format_number(e.runner_up_score) + " against the winner's " +
                format_number(e.score) + ")";
  } else if (e.score < g.min_score) {
    e.message = "no reliable global solution: the best pose overlaps only " +
                format_number(e.score) + " of the source";
  } else {
    e.reliable = true;
    e.message = "global: hypothesis " + std::to_string(e.winner_rank) + " won, overlap " +
                format_number(e.score) + ", runner-up " + format_number(e.runner_up_score);
  }
}

// What estimate_global finds, with the source's feature grid (stored coordinates).
struct EstimateOnGrid {
  GlobalEstimate estimate;
  PointCloud source_grid;
};

EstimateOnGrid estimate_on_grid(const PointCloud& source, const ReferenceIndex& reference,
                                const GlobalSettings& global, std::uint64_t seed) {
  global.validate();
  const detail::Stopwatch clock;
  EstimateOnGrid out;
  GlobalEstimate& e = out.estimate;
  const double grid_m = voxel_size_for_count(reference.cloud(), global.feature_points);
  e.feature_voxel_m = grid_m > 0.0 ? grid_m : median_spacing(reference);
  PointCloud source_grid = source.empty() || !(e.feature_voxel_m > 0.0)
                               ? PointCloud{}
                               : points_only(source, e.feature_voxel_m);
  if (source_grid.size() > kMaxSourceFactor * global.feature_points) {
    // A source far larger than the reference (a map against a scan's grid): bounded work.
    source_grid = points_only(
        source, std::max(e.feature_voxel_m,
                         voxel_size_for_count(source, kMaxSourceFactor * global.feature_points)));
  }
  PointCloud reference_grid = points_only(reference.cloud(), grid_m);
  e.source_points = source_grid.size();
  e.reference_points = reference_grid.size();
  if (e.source_points < global.min_points || e.reference_points < global.min_points) {
    e.message = "no reliable global solution: " + std::to_string(e.source_points) + " source and " +
                std::to_string(e.reference_points) +
                " reference points on the feature grid, at least " +
                std::to_string(global.min_points) + " each needed";
    e.time_ms = clock.elapsed_ms();
    return out;
  }
  Features s = features_of(std::move(source_grid), global, e.feature_voxel_m);
  const Features r = features_of(std::move(reference_grid), global, e.feature_voxel_m);
  const auto matches = detail::match_features(s.fpfh, r.fpfh, 3 * global.min_points);
  e.correspondences = matches.size();
  std::vector<Eigen::Vector3f> from;
  std::vector<Eigen::Vector3f> to;
  for (const auto& [i, j] : matches) {
    from.push_back(s.cloud.points[i]);
    to.push_back(r.cloud.points[j]);
  }
  const detail::Consensus consensus =
      detail::find_consensus(from, to, consensus_settings(global, e.feature_voxel_m), seed);
  e.iterations = consensus.iterations;
  verify(e, consensus, s.cloud, reference, global);
  decide(e, global);
  // Stored coordinates to the clouds' frames.
  for (GlobalHypothesis& h : e.hypotheses) {
    h.T_reference_source =
        between_frames(h.T_reference_source, source.origin_m, reference.cloud().origin_m);
  }
  out.source_grid = std::move(s.cloud);
  e.time_ms = clock.elapsed_ms();
  return out;
}

// SGD-ICP from each hypothesis that overlaps at least half the best's (up to
// refined_hypotheses), each re-scored at the finer distance: a wrong pose that overlaps at the
// coarse distance (a mirrored street, a shifted corridor) does not at the fine one.
std::vector<RegistrationResult> race(GlobalEstimate& e, const PointCloud& source,
                                     const PointCloud& source_grid, const ReferenceIndex& reference,
                                     const SgdSettings& settings, const GlobalSettings& g) {
  const double best = e.hypotheses.front().score;
  std::vector<GlobalHypothesis> refined;
  std::vector<RegistrationResult> results;
  const auto rule = consensus_settings(g, e.feature_voxel_m);
  const Eigen::Vector3d& o_s = source.origin_m;
  const Eigen::Vector3d& o_r = reference.cloud().origin_m;
  for (std::size_t k = 0; k < e.hypotheses.size() && k < g.refined_hypotheses; ++k) {
    const GlobalHypothesis& h = e.hypotheses[k];
    if (k > 0 && h.score < 0.5 * best) break;
    // A run that comes within the same-pose distance of a pose already refined would converge
    // onto it: it ends there (on the bunny most runners-up do, within a few windows).
    const auto joins_refined = [&](const Eigen::Matrix4d& T) {
      return std::any_of(refined.begin(), refined.end(), [&](const GlobalHypothesis& o) {
        return !detail::distinct(o.T_reference_source, T, rule);
      });
    };
    std::optional<RegistrationResult> run =
        detail::align_unless(source, reference, settings, h.T_reference_source, joins_refined);
    if (!run) continue;
    RegistrationResult& r = *run;
    if (joins_refined(r.T_reference_source)) continue;  // converged onto it all the same
    const double fine =
        overlap_fraction(source_grid, reference, between_stored(r.T_reference_source, o_s, o_r),
                         g.fine_distance_voxels * e.feature_voxel_m, kScorePoints);
    refined.push_back({r.T_reference_source, h.consensus, h.consensus_rank, fine});
    results.push_back(std::move(r));
  }
  std::vector<std::size_t> order(refined.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return refined[a].score > refined[b].score;
  });
  e.hypotheses.clear();
  std::vector<RegistrationResult> sorted;
  for (const std::size_t k : order) {
    e.hypotheses.push_back(refined[k]);
    sorted.push_back(std::move(results[k]));
  }
  decide(e, g);
  return sorted;
}

}  // namespace

GlobalEstimate estimate_global(const PointCloud& source, const ReferenceIndex& reference,
                               const GlobalSettings& global, std::uint64_t seed) {
  return estimate_on_grid(source, reference, global, seed).estimate;
}

RegistrationResult align_global(const PointCloud& source, const ReferenceIndex& reference,
                                const SgdSettings& settings, const GlobalSettings& global) {
  settings.validate();
  const detail::Stopwatch clock;
  EstimateOnGrid found = estimate_on_grid(source, reference, global, settings.sampling.seed);
  GlobalEstimate& e = found.estimate;
  RegistrationResult r;
  r.message = e.message;
  if (!e.hypotheses.empty()) {
    std::vector<RegistrationResult> refined =
        race(e, source, found.source_grid, reference, settings, global);
    r = std::move(refined.front());
  }
  r.global_init = true;
  r.global_winner_rank = e.winner_rank;
  r.global_hypotheses = e.hypotheses.size();
  r.global_score = e.score;
  r.global_runner_up_score = e.runner_up_score;
  r.global_ambiguous = e.ambiguous;
  r.global_reliable = e.reliable && !r.degenerate;
  r.global_ms = e.time_ms;
  if (!e.reliable) {
    r.message = e.message;
  } else if (r.degenerate) {
    r.message = "no reliable global solution: degenerate geometry (" + r.message + ")";
  } else {
    r.message = e.message + "; " + r.message;
  }
  r.time_ms = clock.elapsed_ms();
  return r;
}

RegistrationResult align_global(const PointCloud& source, const PointCloud& reference,
                                const SgdSettings& settings, const GlobalSettings& global) {
  settings.validate();
  return align_global(source, reference_index_for(reference, settings), settings, global);
}

}  // namespace sgdicp
