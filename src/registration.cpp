#include "sgdicp/registration.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "checks.hpp"
#include "sgdicp/error.hpp"
#include "sgdicp/evaluation.hpp"
#include "sgdicp/pose.hpp"
#include "sgdicp/preprocessing.hpp"
#include "sgdicp/sampler.hpp"
#include "sgdicp/scaling.hpp"

namespace sgdicp {

namespace {

double median_of(std::vector<float>& values) {
  if (values.empty()) return 0.0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return static_cast<double>(*mid);
}

const Eigen::Vector3f kNoNormal = Eigen::Vector3f::Zero();
const Eigen::Matrix3f kNoCovariance = Eigen::Matrix3f::Identity();

// One mini-batch of the paper's cost (Algorithm 1, lines 2-8): each source point moved by the
// current pose, paired with its nearest reference point within d_max, added to the gradient.
// The tree lives in metres, the pose in scaled space. Kept apart from align() so that the
// compiler inlines the small Eigen products of this hot loop (measured with callgrind).
void accumulate_point_to_point(const PointCloud& source, const ReferenceIndex& reference,
                               const std::vector<std::uint32_t>& batch,
                               const EulerPoseJacobian& pose, const Eigen::Vector3d& o, double k,
                               float d_max_sq_m, CostAccumulator& accumulator,
                               std::vector<float>& distances) {
  const PointCloud& ref = reference.cloud();
  for (const std::uint32_t i : batch) {
    const Eigen::Vector3d s = (source.points[i].cast<double>() - o) / k;
    const Eigen::Vector3d moved = pose.transform(s);
    const Eigen::Vector3f query = (moved * k + o).cast<float>();
    const auto nn = reference.nearest(query, d_max_sq_m);
    if (!nn) continue;
    const Eigen::Vector3d r = (ref.points[nn->index].cast<double>() - o) / k;
    accumulator.add_point_to_point(pose.jacobian(s), moved - r);
    distances.push_back(std::sqrt(nn->squared_distance) / static_cast<float>(k));
  }
}

// A pair found for a mini-batch, kept for trimming and for the costs that need more than the
// two points.
struct Pair {
  Eigen::Vector3d s;      // scaled source point
  Eigen::Vector3d moved;  // moved by the current pose
  std::uint32_t source_index;
  std::uint32_t reference_index;
  float distance;  // scaled
};

void collect_pairs(const PointCloud& source, const ReferenceIndex& reference,
                   const std::vector<std::uint32_t>& batch, const EulerPoseJacobian& pose,
                   const Eigen::Vector3d& o, double k, float d_max_sq_m, std::vector<Pair>& pairs) {
  pairs.clear();
  for (const std::uint32_t i : batch) {
    const Eigen::Vector3d s = (source.points[i].cast<double>() - o) / k;
    const Eigen::Vector3d moved = pose.transform(s);
    const Eigen::Vector3f query = (moved * k + o).cast<float>();
    if (const auto nn = reference.nearest(query, d_max_sq_m)) {
      pairs.push_back(
          {s, moved, i, nn->index, std::sqrt(nn->squared_distance) / static_cast<float>(k)});
    }
  }
}

}  // namespace

RegistrationResult align(const PointCloud& source, const ReferenceIndex& reference,
                         const SgdSettings& settings, const Eigen::Matrix4d& T_init) {
  const auto start = std::chrono::steady_clock::now();
  settings.validate();
  detail::check_source(source, settings.batch_size, "the mini-batch size");
  detail::check_initial_transform(T_init);
  check_reference_prepared(reference, settings.cost);
  // Plane-to-plane also needs the source's covariances: estimated here (and timed) if missing.
  std::optional<PointCloud> source_with_features;
  if (needs_covariances(settings.cost) && !source.has_covariances()) {
    source_with_features = source;
    estimate_covariances(*source_with_features, settings.neighborhood);
  }
  const PointCloud& src = source_with_features ? *source_with_features : source;

  const UnitCubeScaling scaling = UnitCubeScaling::from_boxes(
      BoundingBox::of(src), reference.bounding_box(), settings.scaling_origin);
  const double k = scaling.scale();
  const Eigen::Vector3d o = scaling.offset();
  const PointCloud& ref = reference.cloud();

  RegistrationResult result;
  result.scale_m = k;

  // Matrices read from text carry few digits: project onto the nearest rotation.
  PoseVector theta = pose_from_transform(scaling.to_scaled(orthonormalized(T_init)));
  Optimizer optimizer(settings.optimizer);
  EpochSampler sampler(static_cast<std::uint32_t>(src.size()), settings.seed);

  const double d_max_initial = settings.max_correspondence_distance.to_scaled(k);  // scaled
  double d_max = d_max_initial;
  const double d_min = std::min(d_max, settings.refinement.min_distance.to_scaled(k));
  const double kernel_scale = settings.kernel_scale.to_scaled(k);
  double lr_scale = 1.0;
  // The paper's pair cost without kernel or trimming takes the short path of the hot loop.
  const bool plain = settings.cost == CostType::point_to_point &&
                     settings.kernel == KernelType::none && settings.trim_ratio >= 1.0;

  std::vector<std::uint32_t> batch;
  batch.reserve(settings.batch_size);
  std::vector<Pair> pairs;
  pairs.reserve(settings.batch_size);
  // Scaled correspondence distances of the current and the last complete window of iterations.
  std::vector<float> distances;
  std::vector<float> last_window_distances;
  distances.reserve(settings.batch_size * settings.convergence.window);
  ConvergenceMonitor monitor(settings.convergence);
  std::size_t stage = 0;
  std::size_t empty_batches = 0;
  // The result when averaging: the mean of the final stage's stationary window (no further
  // window of iterations is spent on it).
  std::optional<PoseVector> averaged;

  const auto finish = [&](StopReason reason, std::string message) {
    result.stop_reason = reason;
    result.converged = reason == StopReason::converged;
    result.message = std::move(message);
  };

  bool stopped = false;
  for (std::size_t it = 0; it < settings.max_iterations && !stopped; ++it) {
    // Algorithm 1, lines 2-8: next mini-batch, moved by theta_{t-1}, paired with its nearest
    // reference point within d_max. The tree lives in metres; the pose lives in scaled space.
    sampler.next_batch(settings.batch_size, batch);
    const EulerPoseJacobian pose(theta);
    CostAccumulator accumulator(settings.kernel, kernel_scale, optimizer.needs_hessian());
    const auto d_max_sq_m = static_cast<float>(d_max * k * d_max * k);
    if (plain) {
      accumulate_point_to_point(src, reference, batch, pose, o, k, d_max_sq_m, accumulator,
                                distances);
    } else {
      collect_pairs(src, reference, batch, pose, o, k, d_max_sq_m, pairs);
      // Trimming: keep the closest fraction of the batch's pairs.
      if (settings.trim_ratio < 1.0 && !pairs.empty()) {
        const auto keep = static_cast<std::size_t>(
            std::ceil(settings.trim_ratio * static_cast<double>(pairs.size())));
        std::nth_element(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(keep - 1),
                         pairs.end(),
                         [](const Pair& a, const Pair& b) { return a.distance < b.distance; });
        pairs.resize(keep);
      }
      for (const Pair& pr : pairs) {
        const Eigen::Vector3d r = (ref.points[pr.reference_index].cast<double>() - o) / k;
        const Eigen::Matrix3d omega = information_matrix(
            settings.cost, ref.has_normals() ? ref.normals[pr.reference_index] : kNoNormal,
            ref.has_covariances() ? ref.covariances[pr.reference_index] : kNoCovariance,
            src.has_covariances() ? src.covariances[pr.source_index] : kNoCovariance,
            pose.rotation());
        accumulator.add(pose.jacobian(pr.s), pr.moved - r, omega);
        distances.push_back(pr.distance);
      }
    }
    const std::size_t inliers = accumulator.pairs();
    // Lines 9-10: one optimiser step on the mean cost over the kept pairs (eq. 6, 7).
    const PoseVector gradient = accumulator.gradient(settings.batch_size);
    const PoseVector step =
        optimizer.step(gradient, accumulator.hessian(settings.batch_size), lr_scale);
    theta += step;
    result.iterations = it + 1;
    result.points_processed += batch.size();

    if (settings.record_trace) {
      result.trace.push_back({result.iterations, result.points_processed,
                              scaling.to_metric(transform_from_pose(theta)),
                              settings.optimizer.learning_rate * lr_scale, d_max * k, inliers,
                              accumulator.cost(settings.batch_size)});
    }
    // Both clouds lie in the unit box of the scaled space: a translation of 10 box sizes can
    // only come from steps that blew up.
    if (!theta.allFinite() || theta.head<3>().cwiseAbs().maxCoeff() > 10.0) {
      finish(StopReason::diverged,
             "the pose diverged (translation beyond 10 times the scene size; step size too "
             "large for this data?)");
      stopped = true;
      break;
    }
    empty_batches = inliers == 0 ? empty_batches + 1 : 0;
    // A refined d_max can fall below the jitter of the steps (an exact copy gives a median pair
    // distance of 0 while Adam still steps ~alpha): a mini-batch without pairs then widens it
    // again, up to the initial d_max, instead of losing the data.
    if (inliers == 0 && d_max < d_max_initial) d_max = std::min(2.0 * d_max, d_max_initial);
    if (empty_batches >= settings.convergence.window) {
      finish(StopReason::no_correspondences,
             "no source point had a reference point within d_max = " + std::to_string(d_max * k) +
                 " m for " + std::to_string(empty_batches) + " mini-batches in a row");
      stopped = true;
      break;
    }
    if ((it + 1) % settings.convergence.window == 0) {
      last_window_distances.swap(distances);
      distances.clear();
    }

    if (!monitor.update(gradient, step, inliers, theta)) continue;

    // The stage is stationary.
    ++result.stages;
    if (stage == settings.refinement.stages) {
      if (settings.average_iterates) averaged = monitor.window_mean();
      finish(StopReason::converged, "converged");
      stopped = true;
      continue;
    }
    // Refinement: tighter correspondences, smaller steps.
    ++stage;
    lr_scale *= settings.refinement.step_decay;
    std::vector<float>& recent =
        last_window_distances.size() > distances.size() ? last_window_distances : distances;
    const double robust = settings.refinement.distance_factor * median_of(recent);
    d_max = std::clamp(robust, d_min, d_max);
    monitor.start_stage();
  }
  if (!stopped) {
    finish(StopReason::max_iterations, "reached the iteration limit of " +
                                           std::to_string(settings.max_iterations) +
                                           " before converging");
  }
  const PoseVector returned = averaged.value_or(theta);

  result.T_reference_source = scaling.to_metric(transform_from_pose(returned));
  result.final_max_distance_m = d_max * k;
  evaluate_alignment(src, reference, result.final_max_distance_m,
                     EvaluationSettings{settings.evaluation_points, settings.check_degeneracy},
                     result);
  result.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

RegistrationResult align(const PointCloud& source, const PointCloud& reference,
                         const SgdSettings& settings, const Eigen::Matrix4d& T_init) {
  settings.validate();
  ReferenceIndex index(reference);
  prepare_reference(index, settings.cost, settings.neighborhood);
  return align(source, index, settings, T_init);
}

}  // namespace sgdicp
