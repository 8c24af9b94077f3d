#include "sgdicp/registration/registration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>

#include "index/nearest_memory.hpp"
#include "registration/align_unless.hpp"
#include "registration/solver_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/core/pose.hpp"
#include "sgdicp/core/threads.hpp"
#include "sgdicp/points/scaling.hpp"
#include "sgdicp/registration/evaluation.hpp"
#include "sgdicp/solver/sampler.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "sgdicp/uncertainty/uncertainty.hpp"
#include "surfaces/point_surfaces.hpp"
#include "util/helper_thread.hpp"

namespace sgdicp {

namespace {

const Eigen::Vector3f kNoNormal = Eigen::Vector3f::Zero();

// A pair found for a mini-batch, kept for trimming and for the costs that need more than the
// two points.
struct Pair {
  Eigen::Vector3d s;      // scaled source point
  Eigen::Vector3d moved;  // moved by the current pose
  std::uint32_t source_index;
  std::uint32_t reference_index;
  float distance;  // scaled
};

// Algorithm 1, lines 3-8: each point of a mini-batch moved by the current pose, paired with its
// nearest reference point within d_max, added to the mini-batch cost. The tree lives in metres,
// the pose in the scaled space. The normals and covariances a cost needs come from the clouds or
// are estimated for the pairs that use them (point_surfaces.hpp). It reads the pairing group,
// the surfaces' neighbourhoods and the run's thread count; the run says which cost (use_cost).
class MiniBatchPairing {
 public:
  MiniBatchPairing(const PointCloud& source, const ReferenceIndex* source_index,
                   const ReferenceIndex& reference, const UnitCubeScaling& scaling,
                   const PairingSettings& settings, const NeighborhoodSettings& neighborhood,
                   std::size_t num_threads, std::size_t batch_size)
      : source_(source),
        reference_(reference),
        reference_surfaces_(reference, neighborhood),
        source_surfaces_(source, source_index, neighborhood),
        scaling_(scaling),
        settings_(settings),
        kernel_scale_(settings.kernel_scale.to_scaled(scaling.scale())) {
    pairs_.reserve(batch_size);
    split_queries_ = resolve_thread_count(num_threads) >= 2;
  }

  [[nodiscard]] Eigen::Vector3f reference_normal(std::uint32_t i) {
    return reference_surfaces_.normal(i);
  }

  // What the memory certifies over `index` (null: no memory, or one over another index).
  [[nodiscard]] const detail::NearestMemory* memory_over(const ReferenceIndex& index) const {
    return memory_ && search_ == &index ? &*memory_ : nullptr;
  }

  // The index the pairs are searched in from now on: the reference, or its coarse view (one
  // point per map voxel, the same cloud) for the coarse stage (SgdRun). What the memory
  // certified for one does not hold for the other: it starts again.
  void search_in(const ReferenceIndex& index) {
    if (&index == search_) return;
    search_ = &index;
    memory_.reset();
    queried_ = 0;
  }

  // The cost of the pairs from now on (the coarse stage may pair with another, SgdRun).
  void use_cost(CostType cost) {
    cost_ = cost;
    plain_ = cost == CostType::point_to_point && settings_.kernel == KernelType::none &&
             settings_.trim_ratio >= 1.0;
  }

  // Every query leaves a certificate from now on (NearestMemory): from the second epoch on its
  // own (remember_from_now_on), from the refinement when an uncertainty pass over every source
  // point follows the run, near the poses its last mini-batches met.
  void start_memory() {
    if (!memory_) memory_.emplace(*search_, source_.size());
  }

  // sum w J^T Omega e of the cost over every point of `cloud` (a source in the run's frame, e.g.
  // thinned on another grid), each paired by a fresh search of the reference within d_max. A fresh
  // search of ~19k centroids is 5 ms, most of a grid of laplace's bootstrap: the cloud's two
  // halves are summed apart and added in order, on the helper thread when there is one, the same
  // bits on any thread count. Normals estimated on first use are not thread-safe: then both
  // halves run here.
  PoseVector gradient_over(const PointCloud& cloud, const EulerPoseJacobian& pose,
                           double d_max_scaled) {
    const double k = scaling_.scale();
    const auto d_max_sq_m = static_cast<float>(d_max_scaled * k * d_max_scaled * k);
    const std::size_t n = cloud.size();
    std::array<PoseVector, 2> sums;
    if (split_queries_ && n >= kMinSplitBatch &&
        (cost_ == CostType::point_to_point || surfaces_stored())) {
      const std::array<std::size_t, 3> halves{0, n / 2, n};
      detail::run_ranges(halves, [&](std::size_t begin, std::size_t end) {
        sums[begin == 0 ? 0 : 1] = gradient_part(cloud, pose, d_max_sq_m, begin, end);
      });
    } else {
      sums = {gradient_part(cloud, pose, d_max_sq_m, 0, n / 2),
              gradient_part(cloud, pose, d_max_sq_m, n / 2, n)};
    }
    return sums[0] + sums[1];
  }

  // The cost of the batch at `pose` over the pairs within d_max_scaled; their distances (scaled)
  // are appended to `distances`.
  CostAccumulator accumulate(const std::vector<std::uint32_t>& batch, const EulerPoseJacobian& pose,
                             double d_max_scaled, bool with_hessian,
                             std::vector<float>& distances) {
    CostAccumulator cost(settings_.kernel, kernel_scale_, with_hessian);
    const double k = scaling_.scale();
    const auto d_max_sq_m = static_cast<float>(d_max_scaled * k * d_max_scaled * k);
    find_pairs(batch, pose, d_max_sq_m);
    if (plain_) {
      add_point_to_point(pose, cost, distances);
    } else {
      std::erase_if(pairs_, [](const Pair& pair) { return pair.reference_index == kNoPair; });
      trim();
      add_general(pose, cost, distances);
    }
    return cost;
  }

 private:
  static constexpr std::uint32_t kNoPair = std::numeric_limits<std::uint32_t>::max();
  // Below this many points a batch's queries are not worth handing half to the helper thread.
  static constexpr std::size_t kMinSplitBatch = 32;

  // gradient_over's sum over points [begin, end) of `cloud`.
  PoseVector gradient_part(const PointCloud& cloud, const EulerPoseJacobian& pose, float d_max_sq_m,
                           std::size_t begin, std::size_t end) {
    CostAccumulator cost(settings_.kernel, kernel_scale_, false);
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Vector3d s = scaling_.to_scaled(cloud.points[i]);
      const Eigen::Vector3d moved = pose.transform(s);
      const auto nn = reference_.nearest(scaling_.to_metric(moved).cast<float>(), d_max_sq_m);
      if (!nn) continue;
      const Eigen::Vector3d r = scaling_.to_scaled(reference_.cloud().points[nn->index]);
      if (cost_ == CostType::point_to_point) {
        cost.add_point_to_point(pose.jacobian(s), moved - r);
      } else {
        cost.add_plane(pose.jacobian(s), moved - r,
                       reference_surfaces_.normal(nn->index).cast<double>());
      }
    }
    return 2.0 * cost.gradient(1);
  }

  // Lines 3-5 for every point of the batch, in batch order: moved by the pose and paired with its
  // nearest reference point within d_max (kNoPair when there is none). The queries are most of
  // an iteration: with a helper thread each thread makes half of them, into their own slots.
  void find_pairs(const std::vector<std::uint32_t>& batch, const EulerPoseJacobian& pose,
                  float d_max_sq_m) {
    const auto k = static_cast<float>(scaling_.scale());
    pairs_.resize(batch.size());
    remember_from_now_on(batch.size());
    if (memory_) fresh_.resize(batch.size());
    const auto part = [&](std::size_t begin, std::size_t end) {
      for (std::size_t slot = begin; slot < end; ++slot) {
        Pair& pair = pairs_[slot];
        pair.source_index = batch[slot];
        pair.s = scaling_.to_scaled(source_.points[pair.source_index]);
        pair.moved = pose.transform(pair.s);
        const Eigen::Vector3f query = scaling_.to_metric(pair.moved).cast<float>();
        const auto nn = memory_
                            ? memory_->nearest(pair.source_index, query, d_max_sq_m, fresh_[slot])
                            : search_->nearest(query, d_max_sq_m);
        pair.reference_index = nn ? nn->index : kNoPair;
        pair.distance = nn ? std::sqrt(nn->squared_distance) / k : 0.0f;
      }
    };
    if (split_queries_ && batch.size() >= kMinSplitBatch) {
      const std::array<std::size_t, 3> halves{0, batch.size() / 2, batch.size()};
      detail::run_ranges(halves, part);
    } else {
      part(0, batch.size());
    }
    // In batch order after the queries: a batch that straddles two epochs may hold a point twice.
    if (!memory_) return;
    for (std::size_t slot = 0; slot < batch.size(); ++slot) {
      memory_->remember(batch[slot], fresh_[slot]);
    }
  }

  // A run that has drawn every source point once draws them again (the next epoch): from then on
  // each query leaves what certifies the next one (NearestMemory). The first pass does not pay
  // for the certificates, which a large source drawn for a fraction of a pass would never use.
  void remember_from_now_on(std::size_t batch_points) {
    if (memory_) return;
    queried_ += batch_points;
    if (queried_ > source_.size()) start_memory();
  }

  // The paper's pair cost without kernel or trimming: the short path of the hot loop. Kept
  // apart so that the compiler inlines its small Eigen products (measured with callgrind).
  void add_point_to_point(const EulerPoseJacobian& pose, CostAccumulator& cost,
                          std::vector<float>& distances) const {
    const PointCloud& ref = reference_.cloud();
    for (const Pair& pair : pairs_) {
      if (pair.reference_index == kNoPair) continue;
      const Eigen::Vector3d r = scaling_.to_scaled(ref.points[pair.reference_index]);
      cost.add_point_to_point(pose.jacobian(pair.s), pair.moved - r);
      distances.push_back(pair.distance);
    }
  }

  // Trimmed ICP (Chetverikov et al. 2002): keep the closest fraction of the batch's pairs.
  void trim() {
    if (settings_.trim_ratio >= 1.0 || pairs_.empty()) return;
    const auto keep = static_cast<std::size_t>(
        std::ceil(settings_.trim_ratio * static_cast<double>(pairs_.size())));
    std::nth_element(pairs_.begin(), pairs_.begin() + static_cast<std::ptrdiff_t>(keep - 1),
                     pairs_.end(),
                     [](const Pair& a, const Pair& b) { return a.distance < b.distance; });
    pairs_.resize(keep);
  }

  // Any cost of cost.hpp with its kernel: rho(e^T Omega e). With a helper and every surface the
  // cost reads already stored (nothing estimated on first use, which is not thread-safe), the
  // pairs' terms are made in two halves, one slot each, and added here in pair order: the same
  // sums as on one thread.
  void add_general(const EulerPoseJacobian& pose, CostAccumulator& cost,
                   std::vector<float>& distances) {
    const auto term_of = [&](const Pair& pair) {
      const Eigen::Vector3d r = reference_point(pair);
      if (cost_ == CostType::point_to_plane) {
        return cost.plane_term(pose.jacobian(pair.s), pair.moved - r,
                               reference_surfaces_.normal(pair.reference_index).cast<double>());
      }
      return cost.term(pose.jacobian(pair.s), pair.moved - r, information(pair, pose.rotation()));
    };
    if (split_queries_ && pairs_.size() >= kMinSplitBatch && surfaces_stored()) {
      terms_.resize(pairs_.size());
      const std::array<std::size_t, 3> halves{0, pairs_.size() / 2, pairs_.size()};
      detail::run_ranges(halves, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) terms_[k] = term_of(pairs_[k]);
      });
      for (std::size_t k = 0; k < pairs_.size(); ++k) {
        cost.add(terms_[k]);
        distances.push_back(pairs_[k].distance);
      }
      return;
    }
    for (const Pair& pair : pairs_) {
      if (cost_ == CostType::point_to_plane) {
        cost.add_plane(pose.jacobian(pair.s), pair.moved - reference_point(pair),
                       reference_surfaces_.normal(pair.reference_index).cast<double>());
      } else {
        cost.add(term_of(pair));
      }
      distances.push_back(pair.distance);
    }
  }

  [[nodiscard]] Eigen::Vector3d reference_point(const Pair& pair) const {
    return scaling_.to_scaled(reference_.cloud().points[pair.reference_index]);
  }

  // Whether the cost reads only normals and covariances the clouds store.
  [[nodiscard]] bool surfaces_stored() const {
    const PointCloud& ref = reference_.cloud();
    if (needs_reference_normals(cost_) && !ref.has_normals()) return false;
    return !needs_covariances(cost_) || (ref.has_covariances() && source_.has_covariances());
  }

  // Omega of a pair whose cost is not point-to-plane (that one is plane_term's): the identity,
  // or for plane-to-plane from both points' covariances, looked up or estimated.
  Eigen::Matrix3d information(const Pair& pair, const Eigen::Matrix3d& rotation) {
    if (!needs_covariances(cost_)) return Eigen::Matrix3d::Identity();
    return information_matrix(cost_, kNoNormal,
                              reference_surfaces_.covariance(pair.reference_index),
                              source_surfaces_.covariance(pair.source_index), rotation);
  }

  const PointCloud& source_;
  const ReferenceIndex& reference_;
  const ReferenceIndex* search_ = &reference_;  // reference_ or its coarse view
  detail::PointSurfaces reference_surfaces_;
  detail::PointSurfaces source_surfaces_;
  const UnitCubeScaling& scaling_;
  const PairingSettings& settings_;
  double kernel_scale_;  // scaled
  CostType cost_ = CostType::point_to_point;
  bool plain_ = false;
  std::vector<Pair> pairs_;  // one slot per batch point, then the pairs the cost uses
  std::vector<CostAccumulator::PairTerm> terms_;  // one per pair, when made in two halves
  std::size_t queried_ = 0;                       // source points drawn until memory_ starts
  std::optional<detail::NearestMemory> memory_;
  std::vector<detail::NearestMemory::Entry> fresh_;  // one per batch point
  // With num_threads >= 2 the batches' queries are split with the calling thread's helper
  // (helper_thread.hpp).
  bool split_queries_ = false;
};

// One SGD-ICP run in the scaled space: Algorithm 1, then the refinement stages.
class SgdRun {
 public:
  SgdRun(const PointCloud& source, const ReferenceIndex* source_index,
         const ReferenceIndex& reference, const SgdSettings& settings,
         const UnitCubeScaling& scaling)
      : settings_(settings),
        scaling_(scaling),
        reference_(reference),
        pairing_(source, source_index, reference, scaling, settings.pairing, settings.neighborhood,
                 settings.num_threads, settings.sampling.batch_size),
        sampler_(static_cast<std::uint32_t>(source.size()), settings.sampling.seed),
        optimizer_(settings.optimizer),
        // Batches are the same set every time only when m is a multiple of N: beyond N a batch
        // also draws part of the next epoch at random (EpochSampler).
        monitor_(settings.convergence, settings.sampling.batch_size % source.size() == 0),
        schedule_(settings.refinement,
                  settings.pairing.max_correspondence_distance.to_scaled(scaling.scale()),
                  settings.refinement.min_distance.to_scaled(scaling.scale()),
                  settings.sampling.batch_size * settings.convergence.window) {
    batch_.reserve(settings.sampling.batch_size);
    // The coarse stage pairs with its own cost when refinement stages follow, and with one
    // point per voxel of a map that keeps several (an odometry map): it only has to bring the
    // pose into the refinement's basin, and its wide d_max makes each search in the full map
    // visit thousands of points (docs/design.md, *Coarse view of the map*).
    pairing_.use_cost(settings.refinement.stages > 0 ? settings.coarse_cost : settings.cost);
    if (const ReferenceIndex* coarse = reference.coarse_view();
        coarse != nullptr && settings.refinement.stages > 0) {
      pairing_.search_in(*coarse);
    }
  }

  // Runs from theta until converged, stopped or out of iterations (the reason goes into
  // result); returns the pose to report, in the scaled space. `abandon` (when set) reads theta
  // at the end of each window: true ends the run there, abandoned() then says so.
  PoseVector minimise(PoseVector theta, RegistrationResult& result,
                      const std::function<bool(const PoseVector&)>& abandon = {}) {
    const std::size_t m = settings_.sampling.batch_size;
    for (std::size_t it = 0; it < settings_.max_iterations; ++it) {
      sampler_.next_batch(m, batch_);  // line 2
      const EulerPoseJacobian pose(theta);
      const CostAccumulator cost =  // lines 3-8
          pairing_.accumulate(batch_, pose, schedule_.max_distance(), optimizer_.needs_hessian(),
                              schedule_.pair_distances());
      const PoseVector gradient = cost.gradient(m);  // eq. 6-7
      const PoseVector step = optimizer_.step(gradient, cost.hessian(m), schedule_.step_scale());
      theta += step;  // lines 9-10, eq. 3
      record(theta, cost, result);
      if (stopped(theta, cost.pairs(), result)) return theta;
      const WindowTest test = monitor_.update(gradient, step, cost.pairs(), theta);
      if (test == WindowTest::incomplete) continue;
      if (abandon && abandon(theta)) {
        abandoned_ = true;
        return theta;
      }
      schedule_.end_window();
      if (test == WindowTest::moving) continue;
      ++result.stages;
      if (schedule_.final_stage() || schedule_.settled()) {
        detail::set_stop(result, StopReason::converged, "converged");
        return settings_.average_iterates ? monitor_.window_mean() : theta;
      }
      schedule_.refine();
      begin_refinement();
    }
    detail::set_stop(result, StopReason::max_iterations,
                     detail::iteration_limit_message(settings_.max_iterations));
    return theta;
  }

  // The cost of `batch` at theta with the run's final pairing and cost (for the uncertainty).
  CostAccumulator cost_at(const std::vector<std::uint32_t>& batch, const PoseVector& theta,
                          bool with_hessian) {
    pairing_.use_cost(settings_.cost);  // also when the run ended in its coarse stage
    pairing_.search_in(reference_);
    distances_.clear();
    return pairing_.accumulate(batch, EulerPoseJacobian(theta), schedule_.max_distance(),
                               with_hessian, distances_);
  }

  // The refinement stages pair with the result's cost and, unless told otherwise, step with
  // Gauss-Newton (RefinementSettings::gauss_newton). Not with a robust kernel or trimming:
  // for partial overlap the full Newton steps follow the pull of the pairs that should not be
  // there (the half-cut car pair of tests/test_methods.cpp: 1.2-1.5 m off instead of < 0.5 m).
  void begin_refinement() {
    pairing_.use_cost(settings_.cost);
    pairing_.search_in(reference_);
    // The uncertainty's passes over the whole source (full_pass) then find 1.5x fewer pairs to
    // search: odometry with laplace on the hand-held LiDAR 1.22M -> 0.82M searches (design.md).
    if (settings_.uncertainty.method != UncertaintyType::none) pairing_.start_memory();
    const bool robust =
        settings_.pairing.kernel != KernelType::none || settings_.pairing.trim_ratio < 1.0;
    if (!settings_.refinement.gauss_newton || robust ||
        optimizer_.settings().type == OptimizerType::gauss_newton) {
      return;
    }
    optimizer_ = Optimizer(with_gauss_newton_steps(settings_.optimizer));
  }

  // The gradient of the run's final cost over every point of another source cloud at theta (the
  // uncertainty's grid bootstrap).
  PoseVector gradient_over(const PointCloud& cloud, const PoseVector& theta) {
    pairing_.use_cost(settings_.cost);
    return pairing_.gradient_over(cloud, EulerPoseJacobian(theta), schedule_.max_distance());
  }

  // The pairs' nearest-point memory over the reference, for the final statistics (or null).
  [[nodiscard]] const detail::NearestMemory* nearest_memory() const {
    return pairing_.memory_over(reference_);
  }

  // The normal of reference point i, from the cloud or estimated once (as the plane costs do).
  [[nodiscard]] Eigen::Vector3f reference_normal(std::uint32_t i) {
    return pairing_.reference_normal(i);
  }

  // d_max at the end of the run, scaled.
  [[nodiscard]] double max_distance() const { return schedule_.max_distance(); }
  [[nodiscard]] bool abandoned() const { return abandoned_; }

 private:
  void record(const PoseVector& theta, const CostAccumulator& cost, RegistrationResult& result) {
    result.iterations += 1;
    result.points_processed += batch_.size();
    if (!settings_.record_trace) return;
    result.trace.push_back({result.iterations, result.points_processed,
                            scaling_.to_metric(transform_from_pose(theta)),
                            optimizer_.settings().learning_rate * schedule_.step_scale(),
                            schedule_.max_distance() * scaling_.scale(), cost.pairs(),
                            cost.cost(settings_.sampling.batch_size)});
  }

  // The guards: a pose that blew up, or a whole window of mini-batches without a pair.
  bool stopped(const PoseVector& theta, std::size_t pairs, RegistrationResult& result) {
    // Both clouds lie in the unit box of the scaled space: a translation of 10 box sizes can
    // only come from steps that blew up.
    if (!theta.allFinite() || theta.head<3>().cwiseAbs().maxCoeff() > 10.0) {
      detail::set_stop(result, StopReason::diverged,
                       "the pose diverged (translation beyond 10 times the scene size; step size "
                       "too large for this data?)");
      return true;
    }
    empty_batches_ = pairs == 0 ? empty_batches_ + 1 : 0;
    schedule_.end_batch(pairs);
    if (empty_batches_ < settings_.convergence.window) return false;
    detail::set_stop(result, StopReason::no_correspondences,
                     "no source point had a reference point within d_max = " +
                         std::to_string(schedule_.max_distance() * scaling_.scale()) + " m for " +
                         std::to_string(empty_batches_) + " mini-batches in a row");
    return true;
  }

  const SgdSettings& settings_;
  const UnitCubeScaling& scaling_;
  const ReferenceIndex& reference_;
  MiniBatchPairing pairing_;
  EpochSampler sampler_;
  Optimizer optimizer_;
  ConvergenceMonitor monitor_;
  RefinementSchedule schedule_;
  std::vector<std::uint32_t> batch_;
  std::vector<float> distances_;
  std::size_t empty_batches_ = 0;
  bool abandoned_ = false;
};

}  // namespace

RegistrationResult align(const PointCloud& source, const ReferenceIndex& reference,
                         const SgdSettings& settings, const Eigen::Matrix4d& T_init) {
  return *detail::align_unless(source, reference, settings, T_init, {});
}

std::optional<RegistrationResult> detail::align_unless(const PointCloud& source,
                                                       const ReferenceIndex& reference,
                                                       const SgdSettings& settings,
                                                       const Eigen::Matrix4d& T_init,
                                                       const AbandonTest& abandon) {
  const detail::Stopwatch clock;
  settings.validate();
  detail::check_pair(reference, settings.cost, T_init, detail::SurfaceEstimation::lazy);
  const detail::PairFrame frame(reference);
  const double voxel_m = detail::source_voxel_size(reference, settings.downsampling);
  // The source covariances are set up if either stage's cost needs them.
  const CostType source_needs =
      settings.refinement.stages > 0 && needs_covariances(settings.coarse_cost)
          ? settings.coarse_cost
          : settings.cost;
  const detail::PreparedSource src(
      source, voxel_m, settings.num_threads, frame.origin_m(), source_needs, settings.neighborhood,
      min_source_points(settings),
      settings.adapt_small_sources ? "the smallest mini-batch" : "the mini-batch size",
      detail::SurfaceEstimation::lazy);
  // The run's own copy: m capped and Gauss-Newton steps for a small source.
  SgdSettings run_settings = settings;
  run_settings.sampling.batch_size = batch_size_for(settings, src.cloud().size());
  run_settings.optimizer = optimizer_for(settings, src.cloud().size());
  RegistrationResult result;
  detail::record_clouds(result, src.cloud(), voxel_m, reference);
  const UnitCubeScaling scaling =
      detail::scaling_of(src.cloud(), reference, settings.scaling, result);
  result.scale_m = scaling.scale();
  SgdRun run(src.cloud(), src.index(), reference, run_settings, scaling);
  // Matrices read from text carry few digits: project onto the nearest rotation.
  const PoseVector theta_init =
      pose_from_transform(scaling.to_scaled(frame.to_stored(orthonormalized(T_init))));
  const auto in_clouds = [&](const PoseVector& th) {
    return frame.to_clouds(scaling.to_metric(transform_from_pose(th)));
  };
  std::function<bool(const PoseVector&)> give_up;
  if (abandon) give_up = [&](const PoseVector& th) { return abandon(in_clouds(th)); };
  PoseVector theta = run.minimise(theta_init, result, give_up);
  if (run.abandoned()) return std::nullopt;
  // The uncertainty of any pose the run reports as its estimate (a pose that blew up or lost its
  // pairs has none).
  if (settings.uncertainty.method != UncertaintyType::none &&
      (result.converged || result.stop_reason == StopReason::max_iterations)) {
    const UncertaintyProblem problem{
        [&run](const auto& batch, const PoseVector& th, bool h) {
          return run.cost_at(batch, th, h);
        },
        [&](const PoseVector& th) { return pose_from_transform(in_clouds(th)); },
        &src.cloud(),
        &reference,
        &scaling,
        run.max_distance(),
        scaling.scale(),
        settings.cost,
        run_settings.sampling.batch_size,
        settings.sampling.seed,
        theta_init,
        settings.pairing.trim_ratio >= 1.0,
        [&run](const PointCloud& cloud, const PoseVector& th) {
          return run.gradient_over(cloud, th);
        },
        voxel_m > 0.0 ? &source : nullptr,
        voxel_m,
        frame.origin_m()};
    theta = estimate_uncertainty(problem, settings.uncertainty, theta, result);
  }
  result.T_reference_source = scaling.to_metric(transform_from_pose(theta));
  // The degeneracy check reads the reference normals the run estimated (or would have).
  detail::conclude(
      result, src.cloud(), reference, run.max_distance() * scaling.scale(), settings, clock,
      [&run](std::uint32_t i) { return run.reference_normal(i); }, run.nearest_memory());
  frame.to_clouds(result);
  return result;
}

RegistrationResult align(const PointCloud& source, const PointCloud& reference,
                         const SgdSettings& settings, const Eigen::Matrix4d& T_init) {
  return align(source, reference_index_for(reference, settings), settings, T_init);
}

// The normals and covariances the cost needs are estimated in the run, for the pairs it uses.
ReferenceIndex reference_index_for(const PointCloud& reference, const SgdSettings& settings) {
  return detail::index_for(reference, settings, detail::SurfaceEstimation::lazy);
}

ReferenceIndex reference_index_for(PointCloud&& reference, const SgdSettings& settings) {
  return detail::index_for(std::move(reference), settings, detail::SurfaceEstimation::lazy);
}

}  // namespace sgdicp
