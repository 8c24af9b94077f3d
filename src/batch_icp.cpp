#include "sgdicp/batch_icp.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "checks.hpp"
#include "sgdicp/error.hpp"
#include "sgdicp/evaluation.hpp"
#include "sgdicp/preprocessing.hpp"
#include "sgdicp/scaling.hpp"

namespace sgdicp {

namespace {

struct BatchPair {
  std::uint32_t source_index;
  std::uint32_t reference_index;
  float squared_distance;  // m^2
};

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// The weighted least-squares rigid transform taking points a onto points b (Kabsch/Umeyama
// without scale): centre both sets, SVD of the weighted cross-covariance, reflection fixed.
Eigen::Matrix4d weighted_rigid_fit(const std::vector<Eigen::Vector3d>& a,
                                   const std::vector<Eigen::Vector3d>& b,
                                   const std::vector<double>& w) {
  double w_sum = 0.0;
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) {
    w_sum += w[i];
    ca += w[i] * a[i];
    cb += w[i] * b[i];
  }
  ca /= w_sum;
  cb /= w_sum;
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < a.size(); ++i)
    cross.noalias() += w[i] * (b[i] - cb) * (a[i] - ca).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t.topLeftCorner<3, 3>() = svd.matrixU() * d * svd.matrixV().transpose();
  t.topRightCorner<3, 1>() = cb - t.topLeftCorner<3, 3>() * ca;
  return t;
}

}  // namespace

RegistrationResult align_batch(const PointCloud& source, const ReferenceIndex& reference,
                               const BatchSettings& settings, const Eigen::Matrix4d& T_init) {
  const auto start = std::chrono::steady_clock::now();
  settings.validate();
  detail::check_source(source, 6, "the minimum of");
  detail::check_initial_transform(T_init);
  check_reference_prepared(reference, settings.cost);
  std::optional<PointCloud> source_with_features;
  if (needs_covariances(settings.cost) && !source.has_covariances()) {
    source_with_features = source;
    estimate_covariances(*source_with_features, settings.neighborhood);
  }
  const PointCloud& src = source_with_features ? *source_with_features : source;
  const PointCloud& ref = reference.cloud();

  const double k =
      UnitCubeScaling::from_boxes(BoundingBox::of(src), reference.bounding_box()).scale();
  const double d_max = settings.max_correspondence_distance.to_scaled(k) * k;  // metres
  const auto d_max_sq = static_cast<float>(d_max * d_max);
  const double kernel_scale = settings.kernel_scale.to_scaled(k) * k;  // metres

  RegistrationResult result;
  result.scale_m = k;
  result.final_max_distance_m = d_max;
  Eigen::Matrix4d T = orthonormalized(T_init);
  double lambda_scale = settings.initial_damping;

  std::vector<BatchPair> pairs;
  pairs.reserve(src.size());
  std::vector<Eigen::Vector3d> moved, target;
  std::vector<double> weights;
  bool stopped = false;
  for (std::size_t it = 0; it < settings.max_iterations && !stopped; ++it) {
    // Pair every source point with its nearest reference point within d_max.
    const Eigen::Matrix3f rf = T.topLeftCorner<3, 3>().cast<float>();
    const Eigen::Vector3f tf = T.topRightCorner<3, 1>().cast<float>();
    pairs.clear();
    for (std::size_t i = 0; i < src.size(); ++i) {
      if (const auto nn = reference.nearest(rf * src.points[i] + tf, d_max_sq)) {
        pairs.push_back({static_cast<std::uint32_t>(i), nn->index, nn->squared_distance});
      }
    }
    result.iterations = it + 1;
    result.points_processed += src.size();
    if (pairs.size() < 6) {
      result.stop_reason = StopReason::no_correspondences;
      result.message = "fewer than 6 source points had a reference point within d_max = " +
                       std::to_string(d_max) + " m";
      stopped = true;
      break;
    }
    if (settings.trim_ratio < 1.0) {
      const auto keep = std::max<std::size_t>(
          6, static_cast<std::size_t>(
                 std::ceil(settings.trim_ratio * static_cast<double>(pairs.size()))));
      std::nth_element(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(keep - 1),
                       pairs.end(), [](const BatchPair& a, const BatchPair& b) {
                         return a.squared_distance < b.squared_distance;
                       });
      pairs.resize(keep);
    }

    const Eigen::Matrix3d rotation = T.topLeftCorner<3, 3>();
    const Eigen::Vector3d translation = T.topRightCorner<3, 1>();
    Eigen::Matrix4d delta = Eigen::Matrix4d::Identity();
    if (settings.cost == CostType::point_to_point) {
      // Closed form: IRLS weights from the kernel, then the best rigid fit of the pairs.
      moved.clear();
      target.clear();
      weights.clear();
      for (const auto& p : pairs) {
        moved.push_back(rotation * src.points[p.source_index].cast<double>() + translation);
        target.push_back(ref.points[p.reference_index].cast<double>());
        weights.push_back(kernel_weight(settings.kernel, p.squared_distance, kernel_scale));
      }
      delta = weighted_rigid_fit(moved, target, weights);
    } else {
      // One Levenberg-Marquardt step with the pose perturbed on the left, q' = exp(w) q + v:
      // dq/d(w, v) = [-[q]x | I]. The pairs and Omega stay fixed during the step.
      struct Term {
        Eigen::Vector3d q, r;
        Eigen::Matrix3d omega;
      };
      std::vector<Term> terms;
      terms.reserve(pairs.size());
      PoseMatrix h = PoseMatrix::Zero();
      PoseVector b = PoseVector::Zero();
      double cost = 0.0;
      for (const auto& p : pairs) {
        const Eigen::Vector3d q =
            rotation * src.points[p.source_index].cast<double>() + translation;
        const Eigen::Vector3d r = ref.points[p.reference_index].cast<double>();
        const Eigen::Matrix3d omega = information_matrix(
            settings.cost,
            ref.has_normals() ? ref.normals[p.reference_index] : Eigen::Vector3f::Zero(),
            ref.has_covariances() ? ref.covariances[p.reference_index]
                                  : Eigen::Matrix3f::Identity(),
            src.has_covariances() ? src.covariances[p.source_index] : Eigen::Matrix3f::Identity(),
            rotation);
        const Eigen::Vector3d e = q - r;
        const double s = e.dot(omega * e);
        const double w = kernel_weight(settings.kernel, s, kernel_scale);
        PoseJacobianMatrix j;
        j.leftCols<3>() = -skew(q);
        j.rightCols<3>().setIdentity();
        h.noalias() += w * j.transpose() * omega * j;
        b.noalias() += w * j.transpose() * (omega * e);
        cost += kernel_rho(settings.kernel, s, kernel_scale);
        terms.push_back({q, r, omega});
      }
      const double mean_diagonal = h.trace() / 6.0;
      const auto cost_after = [&](const Eigen::Matrix4d& d) {
        double c = 0.0;
        for (const auto& term : terms) {
          const Eigen::Vector3d e =
              d.topLeftCorner<3, 3>() * term.q + d.topRightCorner<3, 1>() - term.r;
          c += kernel_rho(settings.kernel, e.dot(term.omega * e), kernel_scale);
        }
        return c;
      };
      // Raise the damping until the step lowers the cost (at most 10 tries).
      for (int attempt = 0; attempt < 10; ++attempt) {
        PoseMatrix damped = h;
        damped.diagonal().array() += lambda_scale * mean_diagonal + 1e-12 * mean_diagonal;
        const PoseVector step = -damped.ldlt().solve(b);
        Eigen::Matrix4d candidate = Eigen::Matrix4d::Identity();
        const double angle = step.head<3>().norm();
        if (angle > 0.0) {
          candidate.topLeftCorner<3, 3>() =
              Eigen::AngleAxisd(angle, step.head<3>() / angle).toRotationMatrix();
        }
        candidate.topRightCorner<3, 1>() = step.tail<3>();
        if (lambda_scale == 0.0 || cost_after(candidate) <= cost) {
          delta = candidate;
          lambda_scale = std::max(lambda_scale * 0.1, settings.initial_damping > 0 ? 1e-12 : 0.0);
          break;
        }
        lambda_scale = std::max(lambda_scale * 10.0, 1e-9);
      }
    }
    T = delta * T;
    if (settings.record_trace) {
      // The mean squared pair distance before this step stands for the SGD trace's mini-batch
      // cost; a batch step is always a full one (step size 1).
      double sum_sq = 0.0;
      for (const auto& p : pairs) sum_sq += p.squared_distance;
      result.trace.push_back({result.iterations, result.points_processed, orthonormalized(T), 1.0,
                              d_max, pairs.size(),
                              sum_sq / static_cast<double>(pairs.size()) / (k * k)});
    }
    const double moved_t = delta.topRightCorner<3, 1>().norm() / k;
    const double moved_r = Eigen::AngleAxisd(Eigen::Matrix3d(delta.topLeftCorner<3, 3>())).angle();
    if (!T.allFinite()) {
      result.stop_reason = StopReason::diverged;
      result.message = "the pose became non-finite";
      stopped = true;
      break;
    }
    if (moved_t < settings.translation_tolerance && moved_r < settings.rotation_tolerance) {
      result.stop_reason = StopReason::converged;
      result.converged = true;
      result.message = "converged";
      stopped = true;
    }
  }
  if (!stopped) {
    result.stop_reason = StopReason::max_iterations;
    result.message = "reached the iteration limit of " + std::to_string(settings.max_iterations) +
                     " before converging";
  }
  result.T_reference_source = orthonormalized(T);
  evaluate_alignment(src, reference, d_max,
                     EvaluationSettings{settings.evaluation_points, settings.check_degeneracy},
                     result);
  result.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

RegistrationResult align_batch(const PointCloud& source, const PointCloud& reference,
                               const BatchSettings& settings, const Eigen::Matrix4d& T_init) {
  settings.validate();
  ReferenceIndex index(reference);
  prepare_reference(index, settings.cost, settings.neighborhood);
  return align_batch(source, index, settings, T_init);
}

}  // namespace sgdicp
