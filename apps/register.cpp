// `sgdicp register SOURCE REFERENCE`: one registration, printed as text or JSON.
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>

#include "cli_common.hpp"
#include "cli_settings.hpp"
#include "help_layout.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/transform_io.hpp"
#include "sgdicp/metrics/metrics.hpp"
#include "sgdicp/registration/deskew.hpp"
#include "sgdicp/tools/render.hpp"

namespace sgdicp::cli {
namespace {

struct RegisterOptions {
  std::string source;
  std::string reference;
  std::string init;
  std::string ground_truth;
  std::string output;
  std::string aligned;
  std::string picture;
  std::string trace;
  std::string samples;
  bool json = false;
  bool deskew = false;
  SettingsOptions settings;
  /// The global registration's options (global_settings_table), only with --init global.
  OptionValues global;
  DepthOptions depth;
};

void write_trace_csv(const std::string& path, const RegistrationResult& r) {
  std::ofstream out(path);
  if (!out) throw IoError(path + ": cannot open for writing");
  out << "iteration,points_processed,step_size,max_distance_m,inliers,cost,"
         "t00,t01,t02,t03,t10,t11,t12,t13,t20,t21,t22,t23\n";
  out << std::setprecision(10);
  for (const auto& e : r.trace) {
    out << e.iteration << ',' << e.points_processed << ',' << e.step_size << ',' << e.max_distance_m
        << ',' << e.inliers << ',' << e.cost;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 4; ++j) out << ',' << e.T_reference_source(i, j);
    }
    out << '\n';
  }
  if (!out) throw IoError(path + ": write error");
}

// One pose vector (x y z roll pitch yaw of T_reference_source, metres and radians) per line.
void write_samples(const std::string& path, const RegistrationResult& r) {
  std::ofstream out(path);
  if (!out) throw IoError(path + ": cannot open for writing");
  out << "# x_m y_m z_m roll_rad pitch_rad yaw_rad (theta of T_reference_source, R = Rz Ry Rx)\n";
  out << std::setprecision(17);
  for (const auto& theta : r.samples) {
    for (int k = 0; k < 6; ++k) out << (k ? " " : "") << theta[k];
    out << '\n';
  }
  if (!out) throw IoError(path + ": write error");
}

// The standard deviations of theta, from the covariance's diagonal.
void print_uncertainty(const RegistrationResult& r) {
  const auto sd = [&](int k) { return std::sqrt(r.covariance(k, k)); };
  std::cout << std::defaultfloat << std::setprecision(3) << "std (x, y, z) [m]: " << sd(0) << ' '
            << sd(1) << ' ' << sd(2)
            << ", std (roll, pitch, yaw) [deg]: " << sd(3) * 180.0 / std::numbers::pi << ' '
            << sd(4) * 180.0 / std::numbers::pi << ' ' << sd(5) * 180.0 / std::numbers::pi
            << " (correlation factor " << r.correlation_factor << ", " << r.uncertainty_ms
            << " ms)\n";
  if (r.effective_samples > 0.0) {
    std::cout << "sgld: " << r.samples.size() << " samples worth " << r.effective_samples
              << " independent draws (effective sample size, slowest coordinate)\n";
  }
  if (r.modes.size() > 1) {
    std::cout << "modes: " << r.modes.size() << " (the std is the first's), weights";
    for (const PoseMode& m : r.modes) std::cout << ' ' << m.weight;
    std::cout << '\n';
  }
}

// The option checks that need the method: before any file is read.
void check_options(const RegisterOptions& o, const MethodSpec& method) {
  if (!o.picture.empty()) check_picture_name(o.picture);
  if (o.init != "global" && !o.global.empty()) {
    const auto& [name, text] = *o.global.begin();
    throw InvalidSettingsError("--" + name + " " + text + ": only with --init global");
  }
  const UncertaintyType uncertainty = method.sgd.uncertainty.method;
  if (!o.samples.empty() && uncertainty != UncertaintyType::sgld &&
      uncertainty != UncertaintyType::svgd) {
    throw InvalidSettingsError("--samples " + o.samples +
                               ": only --uncertainty sgld or svgd draws samples");
  }
}

// --deskew: the sweep registered again with its times, from the rigid pose: the pose of its
// middle and the velocity within it (deskew.hpp).
std::optional<DeskewedRegistration> deskew_source(const RegisterOptions& o,
                                                  const PointCloud& source,
                                                  const PointCloud& reference_cloud,
                                                  const RegistrationResult& rigid) {
  if (!o.deskew) return std::nullopt;
  if (!source.has_times()) {
    throw InvalidInputError(o.source +
                            ": --deskew needs each point's time (a PCD/PLY time field: t, "
                            "offset_time, time or timestamp, docs/io.md); this file has none");
  }
  return align_deskewed(source, source.times_s, reference_cloud, rigid.T_reference_source);
}

// The files asked for: transform, trace, samples, aligned cloud (every source point in input
// order, deskewed when --deskew), picture.
void write_outputs(const RegisterOptions& o, const PointCloud& source,
                   const PointCloud& reference_cloud, const RegistrationResult& result,
                   const std::optional<DeskewedRegistration>& deskewed) {
  if (!o.output.empty()) write_transform(o.output, result.T_reference_source);
  if (!o.trace.empty()) write_trace_csv(o.trace, result);
  if (!o.samples.empty()) write_samples(o.samples, result);
  if (!o.aligned.empty()) {
    write_point_cloud(
        o.aligned, deskewed
                       ? rebased(deskewed_in_reference(source, source.times_s, *deskewed),
                                 reference_cloud.origin_m)
                       : transformed(source, result.T_reference_source, reference_cloud.origin_m));
  }
  if (!o.picture.empty()) {
    render_alignment_png(o.picture, reference_cloud, source, result.T_reference_source);
  }
}

void print_json(const MethodSpec& method, const MethodRun& run,
                const std::optional<Eigen::Matrix4d>& T_gt,
                const std::optional<DeskewedRegistration>& deskewed) {
  const RegistrationResult& result = run.result;
  nlohmann::json j = result_to_json(result);
  if (deskewed) {
    j["deskew"] = {
        {"velocity", std::vector<double>(deskewed->velocity.data(), deskewed->velocity.data() + 6)},
        {"mid_time_s", deskewed->mid_time_s},
        {"converged", deskewed->converged},
        {"iterations", deskewed->iterations},
        {"message", deskewed->message}};
  }
  j["build_ms"] = run.prepare_ms;
  j["method"] = method.name;
  if (T_gt) {
    j["translation_error_m"] = translation_error(result.T_reference_source, *T_gt);
    j["rotation_error_euler_rad"] = rotation_error_euler_sum(result.T_reference_source, *T_gt);
    j["rotation_error_geodesic_deg"] =
        rotation_error_geodesic(result.T_reference_source, *T_gt) * 180.0 / std::numbers::pi;
  }
  std::cout << j.dump(2) << '\n';
}

// The transform, convergence, points, inliers and times, as text.
void print_result(const MethodSpec& method, const MethodRun& run, std::size_t source_size) {
  const RegistrationResult& result = run.result;
  std::cout << "method: " << method.name << "\nT_reference_source =\n"
            << format_transform(result.T_reference_source);
  std::cout << std::setprecision(4) << "converged: " << (result.converged ? "yes" : "no") << " ("
            << result.message << ")\n"
            << "iterations: " << result.iterations
            << ", points processed: " << result.points_processed << " (" << std::fixed
            << std::setprecision(2)
            << static_cast<double>(result.points_processed) / static_cast<double>(run.source_points)
            << " passes over " << result.source_points << " source points)\n"
            << "clouds: " << result.source_points << " source and " << result.reference_points
            << " reference points registered"
            << (result.voxel_size_m > 0.0
                    ? " (voxel grid " + format_number(result.voxel_size_m) + " m, from " +
                          std::to_string(source_size) + " source points)"
                    : std::string(" (every point)"))
            << "\n"
            << "inliers: " << result.inliers << " of " << result.evaluated_points << " ("
            << std::setprecision(1) << 100.0 * result.inlier_ratio << " %) within "
            << std::setprecision(4) << result.final_max_distance_m << " m, inlier RMSE "
            << result.inlier_rmse_m << " m\n"
            << "time: " << std::setprecision(1) << result.time_ms << " ms registration + "
            << run.prepare_ms << " ms preparation (kd-tree"
            << (result.voxel_size_m > 0.0 || method.random_ratio ? ", downsampling" : "")
            << (!method.stochastic && (needs_reference_normals(method.batch.cost) ||
                                       needs_covariances(method.batch.cost))
                    ? ", normals/covariances"
                    : "")
            << ")\n";
}

void print_ground_truth_errors(const Eigen::Matrix4d& T_reference_source,
                               const Eigen::Matrix4d& T_gt) {
  std::cout << std::setprecision(4) << "error vs ground truth: translation "
            << translation_error(T_reference_source, T_gt) << " m, rotation "
            << rotation_error_geodesic(T_reference_source, T_gt) * 180.0 / std::numbers::pi
            << " deg (geodesic), " << rotation_error_euler_sum(T_reference_source, T_gt)
            << " rad (sum of |d roll|, |d pitch|, |d yaw|)\n";
}

void warn_if_doubtful(const RegistrationResult& result) {
  if (result.degenerate) {
    std::cerr << "warning: degenerate geometry (constraint ratio " << result.constraint_ratio
              << "): the transform is not constrained along some motion\n";
  }
  if (!result.converged) {
    std::cerr << "warning: the registration did not converge: " << result.message << '\n';
  }
}

void print_deskew(const DeskewedRegistration& d) {
  std::cout << std::setprecision(4) << "deskew: " << d.message << " (" << d.iterations
            << " iterations); the transform is the pose at the sweep's middle, "
            << format_number(d.mid_time_s) << " s; velocity " << d.velocity.head<3>().transpose()
            << " m/s, " << (d.velocity.tail<3>() * 180.0 / std::numbers::pi).transpose()
            << " deg/s (sensor frame)\n";
  if (!d.converged) std::cerr << "warning: the deskewing did not converge: " << d.message << '\n';
}

void print_global(const RegistrationResult& r) {
  std::cout << std::setprecision(3) << "global: hypothesis " << r.global_winner_rank << " of "
            << r.global_hypotheses << " won, overlap " << r.global_score << ", runner-up "
            << r.global_runner_up_score << (r.global_ambiguous ? " (ambiguous)" : "") << ", "
            << std::setprecision(1) << std::fixed << r.global_ms << " ms"
            << (r.global_reliable ? "" : ": no reliable global solution") << '\n'
            << std::defaultfloat;
}

void print_text(const RegisterOptions& o, const MethodSpec& method, const MethodRun& run,
                std::size_t source_size, const std::optional<Eigen::Matrix4d>& T_gt) {
  const RegistrationResult& result = run.result;
  print_result(method, run, source_size);
  if (result.global_init) print_global(result);
  if (T_gt) print_ground_truth_errors(result.T_reference_source, *T_gt);
  if (method.sgd.uncertainty.method != UncertaintyType::none && result.uncertainty_pairs > 0) {
    print_uncertainty(result);
  }
  if (!o.picture.empty()) std::cout << "picture: " << o.picture << '\n';
  warn_if_doubtful(result);
}

void run(const RegisterOptions& o) {
  const MethodSpec method = make_method(o.settings.method, o.settings);
  check_options(o, method);
  const bool global = o.init == "global";
  const GlobalSettings global_settings =
      settings_from_options(GlobalSettings{}, global_settings_table(), o.global);
  const Eigen::Matrix4d T_init = o.init.empty() || global
                                     ? Eigen::Matrix4d::Identity()
                                     : parse_transform_option(o.init, "--init");
  std::optional<Eigen::Matrix4d> T_gt;
  if (!o.ground_truth.empty()) T_gt = parse_transform_option(o.ground_truth, "--ground-truth");
  const PointCloud source = load_cloud(o.source, "source", !o.json, o.depth);
  const PointCloud reference_cloud = load_cloud(o.reference, "reference", !o.json, o.depth);
  const MethodRun run = global
                            ? run_method_global(method, source, reference_cloud, global_settings)
                            : run_method(method, source, reference_cloud, T_init, !o.trace.empty());
  const std::optional<DeskewedRegistration> deskewed =
      deskew_source(o, source, reference_cloud, run.result);
  MethodRun shown = run;  // with --deskew, the pose of the sweep's middle
  if (deskewed) shown.result.T_reference_source = deskewed->T_reference_source;
  const RegistrationResult& result = shown.result;
  write_outputs(o, source, reference_cloud, result, deskewed);

  if (o.json) {
    print_json(method, shown, T_gt, deskewed);
  } else {
    print_text(o, method, shown, source.size(), T_gt);
    if (deskewed) print_deskew(*deskewed);
  }
  if (global && !result.global_reliable) throw ExitStatus(result.message, kExitNoGlobalSolution);
}

}  // namespace

void add_register_command(CLI::App& app) {
  auto o = std::make_shared<RegisterOptions>();
  CLI::App* cmd = app.add_subcommand(
      "register",
      "Register SOURCE to REFERENCE and print T_reference_source, the 4x4 transform that maps "
      "source points into the reference frame (p_ref = R p_src + t, metres).");
  cmd->add_option("SOURCE", o->source,
                  "Source cloud (the one that moves): .pcd .ply .bin .xyz "
                  ".txt .csv .vtk .f32, or a 16-bit .png depth image (see --intrinsics)")
      ->required();
  cmd->add_option("REFERENCE", o->reference, "Reference cloud (fixed), same formats")->required();
  cmd->add_option("--init", o->init,
                  "Initial T_reference_source: a file with a 4x4 or 3x4 row-major matrix, 12/16 "
                  "numbers inline (quoted), or 'global': no initial guess, a global estimate "
                  "(FPFH features, RANSAC; docs/global.md; its settings are the --global-* "
                  "options) then the registration from it; exit status 3 when no reliable "
                  "global solution exists [default: identity]");
  cmd->add_option("--ground-truth", o->ground_truth,
                  "Ground-truth T_reference_source (file or 12/16 numbers): prints the errors");
  cmd->add_flag("--json", o->json,
                "Print one JSON object (transform as 4x4 row-major nested lists, converged, "
                "iterations, points_processed, time_ms, inliers, ...) instead of text");
  cmd->add_option("--output,-o", o->output, "Write the 4x4 transform to this file");
  cmd->add_option("--aligned", o->aligned,
                  "Write the moved source cloud to this file (.ply, .pcd or .xyz): every point in "
                  "input order, deskewed with --deskew");
  cmd->add_flag(
      "--deskew", o->deskew,
      "The source is a sweep measured while the sensor moved: estimate the velocity "
      "within it together with its pose, from each point's time (a PCD/PLY time "
      "field); the transform is then the pose at the sweep's middle (docs/registration.md, "
      "Moving sensors) [default: off]");
  cmd->add_option("--picture", o->picture,
                  "Write a PNG (the name must end in .png) of the reference and the aligned "
                  "source (top and side view)");
  cmd->add_option(
      "--trace", o->trace,
      "Write the per-iteration trace (pose, step size, d_max, points processed) as CSV");
  add_depth_options(*cmd, o->depth);
  cmd->add_option(
      "--samples", o->samples,
      "Write the SGLD samples (--uncertainty sgld) or the SVGD particles (--uncertainty "
      "svgd), one pose vector x y z roll pitch yaw per line (metres, radians)");
  add_method_options(*cmd, o->settings, false);
  add_settings_options(*cmd, o->settings);
  add_table_options(*cmd, global_settings_table(), GlobalSettings{}, o->global,
                    "Global registration (only with --init global; docs/global.md)");
  // What a user of the command sets; every other option is in --help-all.
  static constexpr std::array<CommonOption, 13> kCommon{
      {kMethodBrief,
       kPresetBrief,
       {"init", "Initial T_reference_source: a 4x4 or 3x4 file, 12/16 numbers, or 'global'"},
       {"ground-truth", ""},
       {"output", ""},
       {"aligned", ""},
       {"json", "Print the result as one JSON object instead of text"},
       kGridBrief,
       kMaxDistanceBrief,
       {"threads", "Threads of one registration, 0 = every core (same result)"},
       {"seed", "Seed of the mini-batch sampler (same seed, same result)"},
       {"uncertainty", "Pose covariance: none, laplace (for a pose graph), sgld, svgd"},
       kIntrinsicsBrief}};
  arrange_help(*cmd, kCommon);
  cmd->callback([o] { run(*o); });
}

}  // namespace sgdicp::cli
