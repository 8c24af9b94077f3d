#include "sgdicp/registration/batch_icp.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "core/rigid_fit.hpp"
#include "registration/solver_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/points/scaling.hpp"
#include "solver/levenberg_marquardt.hpp"

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

// The weighted least-squares rigid transform taking points a onto points b (core/rigid_fit.hpp).
Eigen::Matrix4d weighted_rigid_fit(const std::vector<Eigen::Vector3d>& a,
                                   const std::vector<Eigen::Vector3d>& b,
                                   const std::vector<double>& w) {
  return detail::rigid_fit(a.size(), [&](std::size_t i) {
    return detail::FitPair{a[i], b[i], w[i]};
  });
}

// The pairs of an iteration: every source point moved by T with its nearest reference point
// within d_max, the closest fraction kept when trimming.
class BatchPairing {
 public:
  BatchPairing(const PointCloud& source, const ReferenceIndex& reference, double d_max_m,
               double trim_ratio)
      : source_(source),
        reference_(reference),
        d_max_sq_m_(static_cast<float>(d_max_m * d_max_m)),
        trim_ratio_(trim_ratio) {
    pairs_.reserve(source.size());
  }

  const std::vector<BatchPair>& pair(const Eigen::Matrix4d& T) {
    const Eigen::Matrix3f rf = T.topLeftCorner<3, 3>().cast<float>();
    const Eigen::Vector3f tf = T.topRightCorner<3, 1>().cast<float>();
    pairs_.clear();
    for (std::size_t i = 0; i < source_.size(); ++i) {
      if (const auto nn = reference_.nearest(rf * source_.points[i] + tf, d_max_sq_m_)) {
        pairs_.push_back({static_cast<std::uint32_t>(i), nn->index, nn->squared_distance});
      }
    }
    if (trim_ratio_ < 1.0 && pairs_.size() >= kMinPairs) trim();
    return pairs_;
  }

  static constexpr std::size_t kMinPairs = 6;

 private:
  void trim() {
    const auto keep = std::max<std::size_t>(
        kMinPairs,
        static_cast<std::size_t>(std::ceil(trim_ratio_ * static_cast<double>(pairs_.size()))));
    std::nth_element(pairs_.begin(), pairs_.begin() + static_cast<std::ptrdiff_t>(keep - 1),
                     pairs_.end(), [](const BatchPair& a, const BatchPair& b) {
                       return a.squared_distance < b.squared_distance;
                     });
    pairs_.resize(keep);
  }

  const PointCloud& source_;
  const ReferenceIndex& reference_;
  float d_max_sq_m_;
  double trim_ratio_;
  std::vector<BatchPair> pairs_;
};

// The exponential map of a left perturbation (w, v): rotation exp([w]x), translation v.
Eigen::Matrix4d increment_of(const PoseVector& step) {
  Eigen::Matrix4d delta = Eigen::Matrix4d::Identity();
  const double angle = step.head<3>().norm();
  if (angle > 0.0) {
    delta.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(angle, step.head<3>() / angle).toRotationMatrix();
  }
  delta.topRightCorner<3, 1>() = step.tail<3>();
  return delta;
}

// The Gauss-Newton system of sum rho(e^T Omega e) over the pairs at T, with the pose perturbed
// on the left, q' = exp(w) q + v: dq/d(w, v) = [-[q]x | I]. Pairs and Omega stay fixed during
// the step.
class GaussNewtonSystem {
 public:
  GaussNewtonSystem(const std::vector<BatchPair>& pairs, const PointCloud& source,
                    const PointCloud& reference, const Eigen::Matrix4d& T, CostType cost,
                    KernelType kernel, double kernel_scale_m)
      : kernel_(kernel), kernel_scale_m_(kernel_scale_m) {
    const Eigen::Matrix3d rotation = T.topLeftCorner<3, 3>();
    const Eigen::Vector3d translation = T.topRightCorner<3, 1>();
    terms_.reserve(pairs.size());
    for (const auto& p : pairs) {
      const Eigen::Vector3d q =
          rotation * source.points[p.source_index].cast<double>() + translation;
      const Eigen::Vector3d r = reference.points[p.reference_index].cast<double>();
      const Eigen::Matrix3d omega = information_matrix(
          cost,
          reference.has_normals() ? reference.normals[p.reference_index] : Eigen::Vector3f::Zero(),
          reference.has_covariances() ? reference.covariances[p.reference_index]
                                      : Eigen::Matrix3f::Identity(),
          source.has_covariances() ? source.covariances[p.source_index]
                                   : Eigen::Matrix3f::Identity(),
          rotation);
      add(q, r, omega);
    }
  }

  // Solves (H + (lambda + 1e-12) D) x = -b with D the mean diagonal of H: the damped step.
  [[nodiscard]] PoseVector step(double lambda) const {
    const double mean_diagonal = h_.trace() / 6.0;
    PoseMatrix damped = h_;
    damped.diagonal().array() += lambda * mean_diagonal + 1e-12 * mean_diagonal;
    return -damped.ldlt().solve(b_);
  }
  [[nodiscard]] double cost() const noexcept { return cost_; }
  // Whether the weighted pairs constrain the pose at all.
  [[nodiscard]] bool informative() const { return h_.trace() > 0.0; }
  // The cost after moving every paired source point by the increment of `step`.
  [[nodiscard]] double cost_after(const PoseVector& step) const {
    const Eigen::Matrix4d delta = increment_of(step);
    double c = 0.0;
    for (const auto& term : terms_) {
      const Eigen::Vector3d e =
          delta.topLeftCorner<3, 3>() * term.q + delta.topRightCorner<3, 1>() - term.r;
      c += kernel_rho(kernel_, e.dot(term.omega * e), kernel_scale_m_);
    }
    return c;
  }

 private:
  void add(const Eigen::Vector3d& q, const Eigen::Vector3d& r, const Eigen::Matrix3d& omega) {
    const Eigen::Vector3d e = q - r;
    const double s = e.dot(omega * e);
    const double w = kernel_weight(kernel_, s, kernel_scale_m_);
    PoseJacobianMatrix j;
    j.leftCols<3>() = -skew(q);
    j.rightCols<3>().setIdentity();
    h_.noalias() += w * j.transpose() * omega * j;
    b_.noalias() += w * j.transpose() * (omega * e);
    cost_ += kernel_rho(kernel_, s, kernel_scale_m_);
    terms_.push_back({q, r, omega});
  }

  struct Term {
    Eigen::Vector3d q, r;
    Eigen::Matrix3d omega;
  };
  KernelType kernel_;
  double kernel_scale_m_;
  std::vector<Term> terms_;
  PoseMatrix h_ = PoseMatrix::Zero();
  PoseVector b_ = PoseVector::Zero();
  double cost_ = 0.0;
};

// One iteration's increment and what it says about convergence.
struct BatchStep {
  Eigen::Matrix4d delta = Eigen::Matrix4d::Identity();
  // The step the data asks for: the increment itself for the closed form, the (undamped)
  // Gauss-Newton step for the iterative costs. Convergence is judged on it, so that a step
  // that is small only because it is heavily damped does not count.
  Eigen::Matrix4d full_step = Eigen::Matrix4d::Identity();
  bool descended = true;    // false: no damping lowered the cost
  bool informative = true;  // false: no pair carries weight (every kernel weight is 0)
};

// One batch ICP run in metres: pair all, step, until the step the data asks for is small.
class BatchRun {
 public:
  BatchRun(const PointCloud& source, const ReferenceIndex& reference, const BatchSettings& settings,
           double scale_m)
      : source_(source),
        reference_(reference),
        settings_(settings),
        scale_m_(scale_m),
        d_max_m_(settings.pairing.max_correspondence_distance.to_scaled(scale_m) * scale_m),
        kernel_scale_m_(settings.pairing.kernel_scale.to_scaled(scale_m) * scale_m),
        pairing_(source, reference, d_max_m_, settings.pairing.trim_ratio),
        damping_(settings.initial_damping) {}

  [[nodiscard]] double max_distance_m() const noexcept { return d_max_m_; }

  Eigen::Matrix4d minimise(Eigen::Matrix4d T, RegistrationResult& result) {
    for (std::size_t it = 0; it < settings_.max_iterations; ++it) {
      const std::vector<BatchPair>& pairs = pairing_.pair(T);
      result.iterations = it + 1;
      result.points_processed += source_.size();
      if (pairs.size() < BatchPairing::kMinPairs) {
        detail::set_stop(result, StopReason::no_correspondences,
                         "fewer than 6 source points had a reference point within d_max = " +
                             std::to_string(d_max_m_) + " m");
        return T;
      }
      const BatchStep step = settings_.cost == CostType::point_to_point
                                 ? closed_form_step(pairs, T)
                                 : levenberg_marquardt_step(pairs, T);
      T = step.delta * T;
      record(pairs, T, result);
      if (const auto stop = stop_after(T, step)) {
        detail::set_stop(result, stop->first, stop->second);
        return T;
      }
    }
    detail::set_stop(result, StopReason::max_iterations,
                     detail::iteration_limit_message(settings_.max_iterations));
    return T;
  }

 private:
  // Point-to-point in closed form: IRLS weights from the kernel, then the best rigid fit.
  BatchStep closed_form_step(const std::vector<BatchPair>& pairs, const Eigen::Matrix4d& T) {
    const Eigen::Matrix3d rotation = T.topLeftCorner<3, 3>();
    const Eigen::Vector3d translation = T.topRightCorner<3, 1>();
    moved_.clear();
    target_.clear();
    weights_.clear();
    const PointCloud& ref = reference_.cloud();
    for (const auto& p : pairs) {
      moved_.push_back(rotation * source_.points[p.source_index].cast<double>() + translation);
      target_.push_back(ref.points[p.reference_index].cast<double>());
      weights_.push_back(
          kernel_weight(settings_.pairing.kernel, p.squared_distance, kernel_scale_m_));
    }
    BatchStep step;
    step.informative =
        std::any_of(weights_.begin(), weights_.end(), [](double w) { return w > 0.0; });
    if (!step.informative) return step;
    step.delta = weighted_rigid_fit(moved_, target_, weights_);
    step.full_step = step.delta;
    return step;
  }

  // One Levenberg-Marquardt step (levenberg_marquardt.hpp).
  BatchStep levenberg_marquardt_step(const std::vector<BatchPair>& pairs,
                                     const Eigen::Matrix4d& T) {
    const GaussNewtonSystem system(pairs, source_, reference_.cloud(), T, settings_.cost,
                                   settings_.pairing.kernel, kernel_scale_m_);
    BatchStep result;
    result.informative = system.informative();
    if (!result.informative) return result;
    result.full_step = increment_of(system.step(0.0));
    const std::optional<PoseVector> step = damping_.descend(system);
    result.descended = step.has_value();
    if (step) result.delta = increment_of(*step);
    return result;
  }

  void record(const std::vector<BatchPair>& pairs, const Eigen::Matrix4d& T,
              RegistrationResult& result) const {
    if (!settings_.record_trace) return;
    // The mean squared pair distance before this step stands for the SGD trace's mini-batch
    // cost; a batch step is always a full one (step size 1).
    double sum_sq = 0.0;
    for (const auto& p : pairs) sum_sq += p.squared_distance;
    result.trace.push_back({result.iterations, result.points_processed, orthonormalized(T), 1.0,
                            d_max_m_, pairs.size(),
                            sum_sq / static_cast<double>(pairs.size()) / (scale_m_ * scale_m_)});
  }

  [[nodiscard]] bool small(const Eigen::Matrix4d& increment) const {
    const double moved_t = increment.topRightCorner<3, 1>().norm() / scale_m_;
    const double moved_r =
        Eigen::AngleAxisd(Eigen::Matrix3d(increment.topLeftCorner<3, 3>())).angle();
    return moved_t < settings_.translation_tolerance && moved_r < settings_.rotation_tolerance;
  }

  // Why the run stops after this step, if it does.
  [[nodiscard]] std::optional<std::pair<StopReason, std::string>> stop_after(
      const Eigen::Matrix4d& T, const BatchStep& step) const {
    if (!step.informative) {
      return {{StopReason::no_correspondences,
               "no pair carries any weight under the robust kernel (kernel scale too small for "
               "these residuals?)"}};
    }
    if (!T.allFinite()) return {{StopReason::diverged, "the pose became non-finite"}};
    if (small(step.full_step)) return {{StopReason::converged, "converged"}};
    if (!step.descended) {
      return {{StopReason::no_descent,
               "no damped Gauss-Newton step lowered the cost (damping raised " +
                   std::to_string(detail::LevenbergMarquardt::kAttempts) +
                   " times) while the undamped step is still larger than the tolerances"}};
    }
    return std::nullopt;
  }

  const PointCloud& source_;
  const ReferenceIndex& reference_;
  const BatchSettings& settings_;
  double scale_m_;
  double d_max_m_;
  double kernel_scale_m_;
  BatchPairing pairing_;
  detail::LevenbergMarquardt damping_;
  std::vector<Eigen::Vector3d> moved_, target_;
  std::vector<double> weights_;
};

}  // namespace

RegistrationResult align_batch(const PointCloud& source, const ReferenceIndex& reference,
                               const BatchSettings& settings, const Eigen::Matrix4d& T_init) {
  const detail::Stopwatch clock;
  settings.validate();
  detail::check_pair(reference, settings.cost, T_init, detail::SurfaceEstimation::eager);
  const detail::PairFrame frame(reference);
  const double voxel_m = detail::source_voxel_size(reference, settings.downsampling);
  const detail::PreparedSource src(source, voxel_m, settings.num_threads, frame.origin_m(),
                                   settings.cost, settings.neighborhood, BatchPairing::kMinPairs,
                                   "the minimum of");
  RegistrationResult result;
  detail::record_clouds(result, src.cloud(), voxel_m, reference);
  const double scale_m =
      detail::scaling_of(src.cloud(), reference,
                         {.origin = ScalingOrigin::lower_corner, .robust = settings.robust_scaling},
                         result)
          .scale();
  result.scale_m = scale_m;
  BatchRun run(src.cloud(), reference, settings, scale_m);
  result.T_reference_source =
      orthonormalized(run.minimise(frame.to_stored(orthonormalized(T_init)), result));
  detail::conclude(result, src.cloud(), reference, run.max_distance_m(), settings, clock);
  frame.to_clouds(result);
  return result;
}

RegistrationResult align_batch(const PointCloud& source, const PointCloud& reference,
                               const BatchSettings& settings, const Eigen::Matrix4d& T_init) {
  return align_batch(source, reference_index_for(reference, settings), settings, T_init);
}

ReferenceIndex reference_index_for(const PointCloud& reference, const BatchSettings& settings) {
  return detail::index_for(reference, settings, detail::SurfaceEstimation::eager);
}

ReferenceIndex reference_index_for(PointCloud&& reference, const BatchSettings& settings) {
  return detail::index_for(std::move(reference), settings, detail::SurfaceEstimation::eager);
}

}  // namespace sgdicp
