#include "sgdicp/registration.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "sgdicp/error.hpp"
#include "sgdicp/point_to_point.hpp"
#include "sgdicp/pose.hpp"
#include "sgdicp/sampler.hpp"
#include "sgdicp/scaling.hpp"

namespace sgdicp {

std::string_view to_string(StopReason reason) {
  switch (reason) {
    case StopReason::converged:
      return "converged";
    case StopReason::max_iterations:
      return "max_iterations";
    case StopReason::no_correspondences:
      return "no_correspondences";
    case StopReason::diverged:
      return "diverged";
  }
  return "?";
}

SgdSettings SgdSettings::paper(OptimizerType optimizer) {
  SgdSettings s;
  s.batch_size = 160;
  s.max_correspondence_distance = Distance::scaled(0.5);
  s.optimizer.type = optimizer;
  // The paper states alpha = 2 for the fixed step. Adam's step is a length per iteration (it
  // divides by the gradient's RMS), so alpha = 2 would jump twice across the unit cube; we use
  // the original implementation's Adam step 0.1 scaled down by the measured factor
  // (docs/design.md).
  s.optimizer.learning_rate = optimizer == OptimizerType::sgd ? 2.0 : 0.01;
  s.scaling_origin = ScalingOrigin::lower_corner;
  s.refinement.stages = 0;
  s.average_iterates = false;
  return s;
}

void SgdSettings::validate() const {
  if (batch_size == 0) throw InvalidSettingsError("batch size must be at least 1");
  if (!(max_correspondence_distance.value > 0.0) ||
      !std::isfinite(max_correspondence_distance.value)) {
    throw InvalidSettingsError("max correspondence distance must be positive and finite");
  }
  optimizer.validate();
  if (convergence.window < 8) throw InvalidSettingsError("convergence window must be at least 8");
  if (!(convergence.chi2 > 0.0) || !std::isfinite(convergence.chi2)) {
    throw InvalidSettingsError("convergence chi2 must be positive and finite");
  }
  if (!(convergence.max_path_efficiency > 0.0 && convergence.max_path_efficiency <= 1.0)) {
    throw InvalidSettingsError("convergence max path efficiency must be in (0, 1]");
  }
  if (!(convergence.translation_tolerance >= 0.0) || !(convergence.rotation_tolerance >= 0.0) ||
      !std::isfinite(convergence.translation_tolerance) ||
      !std::isfinite(convergence.rotation_tolerance)) {
    throw InvalidSettingsError("convergence tolerances must be finite and non-negative");
  }
  if (!(refinement.step_decay > 0.0 && refinement.step_decay <= 1.0)) {
    throw InvalidSettingsError("refinement step decay must be in (0, 1]");
  }
  if (!(refinement.distance_factor > 0.0) || !std::isfinite(refinement.distance_factor)) {
    throw InvalidSettingsError("refinement distance factor must be positive and finite");
  }
  if (!(refinement.min_distance.value > 0.0) || !std::isfinite(refinement.min_distance.value)) {
    throw InvalidSettingsError("refinement minimum distance must be positive and finite");
  }
  if (max_iterations == 0) throw InvalidSettingsError("max iterations must be at least 1");
}

namespace {

double median_of(std::vector<float>& values) {
  if (values.empty()) return 0.0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return static_cast<double>(*mid);
}

void check_source(const PointCloud& source, std::size_t batch_size) {
  if (source.empty()) throw InvalidInputError("source cloud is empty");
  if (source.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw InvalidInputError("source cloud has more than 2^32-1 points");
  }
  if (source.size() < batch_size) {
    throw InvalidInputError("source cloud has " + std::to_string(source.size()) +
                            " points, fewer than the mini-batch size " +
                            std::to_string(batch_size));
  }
  for (std::size_t i = 0; i < source.size(); ++i) {
    if (!source.points[i].allFinite()) {
      throw InvalidInputError("source cloud has a non-finite point at index " + std::to_string(i));
    }
  }
}

}  // namespace

RegistrationResult align(const PointCloud& source, const ReferenceIndex& reference,
                         const SgdSettings& settings, const Eigen::Matrix4d& T_init) {
  const auto start = std::chrono::steady_clock::now();
  settings.validate();
  check_source(source, settings.batch_size);
  if (!is_rigid_transform(T_init, 1e-4)) {
    throw InvalidInputError(
        "initial transform is not a finite rigid transform (rotation part "
        "must be orthonormal with determinant 1, last row 0 0 0 1)");
  }

  BoundingBox source_box;
  source_box.extend(source);
  const UnitCubeScaling scaling =
      UnitCubeScaling::from_boxes(source_box, reference.bounding_box(), settings.scaling_origin);
  const double k = scaling.scale();
  const Eigen::Vector3d o = scaling.offset();

  RegistrationResult result;
  result.scale_m = k;

  // Matrices read from text carry few digits: project onto the nearest rotation.
  PoseVector theta = pose_from_transform(scaling.to_scaled(orthonormalized(T_init)));
  Optimizer optimizer(settings.optimizer);
  EpochSampler sampler(static_cast<std::uint32_t>(source.size()), settings.seed);

  double d_max = settings.max_correspondence_distance.to_scaled(k);  // scaled units
  const double d_min = std::min(d_max, settings.refinement.min_distance.to_scaled(k));
  double lr_scale = 1.0;

  std::vector<std::uint32_t> batch;
  batch.reserve(settings.batch_size);
  // Scaled correspondence distances of the current and the last complete window of iterations.
  std::vector<float> distances;
  std::vector<float> last_window_distances;
  distances.reserve(settings.batch_size * settings.convergence.window);
  ConvergenceMonitor monitor(settings.convergence);
  std::size_t stage = 0;
  std::size_t empty_batches = 0;
  // Polyak tail average of the final stage, taken once that stage is stationary.
  bool averaging = false;
  PoseVector average_sum = PoseVector::Zero();
  std::size_t average_count = 0;

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
    PointToPointGradient grad(theta, optimizer.needs_hessian());
    const auto d_max_sq_m = static_cast<float>(d_max * k * d_max * k);
    std::size_t inliers = 0;
    for (const std::uint32_t i : batch) {
      const Eigen::Vector3d s = (source.points[i].cast<double>() - o) / k;
      const Eigen::Vector3d moved = grad.transform(s);
      const Eigen::Vector3f query = (moved * k + o).cast<float>();
      const auto nn = reference.nearest(query, d_max_sq_m);
      if (!nn) continue;
      const Eigen::Vector3d r = (reference.cloud().points[nn->index].cast<double>() - o) / k;
      grad.add(s, moved, r);
      distances.push_back(std::sqrt(nn->squared_distance) / static_cast<float>(k));
      ++inliers;
    }
    // Lines 9-10: one optimiser step on the mean cost over the kept pairs (eq. 6, 7).
    const PoseVector gradient = grad.gradient(settings.batch_size);
    const PoseVector step = optimizer.step(gradient, grad.hessian(settings.batch_size), lr_scale);
    theta += step;
    result.iterations = it + 1;
    result.points_processed += batch.size();

    if (settings.record_trace) {
      result.trace.push_back({result.iterations, result.points_processed,
                              scaling.to_metric(transform_from_pose(theta)),
                              settings.optimizer.learning_rate * lr_scale, d_max * k, inliers,
                              grad.cost(settings.batch_size)});
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

    if (averaging) {
      average_sum += theta;
      ++average_count;
      if (average_count >= settings.convergence.window) {
        finish(StopReason::converged, "converged");
        stopped = true;
      }
      continue;
    }
    if (!monitor.update(gradient, step, inliers)) continue;

    // The stage is stationary.
    ++result.stages;
    if (stage == settings.refinement.stages) {
      if (!settings.average_iterates) {
        finish(StopReason::converged, "converged");
        stopped = true;
      } else {
        averaging = true;
      }
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
  const PoseVector returned =
      average_count > 0 ? PoseVector(average_sum / static_cast<double>(average_count)) : theta;

  result.T_reference_source = scaling.to_metric(transform_from_pose(returned));
  result.final_max_distance_m = d_max * k;

  // Final inlier statistics on an evenly strided sample of the source.
  const std::size_t n = source.size();
  const std::size_t stride = settings.evaluation_points == 0
                                 ? 1
                                 : std::max<std::size_t>(1, n / settings.evaluation_points);
  const Eigen::Matrix3f r = result.T_reference_source.topLeftCorner<3, 3>().cast<float>();
  const Eigen::Vector3f t = result.T_reference_source.topRightCorner<3, 1>().cast<float>();
  const auto final_sq =
      static_cast<float>(result.final_max_distance_m * result.final_max_distance_m);
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < n; i += stride) {
    ++result.evaluated_points;
    if (const auto nn = reference.nearest(r * source.points[i] + t, final_sq)) {
      ++result.inliers;
      sum_sq += nn->squared_distance;
    }
  }
  result.inlier_ratio =
      static_cast<double>(result.inliers) / static_cast<double>(result.evaluated_points);
  result.inlier_rmse_m =
      result.inliers > 0 ? std::sqrt(sum_sq / static_cast<double>(result.inliers)) : 0.0;
  result.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

RegistrationResult align(const PointCloud& source, const PointCloud& reference,
                         const SgdSettings& settings, const Eigen::Matrix4d& T_init) {
  settings.validate();
  const ReferenceIndex index(reference);
  return align(source, index, settings, T_init);
}

}  // namespace sgdicp
