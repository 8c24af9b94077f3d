#pragma once
// Options shared by `sgdicp register` and `sgdicp bench`: every setting of SgdSettings, with its
// unit and default (taken from the library, so help and behaviour never disagree).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "sgdicp/batch_icp.hpp"
#include "sgdicp/features.hpp"
#include "sgdicp/preprocessing.hpp"
#include "sgdicp/registration.hpp"

namespace sgdicp::cli {

struct SettingsOptions {
  std::string preset = "default";
  std::optional<std::string> optimizer;
  std::optional<double> learning_rate;
  std::optional<std::size_t> batch_size;
  std::optional<double> max_distance;
  std::string max_distance_unit = "scaled";
  std::optional<std::size_t> max_iterations;
  std::optional<std::uint64_t> seed;
  std::optional<double> momentum, beta1, beta2, rms_decay, epsilon;
  std::optional<std::size_t> window;
  std::optional<double> chi2, path_efficiency;
  std::optional<double> translation_tolerance, rotation_tolerance;
  std::optional<std::size_t> refine_stages;
  std::optional<double> step_decay, distance_factor, min_distance;
  std::optional<bool> average;
  std::optional<std::size_t> evaluation_points;
  std::optional<std::string> scaling_origin;
  // Methods, costs and robustness.
  std::string method = "sgd";
  std::optional<std::string> kernel;
  std::optional<double> kernel_scale;
  std::optional<double> trim;
  std::optional<std::string> preconditioner;
  std::optional<std::size_t> neighbors;
  std::optional<double> damping;
  std::optional<bool> check_degeneracy;
  // Preprocessing.
  std::optional<double> voxel_size;
  std::optional<double> random_ratio;
};

/// The methods of `--method`, in the order --help lists them.
inline const std::vector<std::string>& method_names() {
  static const std::vector<std::string> names = {"sgd", "sgd-plane", "sgd-gicp",
                                                 "icp", "icp-plane", "gicp"};
  return names;
}

inline std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

/// Options that choose the method and the cost-independent parts (kernel, trimming, features).
inline void add_method_options(CLI::App& app, SettingsOptions& o, bool several) {
  const BatchSettings b{};
  const SgdSettings d{};
  const std::string method_help =
      "Method: sgd (SGD-ICP, point-to-point: the paper), sgd-plane (SGD-ICP on point-to-plane), "
      "sgd-gicp (SGD-ICP on plane-to-plane), icp (batch point-to-point, closed-form SVD step), "
      "icp-plane (batch point-to-plane, Levenberg-Marquardt), gicp (batch plane-to-plane, "
      "Levenberg-Marquardt)";
  if (several) {
    app.add_option("--method", o.method,
                   method_help +
                       "; several separated by commas are compared in one run "
                       "[default: sgd]");
  } else {
    app.add_option("--method", o.method, method_help + " [default: sgd]")
        ->check(CLI::IsMember(method_names()));
  }
  app.add_option("--kernel", o.kernel,
                 "Robust kernel on the pair residuals: none, huber, cauchy, geman-mcclure, "
                 "welsch [default: none]")
      ->check(CLI::IsMember({"none", "huber", "cauchy", "geman-mcclure", "welsch"}));
  app.add_option("--kernel-scale", o.kernel_scale,
                 "Kernel scale c (residual size where down-weighting starts), in the unit of "
                 "--max-distance-unit [default: " +
                     num(d.kernel_scale.value) + " scaled]");
  app.add_option("--trim", o.trim,
                 "Keep only this fraction of the pairs (per mini-batch for SGD, per iteration "
                 "for batch methods), the closest ones: trimmed ICP for partial overlap, in (0, 1] "
                 "[default: 1]");
  app.add_option("--preconditioner", o.preconditioner,
                 "SGD methods: 'none' (A = I, the paper) or 'gauss-newton' (A = inverse of the "
                 "averaged mini-batch Gauss-Newton matrix; same as --optimizer gauss-newton) "
                 "[default: none]")
      ->check(CLI::IsMember({"none", "gauss-newton"}));
  app.add_option("--neighbors", o.neighbors,
                 "Plane costs: neighbours per point for normals and covariances [default: " +
                     std::to_string(d.neighborhood.k) + "]");
  app.add_option("--damping", o.damping,
                 "icp-plane, gicp: initial Levenberg-Marquardt damping, relative to the mean "
                 "diagonal, 0 = Gauss-Newton [default: " +
                     num(b.initial_damping) + "]");
  app.add_option("--check-degeneracy", o.check_degeneracy,
                 "Check the final alignment for degenerate geometry (plane, corridor) and report "
                 "it [default: true]");
  app.add_option("--voxel-size", o.voxel_size,
                 "Downsample both clouds to one point per voxel of this size, metres, before "
                 "registering (timed) [default: off]");
  app.add_option("--random-ratio", o.random_ratio,
                 "Keep this random fraction of each cloud's points before registering (seeded "
                 "by --seed), in (0, 1] [default: off]");
}

inline void add_settings_options(CLI::App& app, SettingsOptions& o) {
  const SgdSettings d{};
  const SgdSettings p = SgdSettings::paper();
  const SgdSettings pa = SgdSettings::paper(OptimizerType::adam);
  const auto both = [](const std::string& def, const std::string& paper) {
    return " [default: " + def + "; paper preset: " + paper + "]";
  };
  app.add_option("--preset", o.preset,
                 "Base settings that the options below override: 'default' (the best measured: "
                 "paper coarse phase, then refinement) or 'paper' (m = 160, d_max = 0.5 scaled, "
                 "fixed step 2 or Adam, no refinement, last iterate returned) [default: default]")
      ->check(CLI::IsMember({"default", "paper"}));
  app.add_option(
         "--optimizer", o.optimizer,
         "Step rule of eq. 3: sgd (fixed step), momentum, rmsprop, adam, gauss-newton (A = inverse "
         "of the averaged mini-batch Gauss-Newton matrix; learning rate 1 = full step)" +
             both(std::string(to_string(d.optimizer.type)), "sgd"))
      ->check(CLI::IsMember({"sgd", "momentum", "rmsprop", "adam", "gauss-newton"}));
  app.add_option("--learning-rate", o.learning_rate,
                 "Step size alpha, in scaled units (the clouds are scaled into [0, 1])" +
                     both(num(d.optimizer.learning_rate) + " for adam/rmsprop, 2 for sgd, 0.2 for "
                                                           "momentum, 1 for gauss-newton",
                          num(p.optimizer.learning_rate) + " for sgd, " +
                              num(pa.optimizer.learning_rate) + " for adam"));
  app.add_option("--batch-size,-m", o.batch_size,
                 "Mini-batch size m, source points per iteration" +
                     both(std::to_string(d.batch_size), std::to_string(p.batch_size)));
  app.add_option("--max-distance,-d", o.max_distance,
                 "Correspondence rejection distance d_max, in the unit of --max-distance-unit" +
                     both(num(d.max_correspondence_distance.value) + " scaled for SGD methods, " +
                              num(BatchSettings{}.max_correspondence_distance.value) +
                              " scaled for batch methods",
                          num(p.max_correspondence_distance.value) + " scaled"));
  app.add_option("--max-distance-unit", o.max_distance_unit,
                 "Unit of --max-distance and --min-distance: 'scaled' (fraction of the largest "
                 "side of the joint bounding box) or 'm' (metres) [default: scaled]")
      ->check(CLI::IsMember({"scaled", "m"}));
  app.add_option("--max-iterations", o.max_iterations,
                 "Iteration limit (mini-batches for SGD methods, passes for batch methods); "
                 "reaching it reports 'not converged'" +
                     both(std::to_string(d.max_iterations) + " for SGD methods, " +
                              std::to_string(BatchSettings{}.max_iterations) + " for batch methods",
                          std::to_string(p.max_iterations)));
  app.add_option("--seed", o.seed,
                 "Seed of the mini-batch sampler (same seed, same result)" +
                     both(std::to_string(d.seed), std::to_string(p.seed)));
  app.add_option("--momentum", o.momentum,
                 "Momentum: velocity decay, unitless in [0, 1)" +
                     both(num(d.optimizer.momentum), num(p.optimizer.momentum)));
  app.add_option("--beta1", o.beta1,
                 "Adam: decay of the gradient mean, in [0, 1)" +
                     both(num(d.optimizer.beta1), num(p.optimizer.beta1)));
  app.add_option("--beta2", o.beta2,
                 "Adam: decay of the squared-gradient mean, in [0, 1)" +
                     both(num(d.optimizer.beta2), num(p.optimizer.beta2)));
  app.add_option("--rms-decay", o.rms_decay,
                 "RMSProp: decay of the squared-gradient mean, in [0, 1)" +
                     both(num(d.optimizer.rms_decay), num(p.optimizer.rms_decay)));
  app.add_option("--epsilon", o.epsilon,
                 "Adam/RMSProp: added to the gradient RMS, scaled units" +
                     both(num(d.optimizer.epsilon), num(p.optimizer.epsilon)));
  app.add_option(
      "--window", o.window,
      "Convergence: iterations per test window, >= 8 (a stage ends after a window whose "
      "mean mini-batch gradient is not significantly non-zero); also the length of "
      "the final iterate average" +
          both(std::to_string(d.convergence.window), std::to_string(p.convergence.window)));
  app.add_option("--chi2", o.chi2,
                 "Convergence: critical chi-square value (6 dof) of the Hotelling test on the "
                 "window's mean gradient; larger stops earlier" +
                     both(num(d.convergence.chi2), num(p.convergence.chi2)));
  app.add_option(
      "--path-efficiency", o.path_efficiency,
      "Convergence: a stationary window's net displacement over its path length must "
      "be at most this (1 = straight travel, ~0.2 = jitter), unitless" +
          both(num(d.convergence.max_path_efficiency), num(p.convergence.max_path_efficiency)));
  app.add_option("--translation-tolerance", o.translation_tolerance,
                 "Convergence: a window whose steps each move the translation less than this "
                 "also ends a stage (batch methods: an iteration that moves it less converges), "
                 "scaled units" +
                     both(num(d.convergence.translation_tolerance) + " for SGD methods, " +
                              num(BatchSettings{}.translation_tolerance) + " for batch methods",
                          num(p.convergence.translation_tolerance)));
  app.add_option("--rotation-tolerance", o.rotation_tolerance,
                 "Convergence: ... and the angles less than this (sum of |d roll|, |d pitch|, "
                 "|d yaw|; batch methods: rotation angle), rad" +
                     both(num(d.convergence.rotation_tolerance) + " for SGD methods, " +
                              num(BatchSettings{}.rotation_tolerance) + " for batch methods",
                          num(p.convergence.rotation_tolerance)));
  app.add_option(
      "--refine-stages", o.refine_stages,
      "Refinement stages after the first stationary stage (0 = the paper's single phase)" +
          both(std::to_string(d.refinement.stages), std::to_string(p.refinement.stages)));
  app.add_option("--step-decay", o.step_decay,
                 "Refinement: step-size multiplier per stage, in (0, 1]" +
                     both(num(d.refinement.step_decay), num(p.refinement.step_decay)));
  app.add_option("--distance-factor", o.distance_factor,
                 "Refinement: new d_max = factor x median correspondence distance, unitless" +
                     both(num(d.refinement.distance_factor), num(p.refinement.distance_factor)));
  app.add_option("--min-distance", o.min_distance,
                 "Refinement: lower bound of d_max, in the unit of --max-distance-unit" +
                     both(num(d.refinement.min_distance.value) + " scaled",
                          num(p.refinement.min_distance.value) + " scaled"));
  app.add_option(
      "--average", o.average,
      "Return the mean of the --window iterates of the final stage's stationary window "
      "(true) or the last iterate (false)" +
          both(d.average_iterates ? "true" : "false", p.average_iterates ? "true" : "false"));
  app.add_option(
         "--scaling-origin", o.scaling_origin,
         "Origin of the scaled space and pivot of the rotation: 'corner' (the paper, points "
         "in [0, 1]) or 'center' (points in [-0.5, 0.5])" +
             both(d.scaling_origin == ScalingOrigin::center ? "center" : "corner",
                  p.scaling_origin == ScalingOrigin::center ? "center" : "corner"))
      ->check(CLI::IsMember({"corner", "center"}));
  app.add_option(
      "--evaluation-points", o.evaluation_points,
      "Source points (spread evenly) used for the final inlier ratio and RMSE, 0 = all" +
          both(std::to_string(d.evaluation_points), std::to_string(p.evaluation_points)));
}

/// The settings of the chosen preset with every given option applied. Throws InvalidSettingsError.
inline SgdSettings make_settings(const SettingsOptions& o) {
  const std::optional<OptimizerType> type =
      o.optimizer ? std::optional(optimizer_from_string(*o.optimizer)) : std::nullopt;
  SgdSettings s =
      o.preset == "paper" ? SgdSettings::paper(type.value_or(OptimizerType::sgd)) : SgdSettings{};
  if (type && o.preset != "paper") {
    // Each step rule has its own natural step size: adaptive ones take a length per step, the
    // fixed step a gradient multiplier (the paper's 2), Gauss-Newton a fraction of a Newton step.
    s.optimizer.type = *type;
    switch (*type) {
      case OptimizerType::sgd:
        s.optimizer.learning_rate = 2.0;
        break;
      case OptimizerType::momentum:
        s.optimizer.learning_rate = 2.0 * (1.0 - s.optimizer.momentum);
        break;
      case OptimizerType::gauss_newton:
        s.optimizer.learning_rate = 1.0;
        break;
      case OptimizerType::adam:
      case OptimizerType::rmsprop:
        s.optimizer.learning_rate = SgdSettings{}.optimizer.learning_rate;
        break;
    }
  }
  const auto unit = o.max_distance_unit == "m" ? Distance::Unit::metres : Distance::Unit::scaled;
  if (o.learning_rate) s.optimizer.learning_rate = *o.learning_rate;
  if (o.batch_size) s.batch_size = *o.batch_size;
  if (o.max_distance) s.max_correspondence_distance = {*o.max_distance, unit};
  if (o.max_iterations) s.max_iterations = *o.max_iterations;
  if (o.seed) s.seed = *o.seed;
  if (o.momentum) s.optimizer.momentum = *o.momentum;
  if (o.beta1) s.optimizer.beta1 = *o.beta1;
  if (o.beta2) s.optimizer.beta2 = *o.beta2;
  if (o.rms_decay) s.optimizer.rms_decay = *o.rms_decay;
  if (o.epsilon) s.optimizer.epsilon = *o.epsilon;
  if (o.window) s.convergence.window = *o.window;
  if (o.chi2) s.convergence.chi2 = *o.chi2;
  if (o.path_efficiency) s.convergence.max_path_efficiency = *o.path_efficiency;
  if (o.translation_tolerance) s.convergence.translation_tolerance = *o.translation_tolerance;
  if (o.rotation_tolerance) s.convergence.rotation_tolerance = *o.rotation_tolerance;
  if (o.refine_stages) s.refinement.stages = *o.refine_stages;
  if (o.step_decay) s.refinement.step_decay = *o.step_decay;
  if (o.distance_factor) s.refinement.distance_factor = *o.distance_factor;
  if (o.min_distance) s.refinement.min_distance = {*o.min_distance, unit};
  if (o.average) s.average_iterates = *o.average;
  if (o.evaluation_points) s.evaluation_points = *o.evaluation_points;
  if (o.scaling_origin) {
    s.scaling_origin =
        *o.scaling_origin == "corner" ? ScalingOrigin::lower_corner : ScalingOrigin::center;
  }
  s.validate();
  return s;
}

}  // namespace sgdicp::cli

namespace sgdicp::cli {

/// One method of --method with all its settings resolved.
struct MethodSpec {
  std::string name;
  bool stochastic = true;
  SgdSettings sgd;
  BatchSettings batch;
  std::optional<double> voxel_size;
  std::optional<double> random_ratio;
};

/// Resolves a --method name with the shared options. Throws InvalidSettingsError.
inline MethodSpec make_method(const std::string& name, const SettingsOptions& o) {
  const auto& names = method_names();
  if (std::find(names.begin(), names.end(), name) == names.end()) {
    throw InvalidSettingsError("unknown method '" + name +
                               "' (expected sgd, sgd-plane, sgd-gicp, icp, icp-plane or gicp)");
  }
  MethodSpec m;
  m.name = name;
  m.stochastic = name.rfind("sgd", 0) == 0;
  const CostType cost = name.find("gicp") != std::string::npos    ? CostType::plane_to_plane
                        : name.find("plane") != std::string::npos ? CostType::point_to_plane
                                                                  : CostType::point_to_point;
  const auto unit = o.max_distance_unit == "m" ? Distance::Unit::metres : Distance::Unit::scaled;
  // Both solvers default to no kernel.
  const KernelType kernel = o.kernel ? kernel_from_string(*o.kernel) : KernelType::none;

  m.sgd = make_settings(o);
  m.sgd.cost = cost;
  if (o.preconditioner && *o.preconditioner == "gauss-newton") {
    m.sgd.optimizer.type = OptimizerType::gauss_newton;
    if (!o.learning_rate) m.sgd.optimizer.learning_rate = 1.0;
  }
  m.sgd.kernel = kernel;
  if (o.kernel_scale) m.sgd.kernel_scale = {*o.kernel_scale, unit};
  if (o.trim) m.sgd.trim_ratio = *o.trim;
  if (o.neighbors) m.sgd.neighborhood.k = *o.neighbors;
  if (o.check_degeneracy) m.sgd.check_degeneracy = *o.check_degeneracy;

  BatchSettings& b = m.batch;
  b.cost = cost;
  if (o.max_distance) b.max_correspondence_distance = {*o.max_distance, unit};
  if (o.max_iterations) b.max_iterations = *o.max_iterations;
  b.kernel = kernel;
  if (o.kernel_scale) b.kernel_scale = {*o.kernel_scale, unit};
  if (o.trim) b.trim_ratio = *o.trim;
  if (o.neighbors) b.neighborhood.k = *o.neighbors;
  if (o.damping) b.initial_damping = *o.damping;
  if (o.check_degeneracy) b.check_degeneracy = *o.check_degeneracy;
  if (o.evaluation_points) b.evaluation_points = *o.evaluation_points;
  if (o.translation_tolerance) b.translation_tolerance = *o.translation_tolerance;
  if (o.rotation_tolerance) b.rotation_tolerance = *o.rotation_tolerance;

  m.voxel_size = o.voxel_size;
  m.random_ratio = o.random_ratio;
  if (m.voxel_size && !(*m.voxel_size > 0.0 && std::isfinite(*m.voxel_size))) {
    throw InvalidSettingsError("--voxel-size must be positive and finite");
  }
  if (m.random_ratio && !(*m.random_ratio > 0.0 && *m.random_ratio <= 1.0)) {
    throw InvalidSettingsError("--random-ratio must be in (0, 1]");
  }
  m.sgd.validate();
  b.validate();
  return m;
}

struct MethodRun {
  RegistrationResult result;
  double prepare_ms = 0.0;  ///< downsampling + KD-tree build + reference normals/covariances
  std::size_t source_points = 0;
  std::size_t reference_points = 0;
};

/// Runs one method: downsampling (if asked), KD-tree, reference features, registration; all
/// but file I/O is timed.
inline MethodRun run_method(const MethodSpec& m, const PointCloud& source,
                            const PointCloud& reference, const Eigen::Matrix4d& T_init,
                            bool record_trace = false) {
  const auto start = std::chrono::steady_clock::now();
  const auto reduce = [&](const PointCloud& cloud) {
    PointCloud out = m.voxel_size ? voxel_downsample(cloud, *m.voxel_size) : cloud;
    if (m.random_ratio) out = random_downsample_ratio(out, *m.random_ratio, m.sgd.seed);
    return out;
  };
  const bool reduced = m.voxel_size || m.random_ratio;
  std::optional<PointCloud> small_source;
  if (reduced) small_source = reduce(source);
  const PointCloud& src = small_source ? *small_source : source;
  ReferenceIndex index(reduced ? reduce(reference) : reference);
  prepare_reference(index, m.stochastic ? m.sgd.cost : m.batch.cost,
                    m.stochastic ? m.sgd.neighborhood : m.batch.neighborhood);
  MethodRun run;
  run.prepare_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  run.source_points = src.size();
  run.reference_points = index.size();
  if (m.stochastic) {
    SgdSettings s = m.sgd;
    s.record_trace = record_trace;
    run.result = align(src, index, s, T_init);
  } else {
    BatchSettings b = m.batch;
    b.record_trace = record_trace;
    run.result = align_batch(src, index, b, T_init);
  }
  return run;
}

}  // namespace sgdicp::cli
