// The settings tables (settings.hpp): every setting of both solvers once, with its name, field,
// range, unit and help, which the CLI, Python and docs/registration.md read.
#include "sgdicp/registration/settings.hpp"

#include <algorithm>
#include <array>
#include <string_view>
#include <vector>

#include "registration/setting_rows.hpp"
#include "sgdicp/core/threads.hpp"

namespace sgdicp {

// ---- the tables

namespace {

using detail::common;
using detail::Describe;
using detail::setting;
using S = SgdSettings;
using B = BatchSettings;
using O = OptimizerSettings;
using C = ConvergenceSettings;
using R = RefinementSettings;
using N = NeighborhoodSettings;
using U = UncertaintySettings;
using SA = SamplingSettings;
using P = PairingSettings;
using SC = ScalingSettings;
using E = EvaluationSettings;
using D = DownsamplingSettings;

// Ranges (docs/registration.md explains each): wide enough for every real use, from a 15 cm
// scan to a km-scale map, narrow enough that no value crashes, allocates absurdly or returns the
// initial pose as if converged.
constexpr double kUint64Max = 0x1p64;
// A distance in scaled units: a millionth of the scene (below that, float32 coordinates cannot
// resolve it) to ten scenes (the pose is declared diverged there).
constexpr ValueRange kScaledRange{1e-6, 10.0};
// The fixed step is a gradient multiplier: large ones are legitimate on small gradients, and a
// step that blows the pose up is reported as diverged.
constexpr ValueRange kLearningRate{1e-6, 1e4};
constexpr ValueRange kDamping{0.0, 100.0};
constexpr ValueRange kTolerance{0.0, 0.01};
constexpr ValueRange kTrim{0.01, 1.0};
constexpr ValueRange kIterations{1.0, 1e9};
constexpr ValueRange kNeighbors{3.0, 1000.0};
constexpr ValueRange kEvaluationPoints{0.0, 4294967295.0};
constexpr ValueRange kThreads{0.0, static_cast<double>(kMaxThreads)};
// A voxel side: 0 (no fixed grid) up to 1000 km; sizes too small for the coordinates are
// refused when the grid is built (voxel indices beyond 2^62).
constexpr ValueRange kVoxelSize{0.0, 1e6};
constexpr ValueRange kDownsampleTo{0.0, 4294967295.0};

// The shared texts of settings that both solvers have.
constexpr std::string_view kMaxDistanceHelp = "Correspondence rejection distance d_max";
constexpr std::string_view kKernelHelp = "Robust kernel on the pair residuals";
constexpr std::string_view kKernelScaleHelp =
    "Kernel scale c, the residual size where down-weighting starts";
constexpr std::string_view kTrimHelp =
    "Keep only this fraction of the pairs (per mini-batch for SGD, per iteration for batch "
    "methods), the closest ones: trimmed ICP for partial overlap";
constexpr std::string_view kVoxelSizeHelp =
    "Thin both clouds to one point (the centroid) per voxel of this side before registering "
    "(timed), 0 = the grid --downsample-to chooses";
constexpr std::string_view kDownsampleToHelp =
    "Without --voxel-size: the voxel grid that keeps about this many points of the reference "
    "(chosen from the data, +-15 %), applied to both clouds; clouds with at most this many "
    "points, or with normals or covariances given, are used as they are; 0 = no downsampling";
constexpr std::string_view kThreadsHelp =
    "Threads of one registration (its voxel grid passes, KD-tree build, for the SGD plane costs "
    "the grid's reference normals, the SGD mini-batches' queries and the final statistics' on "
    "a second thread), "
    "0 = every core; the result is the same for any count";
constexpr std::string_view kNeighborsHelp =
    "Plane costs: neighbours per point (itself included) for normals and covariances";
constexpr std::string_view kEvaluationHelp =
    "Source points (spread evenly) used for the final inlier ratio and RMSE, 0 = all";
constexpr std::string_view kTraceHelp = "Record a per-iteration trace in the result";
constexpr std::string_view kCostHelp =
    "Cost of a pair: point-to-point (the paper), point-to-plane or plane-to-plane (GICP)";

Setting<S> optimizer_setting() {
  Setting<S> s = setting<S, &S::optimizer, &O::type>(
      {"optimizer",
       "optimizer.type",
       {},
       {},
       "Step rule of eq. 3 (sgd: fixed step; gauss-newton: A = inverse of the averaged "
       "mini-batch Gauss-Newton matrix); also sets the learning rate to the rule's own unless "
       "one is given"});
  s.set = [](S& x, const SettingValue& v) {
    x.optimizer.type = parse_enum<OptimizerType>(std::get<std::string>(v));
    x.optimizer.learning_rate = default_learning_rate(x.optimizer.type);
  };
  return s;
}

// Named, the cost is the cost of every stage, as a method named for its cost (methods.hpp); a
// coarse-cost named after it (table order) sets the first stage's.
Setting<S> cost_setting() {
  Setting<S> s = setting<S, &S::cost>(
      {"cost",
       "cost",
       {},
       "",
       "Cost of a pair in every stage (a coarse-cost given too sets the first stage's): "
       "point-to-point (the paper), point-to-plane or plane-to-plane (GICP)",
       true});
  s.set = [](S& x, const SettingValue& v) {
    x.cost = x.coarse_cost = parse_enum<CostType>(std::get<std::string>(v));
  };
  return s;
}

// The step rule and the mini-batch (the first: "optimizer" sets the learning rate).
std::vector<Setting<S>> step_settings() {
  return {
      optimizer_setting(),
      setting<S, &S::optimizer, &O::learning_rate>(
          {"learning-rate", "optimizer.learning_rate", kLearningRate, "scaled units",
           "Step size alpha (adaptive rules: a length per step; sgd, momentum: a gradient "
           "multiplier; gauss-newton: a fraction of the Newton step)"}),
      setting<S, &S::sampling, &SA::batch_size>({"batch-size",
                                                 "sampling.batch_size",
                                                 {1.0, 1e7},
                                                 "",
                                                 "Mini-batch size m, source points per iteration"}),
      common(setting<S, &S::pairing, &P::max_correspondence_distance>(
          {"max-distance", "pairing.max_correspondence_distance", kScaledRange, "",
           kMaxDistanceHelp})),
      setting<S, &S::max_iterations>(
          {"max-iterations", "max_iterations", kIterations, "",
           "Iteration limit (mini-batches); reaching it reports 'not converged'"}),
      common(setting<S, &S::sampling, &SA::seed>(
          {"seed",
           "sampling.seed",
           {0.0, kUint64Max},
           "",
           "Seed of the mini-batch sampler (same seed, same result)"})),
      setting<S, &S::optimizer, &O::damping>(
          {"damping", "optimizer.damping", kDamping, "",
           "Gauss-Newton step: Levenberg damping, relative to the mean diagonal of the averaged "
           "matrix (batch methods: the initial Levenberg-Marquardt damping)"}),
  };
}

// When a stage, and the run, stop.
std::vector<Setting<S>> stop_settings() {
  return {
      setting<S, &S::convergence, &C::window>(
          {"window",
           "convergence.window",
           {8.0, 1e5},
           "",
           "Convergence: iterations per test window (a stage ends after a window whose mean "
           "mini-batch gradient is not significantly non-zero); also the length of the final "
           "iterate average"}),
      setting<S, &S::convergence, &C::chi2>(
          {"chi2",
           "convergence.chi2",
           {0.0, 1000.0, true, false},
           "",
           "Convergence: critical chi-square value (6 dof) of the Hotelling test on the "
           "window's mean gradient; larger stops earlier"}),
      setting<S, &S::convergence, &C::translation_tolerance>(
          {"translation-tolerance", "convergence.translation_tolerance", kTolerance, "scaled units",
           "Convergence: a window whose steps each move the translation less than this also "
           "ends a stage (batch methods: an iteration that moves it less converges)"}),
      setting<S, &S::convergence, &C::rotation_tolerance>(
          {"rotation-tolerance", "convergence.rotation_tolerance", kTolerance, "rad",
           "Convergence: ... and the angles less than this (sum of |d roll|, |d pitch|, "
           "|d yaw|; batch methods: rotation angle)"}),
      setting<S, &S::refinement, &R::stages>(
          {"refine-stages",
           "refinement.stages",
           {0.0, 100.0},
           "",
           "Refinement stages after the first stationary stage (0 = the paper's single "
           "phase)"}),
      setting<S, &S::refinement, &R::step_decay>({"step-decay",
                                                  "refinement.step_decay",
                                                  {0.01, 1.0},
                                                  "",
                                                  "Refinement: step-size multiplier per stage"}),
      setting<S, &S::refinement, &R::distance_factor>(
          {"distance-factor",
           "refinement.distance_factor",
           {1.0, 1000.0},
           "",
           "Refinement: new d_max = factor x median correspondence distance (below 1 it would "
           "reject most pairs: use trim for that)"}),
      setting<S, &S::refinement, &R::min_distance>({"min-distance", "refinement.min_distance",
                                                    kScaledRange, "",
                                                    "Refinement: lower bound of d_max"}),
  };
}

// What is returned, and how pairs are weighed.
std::vector<Setting<S>> result_and_pair_settings() {
  return {
      setting<S, &S::average_iterates>(
          {"average",
           "average_iterates",
           {},
           "",
           "Return the mean of the window iterates of the final stage's stationary window "
           "(true) or the last iterate (false)"}),
      setting<S, &S::scaling, &SC::origin>(
          {"scaling-origin",
           "scaling.origin",
           {},
           "",
           "Origin of the scaled space and pivot of the rotation (lower-corner, also spelled "
           "corner: the paper, points in [0, 1]; center: points in [-0.5, 0.5])"}),
      setting<S, &S::evaluation, &E::evaluation_points>({"evaluation-points",
                                                         "evaluation.evaluation_points",
                                                         kEvaluationPoints, "", kEvaluationHelp}),
      cost_setting(),
      setting<S, &S::coarse_cost>(
          {"coarse-cost",
           "coarse_cost",
           {},
           "",
           "Cost of the first (coarse) stage when refinement stages follow (the refinement "
           "stages and the result use the method's cost): point-to-point keeps the paper's wide "
           "basin"}),
      setting<S, &S::pairing, &P::kernel>({"kernel", "pairing.kernel", {}, "", kKernelHelp}),
      setting<S, &S::pairing, &P::kernel_scale>(
          {"kernel-scale", "pairing.kernel_scale", kScaledRange, "", kKernelScaleHelp}),
      setting<S, &S::pairing, &P::trim_ratio>({"trim", "pairing.trim_ratio", kTrim, "", kTrimHelp}),
      setting<S, &S::neighborhood, &N::k>(
          {"neighbors", "neighborhood.k", kNeighbors, "", kNeighborsHelp}),
      common(setting<S, &S::num_threads>({"threads", "num_threads", kThreads, "", kThreadsHelp})),
      common(setting<S, &S::downsampling, &D::voxel_size_m>(
          {"voxel-size", "downsampling.voxel_size_m", kVoxelSize, "m", kVoxelSizeHelp})),
      setting<S, &S::downsampling, &D::downsample_to>(
          {"downsample-to", "downsampling.downsample_to", kDownsampleTo, "", kDownsampleToHelp}),
      setting<S, &S::record_trace>({"record-trace", "record_trace", {}, "", kTraceHelp, true}),
  };
}

// The pose uncertainty of the result (docs/uncertainty.md).
std::vector<Setting<S>> uncertainty_settings() {
  return {
      common(setting<S, &S::uncertainty, &U::method>(
          {"uncertainty",
           "uncertainty.method",
           {},
           "",
           "Pose uncertainty of the result: none, laplace (sandwich covariance of the re-paired "
           "optimum: the one to use for a pose graph), sgld (Bayesian ICP: Langevin samples) or "
           "svgd (Stein ICP: "
           "particles, clustered into modes)"})),
      setting<S, &S::uncertainty, &U::samples>(
          {"uncertainty-samples", "uncertainty.samples", {2.0, 1e6}, "", "sgld: samples kept"}),
      setting<S, &S::uncertainty, &U::thinning>(
          {"thinning", "uncertainty.thinning", {1.0, 1e4}, "", "sgld: iterations per sample"}),
      setting<S, &S::uncertainty, &U::particles>(
          {"particles", "uncertainty.particles", {1.0, 1e4}, "", "svgd: particles K"}),
      setting<S, &S::uncertainty, &U::svgd_iterations>(
          {"svgd-iterations",
           "uncertainty.svgd_iterations",
           {1.0, 1e6},
           "",
           "svgd: iterations, one mini-batch shared by every particle each"}),
      setting<S, &S::uncertainty, &U::svgd_spread>(
          {"svgd-spread",
           "uncertainty.svgd_spread",
           {1e-3, 1e9},
           "posterior std",
           "svgd: spread of the initial particles around the estimate, in Laplace standard "
           "deviations (wide values reach other modes)"}),
      setting<S, &S::uncertainty, &U::temper>(
          {"temper",
           "uncertainty.temper",
           {},
           "",
           "laplace: the sandwich of the re-paired optimum and the grid's share; sgld, svgd: "
           "the likelihood tempered by the residuals' measured correlation (false: the "
           "fixed-pair Hessian with independent residuals, as the peers report)"}),
  };
}

// The members no user names (settings.hpp, *Fixed rules*): checked by validate() with their C++
// names, never CLI options or Python keywords.
std::vector<Setting<S>> make_fixed_rules_table() {
  return {
      setting<S, &S::convergence, &C::max_path_efficiency>(
          {"convergence.max_path_efficiency",
           "convergence.max_path_efficiency",
           {0.0, 1.0, true, false},
           "",
           "A stationary window's net displacement over its path length"}),
      setting<S, &S::refinement, &R::gauss_newton>(
          {"refinement.gauss_newton",
           "refinement.gauss_newton",
           {},
           "",
           "The refinement stages take Gauss-Newton steps"}),
      setting<S, &S::refinement, &R::settle_tolerance>(
          {"refinement.settle_tolerance",
           "refinement.settle_tolerance",
           {0.0, 0.99},
           "",
           "A refinement stage ends the run when its pairs have settled"}),
      setting<S, &S::uncertainty, &U::burn_in>({"uncertainty.burn_in",
                                                "uncertainty.burn_in",
                                                {0.0, 1e7},
                                                "",
                                                "sgld: iterations before the first sample"}),
      setting<S, &S::uncertainty, &U::step>({"uncertainty.step",
                                             "uncertainty.step",
                                             {1e-4, 1.0},
                                             "",
                                             "sgld: contraction per iteration"}),
      setting<S, &S::uncertainty, &U::svgd_step>({"uncertainty.svgd_step",
                                                  "uncertainty.svgd_step",
                                                  {1e-4, 10.0},
                                                  "posterior std",
                                                  "svgd: Adam's last step"}),
      setting<S, &S::uncertainty, &U::block_size>({"uncertainty.block_size",
                                                   "uncertainty.block_size", kScaledRange, "",
                                                   "Block side of the sandwich estimator"}),
      setting<S, &S::uncertainty, &U::softening>({"uncertainty.softening",
                                                  "uncertainty.softening",
                                                  {0.0, 1.0},
                                                  "",
                                                  "laplace: the curvature's softening to use, 0 = "
                                                  "measure it (the secant); (0, 0.1) refused"}),
  };
}

std::vector<Setting<S>> make_sgd_table() {
  std::vector<Setting<S>> table = step_settings();
  for (auto part : {stop_settings(), result_and_pair_settings(), uncertainty_settings()}) {
    table.insert(table.end(), part.begin(), part.end());
  }
  return table;
}

std::vector<Setting<B>> make_batch_table() {
  return {
      setting<B, &B::pairing, &P::max_correspondence_distance>(
          {"max-distance", "pairing.max_correspondence_distance", kScaledRange, "",
           kMaxDistanceHelp}),
      setting<B, &B::max_iterations>(
          {"max-iterations", "max_iterations", kIterations, "",
           "Iteration limit (passes over the source); reaching it reports 'not converged'"}),
      setting<B, &B::initial_damping>(
          {"damping", "initial_damping", kDamping, "",
           "icp-plane, gicp: initial Levenberg-Marquardt damping, relative to the mean diagonal "
           "of J^T J; 0 = Gauss-Newton"}),
      setting<B, &B::translation_tolerance>(
          {"translation-tolerance", "translation_tolerance", kTolerance, "scaled units",
           "Converged when an iteration moves the translation less than this ..."}),
      setting<B, &B::rotation_tolerance>({"rotation-tolerance", "rotation_tolerance", kTolerance,
                                          "rad",
                                          "... and the rotation less than this (rotation angle)"}),
      setting<B, &B::evaluation, &E::evaluation_points>({"evaluation-points",
                                                         "evaluation.evaluation_points",
                                                         kEvaluationPoints, "", kEvaluationHelp}),
      setting<B, &B::cost>({"cost", "cost", {}, "", kCostHelp, true}),
      setting<B, &B::pairing, &P::kernel>({"kernel", "pairing.kernel", {}, "", kKernelHelp}),
      setting<B, &B::pairing, &P::kernel_scale>(
          {"kernel-scale", "pairing.kernel_scale", kScaledRange, "", kKernelScaleHelp}),
      setting<B, &B::pairing, &P::trim_ratio>({"trim", "pairing.trim_ratio", kTrim, "", kTrimHelp}),
      setting<B, &B::neighborhood, &N::k>(
          {"neighbors", "neighborhood.k", kNeighbors, "", kNeighborsHelp}),
      setting<B, &B::num_threads>({"threads", "num_threads", kThreads, "", kThreadsHelp}),
      setting<B, &B::downsampling, &D::voxel_size_m>(
          {"voxel-size", "downsampling.voxel_size_m", kVoxelSize, "m", kVoxelSizeHelp}),
      setting<B, &B::downsampling, &D::downsample_to>(
          {"downsample-to", "downsampling.downsample_to", kDownsampleTo, "", kDownsampleToHelp}),
      setting<B, &B::record_trace>({"record-trace", "record_trace", {}, "", kTraceHelp, true}),
  };
}

}  // namespace

const std::vector<Setting<SgdSettings>>& sgd_settings_table() {
  static const std::vector<Setting<SgdSettings>> table = make_sgd_table();
  return table;
}

const std::vector<Setting<SgdSettings>>& sgd_fixed_rules_table() {
  static const std::vector<Setting<SgdSettings>> table = make_fixed_rules_table();
  return table;
}

const std::vector<Setting<BatchSettings>>& batch_settings_table() {
  static const std::vector<Setting<BatchSettings>> table = make_batch_table();
  return table;
}

bool is_retired_setting(std::string_view name) {
  static constexpr std::array<std::string_view, 19> kRetired{"momentum",
                                                             "beta1",
                                                             "beta2",
                                                             "rms-decay",
                                                             "epsilon",
                                                             "hessian-decay",
                                                             "path-efficiency",
                                                             "refine-gauss-newton",
                                                             "settle-tolerance",
                                                             "flat-neighbors",
                                                             "flatness",
                                                             "robust-scaling",
                                                             "cap-batch-to-source",
                                                             "small-source-gauss-newton",
                                                             "burn-in",
                                                             "sgld-step",
                                                             "svgd-step",
                                                             "block-size",
                                                             "preconditioner"};
  return std::any_of(kRetired.begin(), kRetired.end(),
                     [name](std::string_view r) { return detail::same_name(r, name); });
}

const Setting<SgdSettings>* find_sgd_setting(std::string_view name) {
  return detail::find_in(sgd_settings_table(), name);
}

const Setting<BatchSettings>* find_batch_setting(std::string_view name) {
  return detail::find_in(batch_settings_table(), name);
}

}  // namespace sgdicp
