#include "sgdicp/uncertainty/uncertainty.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "sgdicp/points/voxel_grid.hpp"
#include "sgdicp/solver/optimizer.hpp"
#include "sgdicp/solver/sampler.hpp"
#include "surfaces/point_surfaces.hpp"
#include "uncertainty/effective_samples.hpp"
#include "uncertainty/shrinkage.hpp"
#include "uncertainty/stein.hpp"
#include "util/stopwatch.hpp"

namespace sgdicp {

PoseMatrix se3_jacobian(const PoseVector& theta) {
  const Eigen::Matrix3d r = rotation_from_rpy(theta[3], theta[4], theta[5]);
  const auto d = rotation_derivatives(theta[3], theta[4], theta[5]);
  PoseMatrix j = PoseMatrix::Zero();
  j.topLeftCorner<3, 3>() = r.transpose();  // rho = R^T dt
  for (int k = 0; k < 3; ++k) {
    const Eigen::Matrix3d w = r.transpose() * d[k];  // skew(phi) to first order
    j.block<3, 1>(3, 3 + k) << w(2, 1), w(0, 2), w(1, 0);
  }
  return j;
}

namespace {

PoseVector pose_difference(const PoseVector& a, const PoseVector& b) {
  PoseVector d = a - b;
  for (int k = 3; k < 6; ++k) d[k] = wrap_angle(d[k]);
  return d;
}

}  // namespace

PoseMatrix pose_map_jacobian(const std::function<PoseVector(const PoseVector&)>& f,
                             const PoseVector& x, double h) {
  PoseMatrix j;
  for (int k = 0; k < 6; ++k) {
    PoseVector up = x, down = x;
    up[k] += h;
    down[k] -= h;
    j.col(k) = pose_difference(f(up), f(down)) / (2.0 * h);
  }
  return j;
}

namespace {

// The source indices grouped into cubic blocks of side block_m, in a fixed order (sorted keys,
// each block's points in index order), so that sums over blocks do not depend on a hash table's
// order. A map of the few blocks, not a sort of every point: a sort was 5 % of the odometry's
// laplace (perf, hand-held LiDAR).
using Blocks = std::vector<std::vector<std::uint32_t>>;

Blocks blocks_of(const PointCloud& source, double block_m) {
  std::map<std::array<long long, 3>, std::vector<std::uint32_t>> by_key;
  for (std::uint32_t i = 0; i < source.size(); ++i) {
    const Eigen::Vector3d p = source.points[i].cast<double>() / block_m;
    by_key[{static_cast<long long>(std::floor(p.x())), static_cast<long long>(std::floor(p.y())),
            static_cast<long long>(std::floor(p.z()))}]
        .push_back(i);
  }
  Blocks blocks;
  blocks.reserve(by_key.size());
  for (auto& [key, members] : by_key) blocks.push_back(std::move(members));
  return blocks;
}

// Sums over every source point paired at the optimum (scaled space).
struct FullPass {
  PoseMatrix jtj = PoseMatrix::Zero();     // sum w J^T Omega J
  PoseVector jte = PoseVector::Zero();     // sum w J^T Omega e
  PoseMatrix blocks = PoseMatrix::Zero();  // sum over blocks of (block's jte)(block's jte)^T
  double sum_rho = 0.0;                    // sum rho(e^T Omega e)
  std::size_t pairs = 0;
  std::size_t paired_blocks = 0;
};

// Point-to-point pairs of a block with the information of the surface, n n^T.
CostAccumulator surface_cost(const UncertaintyProblem& p, const std::vector<std::uint32_t>& block,
                             const PoseVector& theta, detail::PointSurfaces& surfaces) {
  CostAccumulator cost(KernelType::none, 1.0, true);
  const EulerPoseJacobian pose(theta);
  const double k = p.scaling->scale();
  const auto d_max_sq_m = static_cast<float>(p.max_distance * k * p.max_distance * k);
  for (const std::uint32_t i : block) {
    const Eigen::Vector3d s = p.scaling->to_scaled(p.source->points[i]);
    const Eigen::Vector3d moved = pose.transform(s);
    const auto nn = p.reference->nearest(p.scaling->to_metric(moved).cast<float>(), d_max_sq_m);
    if (!nn) continue;
    // The reference's own normal, or one of its kSurfaceNeighbors nearest points (zero, no
    // information, where they span no plane).
    const Eigen::Vector3d n = surfaces.normal(nn->index).cast<double>();
    const Eigen::Vector3d r = p.scaling->to_scaled(p.reference->cloud().points[nn->index]);
    cost.add(cost.plane_term(pose.jacobian(s), moved - r, n));
  }
  return cost;
}

// With `surfaces` (point-to-point only), the pairs' surface information n n^T; else (nullptr) the
// run's own cost, whose gradient the run drives to zero.
FullPass full_pass(const UncertaintyProblem& p, const Blocks& blocks, const PoseVector& theta,
                   detail::PointSurfaces* surfaces) {
  FullPass out;
  for (const auto& block : blocks) {
    const CostAccumulator c = surfaces != nullptr ? surface_cost(p, block, theta, *surfaces)
                                                  : p.batch_cost(block, theta, true);
    if (c.pairs() == 0) continue;
    const PoseVector g = 2.0 * c.gradient(1);
    out.jtj += 2.0 * c.hessian(1);
    out.jte += g;
    out.blocks += g * g.transpose();
    out.sum_rho += 4.0 * c.cost(1);
    out.pairs += c.pairs();
    ++out.paired_blocks;
  }
  return out;
}

// sum w J^T Omega e over every source point with the run's own pairing and cost.
PoseVector run_cost_gradient(const UncertaintyProblem& p, const Blocks& blocks,
                             const PoseVector& theta) {
  PoseVector sum = PoseVector::Zero();
  for (const auto& block : blocks) {
    sum += 2.0 * p.batch_cost(block, theta, false).gradient(1);
  }
  return sum;
}

bool uses_surface_information(const UncertaintyProblem& p) {
  return p.cost == CostType::point_to_point && p.reference != nullptr;
}

PoseVector prior_information() {
  PoseVector d;
  d << PoseVector::Constant(0.0);
  d.head<3>().setConstant(1.0 / (kPriorTranslationStd * kPriorTranslationStd));
  d.tail<3>().setConstant(1.0 / (kPriorRotationStd * kPriorRotationStd));
  return d;
}

// kappa = tr(H^-1 S) / (6 sigma^2): the mean factor by which the block sandwich H^-1 S H^-1
// exceeds the covariance of independent residuals sigma^2 H^-1 (1 when they are independent).
double correlation_factor(const FullPass& f, double sigma2) {
  const auto b = static_cast<double>(f.paired_blocks);
  if (b <= 6.0) return 1.0;
  // The block gradients sum to (nearly) zero at the optimum: B / (B - 6) undoes that bias.
  const PoseMatrix s = f.blocks * (b / (b - 6.0));
  PoseMatrix h = f.jtj;
  h.diagonal() += sigma2 * prior_information();  // bounded in unconstrained directions
  const double kappa = h.ldlt().solve(s).trace() / (6.0 * sigma2);
  return std::isfinite(kappa) ? std::max(1.0, kappa) : 1.0;
}

// dG/dtheta by forward differences of the full-data gradient G of the run's own cost, its pairs
// found anew at every pose (run_cost_gradient), `steps` along each axis from theta, where G is
// `g_theta` (known from the covariance's own pass): the curvature of the objective the run
// actually minimises. Where nearest neighbours change as the pose moves (noisy points as dense
// as the noise, centroids of voxels that cut a noisy surface), it is far flatter than the
// Gauss-Newton matrix of pairs held fixed, and the error of the optimum that much larger
// (docs/uncertainty.md, *The methods*: laplace). Central differences, 12 passes where these take
// 6, gave the same calibration within a few per cent on every scene and noise level
// (docs/design.md, *The secant's forward differences*).
PoseMatrix secant_curvature(const UncertaintyProblem& p, const Blocks& blocks,
                            const PoseVector& theta, const PoseVector& steps,
                            const PoseVector& g_theta) {
  PoseMatrix a;
  for (int k = 0; k < 6; ++k) {
    PoseVector up = theta;
    up[k] += steps[k];
    a.col(k) = (run_cost_gradient(p, blocks, up) - g_theta) / steps[k];
  }
  return 0.5 * (a + a.transpose());
}

// The directions the data hold in `metric` (the Gauss-Newton matrix of the pairs held fixed, plus
// the prior): where the pairs' information `jtj` is more than half of it. Along a direction the
// data leave free (a plane's slide) the metric is the prior's and a secant measures only noise.
struct HeldDirections {
  PoseMatrix l;  // metric = l l^T
  PoseMatrix l_inverse;
  Eigen::MatrixXd u;  // orthonormal columns in the metric's whitened space, one per direction
};

HeldDirections held_directions(const PoseMatrix& metric, const PoseMatrix& jtj) {
  HeldDirections h;
  h.l = Eigen::LLT<PoseMatrix>(metric).matrixL();
  h.l_inverse = h.l.inverse();
  const PoseMatrix y = h.l_inverse * jtj * h.l_inverse.transpose();
  const Eigen::SelfAdjointEigenSolver<PoseMatrix> share(PoseMatrix(0.5 * (y + y.transpose())));
  std::vector<int> held;
  for (int k = 0; k < 6; ++k) {
    if (share.eigenvalues()[k] > 0.5) held.push_back(k);
  }
  h.u.resize(6, static_cast<Eigen::Index>(held.size()));
  for (std::size_t k = 0; k < held.size(); ++k) {
    h.u.col(static_cast<Eigen::Index>(k)) = share.eigenvectors().col(held[k]);
  }
  return h;
}

// The softening that re-pairing brings to the metric, measured by the secant `a`: one factor for
// every held direction, the geometric mean of a's eigenvalues there in the metric, each kept
// within [kMinSoftening, 1] (re-pairing softens that curvature, it does not stiffen it). The
// secant of one problem's re-paired gradient crosses a few pairing jumps per step, so its
// eigenvalues scatter (0.02-0.72 within one car scan) and the inverse of a scattered curvature
// is biased wide, most of all in the direction measured softest: per direction, the car's
// variance came out 4-6x the errors', one factor 0.8-2.7x (docs/uncertainty.md, *Calibration*).
double measured_softening(const PoseMatrix& a, const HeldDirections& h) {
  if (h.u.cols() == 0) return 1.0;
  const PoseMatrix y = h.l_inverse * a * h.l_inverse.transpose();
  const Eigen::MatrixXd m = h.u.transpose() * PoseMatrix(0.5 * (y + y.transpose())) * h.u;
  const Eigen::VectorXd w =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(m, Eigen::EigenvaluesOnly)
          .eigenvalues()
          .cwiseMax(kMinSoftening)
          .cwiseMin(1.0);
  return std::exp(w.array().log().mean());
}

// The metric softened by `softening` along the held directions, unchanged along the free ones.
PoseMatrix softened_metric(const HeldDirections& h, double softening) {
  const PoseMatrix within = PoseMatrix::Identity() + (softening - 1.0) * h.u * h.u.transpose();
  return h.l * within * h.l.transpose();
}

// The block sandwich of the run's own estimating equation G(theta) = 0: A^-1 S A^-1, A the
// secant curvature, S the covariance of G from its block sums (B / (B - 6) sum g_b g_b^T; the
// independent-residual sigma^2 H when there are too few blocks to measure it).
PoseMatrix sandwich_of(const PoseMatrix& a_inverse, const FullPass& own, double sigma2) {
  const auto b = static_cast<double>(own.paired_blocks);
  PoseMatrix meat =
      b > 6.0 ? PoseMatrix(own.blocks * (b / (b - 6.0))) : PoseMatrix(sigma2 * own.jtj);
  // The prior's own share, as a pseudo-observation with A's prior information: it bounds a
  // direction the data leave free (a plane's slide, where every pair's gradient is zero and the
  // meat alone would say "no error at all"); elsewhere it is negligible.
  meat.diagonal() += sigma2 * sigma2 * prior_information();
  PoseMatrix cov = a_inverse * meat * a_inverse.transpose();
  return 0.5 * (cov + cov.transpose());
}

// The secant's steps: at most half the final d_max (a rotation: half of it at half the scaled
// cloud's unit radius), where the pairs the run keeps still exist.
PoseVector secant_steps(PoseVector steps, const UncertaintyProblem& p) {
  const double cap = kMaxSecantStep * p.max_distance;
  steps.head<3>() = steps.head<3>().cwiseMin(cap);
  steps.tail<3>() = steps.tail<3>().cwiseMin(2.0 * cap);
  return steps.cwiseMax(1e-12);
}

struct SandwichEstimate {
  PoseVector theta;        // scaled: the optimum of the re-paired objective
  PoseMatrix covariance;   // scaled theta
  PoseMatrix a_inverse;    // the inverse secant curvature (with the prior) at theta
  double softening = 1.0;  // measured by the secant, or the one given
};

// The covariance of the optimum of the re-paired objective, and that optimum: a secant at
// kSecantFirstStep standard deviations of the tempered Laplace covariance `laplace` (about the
// scale of the error it describes), and a Newton step with it towards the optimum: the fixed
// pairs' Gauss-Newton steps under-step there by the softening. A second secant at the scale of
// the first estimate changed no figure of the calibration beyond its trial-to-trial spread
// (docs/uncertainty.md), for 6 more passes over the source. A softening `given` (> 0) is used
// instead of the secant's: its 6 passes are skipped (the odometry reuses its frames' own).
SandwichEstimate sandwich_estimate(const UncertaintyProblem& p, const Blocks& blocks,
                                   PoseVector theta, const FullPass& full, double sigma2,
                                   const PoseMatrix& laplace, double given) {
  PoseMatrix metric = full.jtj;
  metric.diagonal() += sigma2 * prior_information();
  const PoseMatrix prior = (sigma2 * prior_information()).asDiagonal();
  FullPass own = uses_surface_information(p) ? full_pass(p, blocks, theta, nullptr) : full;
  const PoseVector steps = secant_steps(kSecantFirstStep * laplace.diagonal().cwiseSqrt(), p);
  const HeldDirections held = held_directions(metric, full.jtj);
  const double softening =
      given > 0.0 ? given  // in [kMinSoftening, 1] (SgdSettings::validate)
                  : measured_softening(secant_curvature(p, blocks, theta, steps, own.jte), held);
  const PoseMatrix a = softened_metric(held, softening) + prior;
  const PoseMatrix a_inverse = a.inverse();
  PoseMatrix cov = sandwich_of(a_inverse, own, sigma2);
  // Newton's step on G, within the secant's steps along each axis, either way (a flat secant
  // would send it far off on a sparse cloud), taken when the pairs' mean cost does not grow and
  // they stay.
  PoseVector step = a_inverse * own.jte;
  step *= std::min(1.0, (steps.array() / step.array().abs()).minCoeff());
  const FullPass moved = full_pass(p, blocks, theta - step, nullptr);
  if (step.allFinite() && moved.pairs >= own.pairs - own.pairs / 20 &&
      moved.sum_rho / static_cast<double>(std::max<std::size_t>(moved.pairs, 1)) <=
          own.sum_rho / static_cast<double>(std::max<std::size_t>(own.pairs, 1))) {
    theta -= step;
    own = moved;
    cov = sandwich_of(a_inverse, own, sigma2);
  }
  return {theta, cov, a_inverse, softening};
}

// The source thinned on its grid shifted by `offset` (metres), in the pair's frame.
PointCloud thinned_on_shifted_grid(const UncertaintyProblem& p, const Eigen::Vector3d& offset) {
  PointCloud shifted = *p.unthinned_source;
  const Eigen::Vector3f o = offset.cast<float>();
  for (Eigen::Vector3f& q : shifted.points) q -= o;
  PointCloud out = voxel_downsample(shifted, p.voxel_m);
  for (Eigen::Vector3f& q : out.points) q += o;
  return out.origin_m == p.frame_origin_m ? out : rebased(out, p.frame_origin_m);
}

// The grid bootstrap: a voxel's centroid of a noisy surface is pulled off it wherever the voxel
// cuts the noise's thickness, the same way along a whole wall that lies along the grid, and
// differently in the source's grid and the reference's. That error is coherent, the residuals do
// not show it, and on dense clouds as noisy as a tenth of a voxel it is most of the pose's error
// (the 7-Scenes frame at 1 cm: 15 mm in single problems against a sandwich of 0.5 mm;
// docs/uncertainty.md, *The grid's own error*). Thinning the source on kGridOffsets grids shifted
// at random, each one's optimum is a Newton step away, -A^-1 G_k; the covariance of those optima
// (the actual grid's among them) is the grid's share of the error. Seven draws in 6-D give a
// covariance whose inverse has no finite mean (the 7-Scenes frame at 3 cm: mean NEES 29, median
// 11), so it is shrunk toward the sandwich's shape `shape` (docs/design.md, *The grid's share,
// shrunk*). Where the first grids put the share below a fraction of the sandwich, the rest are
// skipped (detail::grid_share).
PoseMatrix grid_covariance(const UncertaintyProblem& p, const PoseVector& theta,
                           const PoseMatrix& a_inverse, const PoseMatrix& shape) {
  if (p.unthinned_source == nullptr || !(p.voxel_m > 0.0) || !p.cloud_gradient) {
    return PoseMatrix::Zero();
  }
  std::mt19937_64 engine(p.seed ^ 0x5851f42d4c957f2dULL);
  const auto uniform = [&engine] { return static_cast<double>(engine() >> 11) * 0x1.0p-53; };
  const auto optimum_on_grid = [&](int) -> std::optional<PoseVector> {
    const Eigen::Vector3d offset = p.voxel_m * Eigen::Vector3d(uniform(), uniform(), uniform());
    const PoseVector g = p.cloud_gradient(thinned_on_shifted_grid(p, offset), theta);
    if (!g.allFinite()) return std::nullopt;
    return PoseVector(-(a_inverse * g));
  };
  return detail::grid_share(optimum_on_grid, shape).covariance;
}

// Normal deviates from a fully specified engine and Box-Muller, so that a seed gives the same
// chain with any standard library (std::normal_distribution is implementation-defined).
class Gaussian {
 public:
  explicit Gaussian(std::uint64_t seed) : engine_(seed ^ 0x9e3779b97f4a7c15ULL) {}
  double operator()() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = (static_cast<double>(engine_() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
    const double u2 = static_cast<double>(engine_() >> 11) * 0x1.0p-53;
    const double radius = std::sqrt(-2.0 * std::log(u1));
    spare_ = radius * std::sin(2.0 * std::numbers::pi * u2);
    has_spare_ = true;
    return radius * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

struct Posterior {
  PoseVector theta_hat;  // scaled
  PoseVector jte_hat;    // full-data sum w J^T Omega e at theta_hat
  double inv_variance;   // 1 / (sigma^2 tau)
  PoseMatrix precision;  // H / (sigma^2 tau) + prior
};

// g_batch(theta): sum w J^T Omega e over a mini-batch with the run's own pairing and cost.
PoseVector batch_gradient(const UncertaintyProblem& p, const std::vector<std::uint32_t>& batch,
                          const PoseVector& theta) {
  return 2.0 * p.batch_cost(batch, theta, false).gradient(1);
}

// The control variate's g_batch(theta_hat) of every mini-batch. When the batch cost is a sum over
// its points (no trimming), each point's gradient at the optimum is paired once, and a batch's
// is the sum of its points': one pairing per iteration instead of two (sgld), K instead of
// K + 1 (svgd). Otherwise the batch is paired at theta_hat again.
class OptimumGradients {
 public:
  OptimumGradients(const UncertaintyProblem& p, const PoseVector& theta_hat)
      : p_(p), theta_hat_(theta_hat) {
    if (!p.additive_batches) return;
    per_point_.reserve(p.source->size());
    std::vector<std::uint32_t> one(1);
    for (std::uint32_t i = 0; i < p.source->size(); ++i) {
      one[0] = i;
      per_point_.push_back(batch_gradient(p, one, theta_hat));
    }
  }
  [[nodiscard]] PoseVector operator()(const std::vector<std::uint32_t>& batch) const {
    if (per_point_.empty()) return batch_gradient(p_, batch, theta_hat_);
    PoseVector sum = PoseVector::Zero();
    for (const std::uint32_t i : batch) sum += per_point_[i];
    return sum;
  }
  // The full-data gradient at the optimum, when the points' gradients are known.
  [[nodiscard]] std::optional<PoseVector> full() const {
    if (per_point_.empty()) return std::nullopt;
    PoseVector sum = PoseVector::Zero();
    for (const PoseVector& g : per_point_) sum += g;
    return sum;
  }

 private:
  const UncertaintyProblem& p_;
  PoseVector theta_hat_;
  std::vector<PoseVector> per_point_;
};

// grad U at theta from one mini-batch, with the control variate of the optimum (Baker et al.
// 2019): grad U(theta_hat) + N/m (g_batch(theta) - g_batch(theta_hat)), plus the prior's;
// at_hat = g_batch(theta_hat).
PoseVector energy_gradient(const UncertaintyProblem& p, const Posterior& post,
                           const std::vector<std::uint32_t>& batch, const PoseVector& theta,
                           const PoseVector& at_hat) {
  const double n_over_m = static_cast<double>(p.source->size()) /
                          static_cast<double>(std::min(p.batch_size, p.source->size()));
  return (post.jte_hat + n_over_m * (batch_gradient(p, batch, theta) - at_hat)) *
             post.inv_variance +
         prior_information().cwiseProduct(theta - p.theta_init);
}

// The space whitened by the Laplace precision P = L L^T: z = L^T (theta - theta_hat), one unit
// one posterior standard deviation along every axis, so that distances compare translation
// (scaled units) and rotation (rad) on one scale; gradients map by grad_z = L^-1 grad_theta.
struct Whitening {
  PoseVector theta_hat;
  Eigen::LLT<PoseMatrix> llt;
  [[nodiscard]] PoseVector theta(const PoseVector& z) const {
    return theta_hat + llt.matrixU().solve(z);
  }
  [[nodiscard]] PoseVector gradient(const PoseVector& grad_theta) const {
    return llt.matrixL().solve(grad_theta);
  }
};

// Pre-conditioned SGLD (Li et al. 2016, eq. 4 without the Gamma term) on the energy
// U = sum rho / (2 sigma^2 tau) - log prior, whose gradient is estimated on a mini-batch with
// the control variate of the optimum. The chain runs in the space whitened by the Laplace
// precision, where the curvature is about the identity: RMSProp's diagonal alone leaves the
// correlations between axes (KITTI's rotation and translation), and a step that suits the
// stiffest axis then mixes the soft directions too slowly (measured: docs/uncertainty.md).
std::vector<PoseVector> sgld_chain(const UncertaintyProblem& p, const UncertaintySettings& s,
                                   const Posterior& post, const Whitening& white,
                                   const OptimumGradients& at_hat) {
  // RMSProp's mean square starts at its stationary value, the whitened curvature (E[(grad U)^2]
  // = 1 for a Gaussian), so no warm-up is spent on it.
  PoseVector mean_square = PoseVector::Ones();
  // eps such that every axis contracts by `step` per iteration: eps sqrt(1) / 2.
  const double eps = 2.0 * s.step;
  constexpr double kDecay = 0.99;  // Li et al. 2016
  EpochSampler sampler(static_cast<std::uint32_t>(p.source->size()), p.seed + 1);
  Gaussian normal(p.seed);
  std::vector<std::uint32_t> batch;
  std::vector<PoseVector> samples;
  samples.reserve(s.samples);
  PoseVector z = PoseVector::Zero();  // the estimate
  const std::size_t iterations = s.burn_in + s.samples * s.thinning;
  for (std::size_t it = 1; it <= iterations; ++it) {
    sampler.next_batch(p.batch_size, batch);
    const PoseVector grad =
        white.gradient(energy_gradient(p, post, batch, white.theta(z), at_hat(batch)));
    mean_square = kDecay * mean_square + (1.0 - kDecay) * grad.cwiseProduct(grad);
    const PoseVector g = mean_square.cwiseSqrt().cwiseInverse();
    for (int k = 0; k < 6; ++k) {
      z[k] += -0.5 * eps * g[k] * grad[k] + std::sqrt(eps * g[k]) * normal();
    }
    if (it > s.burn_in && (it - s.burn_in) % s.thinning == 0) samples.push_back(white.theta(z));
  }
  return samples;
}

// Stein ICP (Maken et al. 2022) in the whitened space, where the kernel's distances are taken.
// The particles start at N(0, spread^2 I), the Laplace covariance inflated by spread^2. Returns z.
std::vector<PoseVector> svgd_particles(const UncertaintyProblem& p, const UncertaintySettings& s,
                                       const Posterior& post, const Whitening& white,
                                       const OptimumGradients& optimum_gradients) {
  EpochSampler sampler(static_cast<std::uint32_t>(p.source->size()), p.seed + 1);
  Gaussian normal(p.seed);
  std::vector<PoseVector> z(s.particles);
  for (PoseVector& zi : z) {
    for (int k = 0; k < 6; ++k) zi[k] = s.svgd_spread * normal();
  }
  std::vector<std::uint32_t> batch;
  // One mini-batch per iteration for every particle (and one control-variate term for all).
  const ParticleGradients gradients = [&](const std::vector<PoseVector>& zs,
                                          std::vector<PoseVector>& grads) {
    sampler.next_batch(p.batch_size, batch);
    const PoseVector at_hat = optimum_gradients(batch);
    for (std::size_t i = 0; i < zs.size(); ++i) {
      grads[i] = white.gradient(energy_gradient(p, post, batch, white.theta(zs[i]), at_hat));
    }
  };
  return stein_descent(std::move(z), gradients, s.svgd_iterations, kSvgdFirstStep * s.svgd_spread,
                       s.svgd_step);
}

struct Moments {
  PoseVector mean;
  PoseMatrix covariance;
};

// Mean and covariance of reported poses, the angles averaged as offsets from `origin`.
Moments moments_of(const std::vector<PoseVector>& poses, const PoseVector& origin) {
  PoseVector mean_offset = PoseVector::Zero();
  for (const PoseVector& x : poses) mean_offset += pose_difference(x, origin);
  const auto n = static_cast<double>(poses.size());
  mean_offset /= n;
  Moments m{origin + mean_offset, PoseMatrix::Zero()};
  for (int k = 3; k < 6; ++k) m.mean[k] = wrap_angle(m.mean[k]);
  for (const PoseVector& x : poses) {
    const PoseVector d = pose_difference(x, origin) - mean_offset;
    m.covariance += d * d.transpose();
  }
  m.covariance /= std::max(1.0, n - 1.0);
  return m;
}

void fill_from_samples(const UncertaintyProblem& p, const std::vector<PoseVector>& chain,
                       const PoseVector& reported_hat, RegistrationResult& result) {
  result.samples.clear();
  for (const PoseVector& theta : chain) result.samples.push_back(p.to_reported(theta));
  const Moments m = moments_of(result.samples, reported_hat);
  result.sample_mean = m.mean;
  result.covariance = m.covariance;
}

// svgd: the particles as samples, their modes (each averaged from its own first particle, so
// that a mode half a turn away is not wrapped), and the heaviest mode's covariance.
void fill_from_particles(const UncertaintyProblem& p, const std::vector<PoseVector>& z,
                         const Whitening& white, const PoseVector& reported_hat,
                         RegistrationResult& result) {
  std::vector<PoseVector> thetas;
  for (const PoseVector& zi : z) thetas.push_back(white.theta(zi));
  fill_from_samples(p, thetas, reported_hat, result);
  result.modes.clear();
  // Particles the kernel cannot tell apart (k > 0.94) share their gradients and move as one.
  for (const auto& members : particle_modes(z, detail::particle_link(z))) {
    std::vector<PoseVector> poses;
    for (const std::size_t i : members) poses.push_back(result.samples[i]);
    const Moments m = moments_of(poses, poses.front());
    result.modes.push_back({static_cast<double>(members.size()) / static_cast<double>(z.size()),
                            m.mean, m.covariance});
  }
  result.covariance = result.modes.front().covariance;
}

}  // namespace

PoseVector estimate_uncertainty(const UncertaintyProblem& p, const UncertaintySettings& s,
                                PoseVector theta_hat, RegistrationResult& result) {
  if (s.method == UncertaintyType::none) return theta_hat;
  const detail::Stopwatch clock;
  // SGD stops within the noise ball of its mini-batch gradient, which is wider than the
  // posterior: Gauss-Newton steps on every pair bring the estimate to the full-data optimum
  // that the covariance describes (measured: docs/uncertainty.md).
  const Blocks blocks = blocks_of(*p.source, s.block_size.to_metres(p.scale_m));
  // The reference's normals of the surface information, estimated on first use and kept for the
  // polish steps' passes (point-to-point only).
  std::optional<detail::PointSurfaces> surfaces;
  if (uses_surface_information(p)) {
    surfaces.emplace(*p.reference, NeighborhoodSettings{.k = kSurfaceNeighbors});
  }
  detail::PointSurfaces* const information = surfaces ? &*surfaces : nullptr;
  FullPass full = full_pass(p, blocks, theta_hat, information);
  for (int step = 0; step < kPolishSteps && full.pairs > 6; ++step) {
    PoseMatrix h = full.jtj;
    h.diagonal() += 1e-9 * h.trace() * PoseVector::Ones() + 1e-12 * prior_information();
    theta_hat -= h.ldlt().solve(full.jte);
    full = full_pass(p, blocks, theta_hat, information);
  }
  result.uncertainty_pairs = full.pairs;
  const auto residuals = static_cast<double>(full.pairs * residuals_per_pair(p.cost));
  const PoseVector reported_hat = p.to_reported(theta_hat);
  if (residuals <= 6.0 || !(full.sum_rho > 0.0)) {
    result.covariance.setConstant(std::numeric_limits<double>::quiet_NaN());
    result.covariance_se3 = result.covariance;
    result.message += "; no uncertainty: too few pairs at the optimum";
    return theta_hat;
  }
  const double sigma2 = full.sum_rho / (residuals - 6.0);  // scaled units^2
  result.residual_sigma_m = std::sqrt(sigma2) * p.scale_m;
  result.correlation_factor = correlation_factor(full, sigma2);
  const double tau = s.temper ? result.correlation_factor : 1.0;
  Posterior post{theta_hat, full.jte, 1.0 / (sigma2 * tau), full.jtj / (sigma2 * tau)};
  post.precision.diagonal() += prior_information();
  if (s.method == UncertaintyType::laplace) {
    PoseMatrix cov = post.precision.ldlt().solve(PoseMatrix::Identity());
    if (s.temper) {
      const SandwichEstimate sandwich =
          sandwich_estimate(p, blocks, theta_hat, full, sigma2, cov, s.softening);
      result.softening = sandwich.softening;
      theta_hat = sandwich.theta;
      cov = sandwich.covariance +
            grid_covariance(p, theta_hat, sandwich.a_inverse, sandwich.covariance);
    }
    const PoseMatrix jm = pose_map_jacobian(p.to_reported, theta_hat);
    result.covariance = jm * cov * jm.transpose();
  } else {
    const OptimumGradients at_hat(p, theta_hat);
    // The control variate needs the full-data gradient of the energy the chain samples, the
    // run's own cost (point-to-point: not the surface information's).
    if (const auto full_gradient = at_hat.full()) {
      post.jte_hat = *full_gradient;
    } else if (p.cost == CostType::point_to_point) {
      post.jte_hat = run_cost_gradient(p, blocks, theta_hat);
    }
    const Whitening white{theta_hat, Eigen::LLT<PoseMatrix>(post.precision)};
    if (s.method == UncertaintyType::sgld) {
      fill_from_samples(p, sgld_chain(p, s, post, white, at_hat), reported_hat, result);
      result.effective_samples = detail::effective_sample_size(result.samples);
      if (result.effective_samples < kFewEffectiveSamples) {
        result.message += "; sgld: its " + std::to_string(result.samples.size()) +
                          " samples are worth " +
                          std::to_string(static_cast<int>(std::lround(result.effective_samples))) +
                          " independent draws: the covariance's own sampling error is large "
                          "(more uncertainty_samples, or laplace)";
      }
    } else {
      fill_from_particles(p, svgd_particles(p, s, post, white, at_hat), white, reported_hat,
                          result);
    }
  }
  result.covariance = 0.5 * (result.covariance + result.covariance.transpose()).eval();
  const PoseMatrix js = se3_jacobian(p.to_reported(theta_hat));
  result.covariance_se3 = js * result.covariance * js.transpose();
  result.uncertainty_ms = clock.elapsed_ms();
  return theta_hat;
}

}  // namespace sgdicp
