// `sgdicp odometry INPUT --poses-out FILE`: scan-to-map odometry over a folder of frames, the
// trajectory in the KITTI (and TUM) format, and its errors against a ground truth.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <new>
#include <optional>
#include <string_view>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "cli_common.hpp"
#include "cli_settings.hpp"
#include "help_layout.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/frame_source.hpp"
#include "sgdicp/io/io.hpp"
#include "sgdicp/io/trajectory_io.hpp"
#include "sgdicp/io/transform_io.hpp"
#include "sgdicp/metrics/trajectory_metrics.hpp"
#include "sgdicp/odometry/localizer.hpp"
#include "sgdicp/odometry/odometry.hpp"
#include "sgdicp/tools/render.hpp"

namespace sgdicp::cli {
namespace {

struct OdometryOptions {
  std::string input;
  std::string poses_out;
  std::string tum;
  std::string ground_truth;
  std::string ground_truth_calib;
  std::string picture;
  std::string report;
  std::string covariances_out;
  std::string map_out;
  double map_voxel_m = 0.0;
  // sgdicp localize: the map to localize in, and the first frame's pose in it ("global": none).
  std::string localize_in;
  std::string init = "global";
  std::string deskew = "auto";
  bool ground_truth_prefix = false;
  double rate_hz = 0.0;
  std::size_t max_frames = 0;
  bool quiet = false;
  OptionValues odometry_values;
  SettingsOptions settings;
  DepthOptions depth;
};

// --intrinsics as a K file or fx,fy,cx,cy; none: the layout's own (camera-intrinsics.txt).
std::optional<PinholeIntrinsics> intrinsics_option(const std::string& text) {
  if (text.empty()) return std::nullopt;
  std::error_code ec;
  try {
    if (std::filesystem::exists(text, ec)) return read_intrinsics(text);
    return parse_intrinsics(text);
  } catch (const FormatError& e) {
    throw FormatError(std::string("--intrinsics: ") + e.what());
  } catch (const InvalidSettingsError& e) {
    throw InvalidSettingsError(std::string("--intrinsics: ") + e.what());
  }
}

OdometrySettings odometry_settings(const OdometryOptions& o) {
  OdometrySettings s =
      settings_from_options(OdometrySettings{}, odometry_settings_table(), o.odometry_values);
  // A d_max given on the command line is used as is, every frame.
  s.adaptive_threshold = !o.settings.values.contains("max-distance");
  s.step_within_threshold = !o.settings.values.contains("learning-rate");
  // A step rule chosen on the command line is used from every start.
  s.deskew = parse_enum<DeskewMode>(o.deskew);
  s.tracking_gauss_newton =
      !o.settings.values.contains("optimizer") && !o.settings.values.contains("learning-rate");
  return s;
}

double median_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

constexpr std::string_view kReportHeader =
    "frame,file,failed,recovered,start,converged,iterations,source_points,map_points,overlap,"
    "inlier_ratio,inlier_rmse_m,threshold_m,index_build_ms,time_ms,constraint_ratio,doubtful,"
    "message\n";

void write_report_row(std::ostream& out, const FrameSource& source, const FrameReport& r) {
  std::string message = r.message;
  std::replace(message.begin(), message.end(), '"', '\'');
  out << std::setprecision(6) << r.index << ',' << source.frames[r.index].filename().string() << ','
      << r.failed << ',' << r.recovered << ',' << enum_name(r.start) << ',' << r.converged << ','
      << r.iterations << ',' << r.source_points << ',' << r.map_points << ',' << r.overlap << ','
      << r.inlier_ratio << ',' << r.inlier_rmse_m << ',' << r.threshold_m << ',' << r.index_build_ms
      << ',' << r.time_ms << ',' << r.constraint_ratio << ',' << r.doubtful << ",\"" << message
      << "\"\n";
}

// The frame's covariance: its 36 numbers row-major on one line, NaN as `nan` (whatever its sign).
void write_covariance_row(std::ostream& out, const Eigen::Matrix<double, 6, 6>& covariance) {
  const std::streamsize precision = out.precision(9);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      out << (r || c ? " " : "");
      const double v = covariance(r, c);
      if (std::isnan(v)) {
        out << "nan";
      } else {
        out << v + 0.0;  // -0 prints as 0
      }
    }
  }
  out << '\n';
  out.precision(precision);
}

// The per-frame files, written as the run goes: a frame's lines are on disk (flushed) before the
// next frame is read, so a run stopped by an error, a signal or a crash keeps every pose it had.
// Opened with the first frame's lines: an unwritable name fails after one frame, not after a long
// run, and settings that no frame can be read with leave no file behind.
class FrameWriters {
 public:
  FrameWriters(const OdometryOptions& o, std::vector<double> timestamps_s)
      : o_(o), timestamps_s_(std::move(timestamps_s)) {}

  // The lines of the frame reported last.
  void write(const FrameSource& source, const Odometry& odometry) {
    if (!poses_.is_open()) {
      open(poses_, o_.poses_out);
      if (!o_.tum.empty()) open(tum_, o_.tum) << kTumHeader;
      if (!o_.report.empty()) open(report_, o_.report) << kReportHeader;
      if (!o_.covariances_out.empty()) open(covariances_, o_.covariances_out);
    }
    const FrameReport& r = odometry.reports().back();
    write_kitti_pose(poses_, r.T_first_frame);
    check(poses_.flush(), o_.poses_out);
    if (tum_.is_open()) {
      write_tum_pose(tum_, timestamps_s_[r.index], r.T_first_frame);
      check(tum_.flush(), o_.tum);
    }
    if (report_.is_open()) {
      write_report_row(report_, source, r);
      check(report_.flush(), o_.report);
    }
    if (covariances_.is_open()) {
      write_covariance_row(covariances_, r.covariance);
      check(covariances_.flush(), o_.covariances_out);
    }
  }

 private:
  static std::ofstream& open(std::ofstream& out, const std::string& path) {
    out.open(path);
    if (!out) throw IoError(path + ": cannot open for writing");
    return out;
  }
  static void check(const std::ostream& out, const std::string& path) {
    if (!out) throw IoError(path + ": write error");
  }

  const OdometryOptions& o_;
  std::vector<double> timestamps_s_;
  std::ofstream poses_, tum_, report_, covariances_;
};

// The timestamps of the first `frames` frames, or nothing when the source does not give them.
std::vector<double> frame_times_s(const FrameSource& source, std::size_t frames) {
  if (source.timestamps_s.size() < frames) return {};
  return {source.timestamps_s.begin(),
          source.timestamps_s.begin() + static_cast<std::ptrdiff_t>(frames)};
}

// The ground truth of the frames an evaluation compares: `frames[i]` is matched with `poses[i]`.
struct GroundTruth {
  std::vector<std::size_t> frames;
  std::vector<Eigen::Matrix4d> poses;
};

// Frames and ground truth both with timestamps (TUM): matched in time within 0.02 s, as the
// TUM benchmark's associate.py does; frames without a match are left out, and said so.
GroundTruth associated_ground_truth(const OdometryOptions& o, const Trajectory& truth,
                                    const std::vector<double>& frame_times_s) {
  const auto matches = associate_timestamps(frame_times_s, truth.timestamps_s);
  GroundTruth out;
  for (std::size_t k = 0; k < matches.size(); ++k) {
    if (!matches[k]) continue;
    out.frames.push_back(k);
    out.poses.push_back(truth.poses[*matches[k]]);
  }
  if (out.frames.size() < 2) {
    throw InvalidInputError("--ground-truth " + o.ground_truth + ": " +
                            std::to_string(out.frames.size()) +
                            " frames have a ground-truth pose within 0.02 s (timestamps compared)");
  }
  std::cout << "ground truth associated by timestamp (within 0.02 s): " << out.frames.size()
            << " of " << frame_times_s.size() << " frames\n";
  return out;
}

// The ground truth as poses of the frames, relative to the first: matched by timestamp or
// checked against the frame count, moved into the sensor frame by a KITTI calibration when given.
GroundTruth load_ground_truth(const OdometryOptions& o, const FrameSource& source,
                              std::size_t frames) {
  Trajectory truth = read_trajectory(o.ground_truth);
  GroundTruth out;
  const std::vector<double> times = frame_times_s(source, frames);
  if (!truth.timestamps_s.empty() && !times.empty()) {
    out = associated_ground_truth(o, truth, times);
  } else {
    if (truth.poses.size() != frames) {
      if (truth.poses.size() < frames || !o.ground_truth_prefix) {
        throw InvalidInputError(
            "--ground-truth " + o.ground_truth + ": " + std::to_string(truth.poses.size()) +
            " poses for " + std::to_string(frames) + " frames" +
            (truth.poses.size() > frames
                 ? " (add --ground-truth-prefix to compare with its first poses)"
                 : ""));
      }
      truth.poses.resize(frames);
    }
    out.poses = std::move(truth.poses);
    for (std::size_t k = 0; k < frames; ++k) out.frames.push_back(k);
  }
  if (!o.ground_truth_calib.empty()) {
    const Eigen::Matrix4d Tr = read_kitti_calibration_tr(o.ground_truth_calib);
    const Eigen::Matrix4d Tr_inv = Tr.inverse();
    for (auto& G : out.poses) G = Tr_inv * G * Tr;  // camera poses -> sensor poses
  }
  out.poses = relative_to_first(out.poses);
  return out;
}

// Prints the errors against the ground truth; returns the absolute trajectory error (its
// alignment places the estimate in the picture).
AbsoluteTrajectoryError print_evaluation(const std::vector<Eigen::Matrix4d>& estimate,
                                         const std::vector<Eigen::Matrix4d>& truth) {
  std::cout << std::setprecision(4);
  const double length = path_length_m(truth);
  std::cout << "ground truth: " << truth.size() << " poses, path " << length << " m\n";
  if (truth.size() >= 2) {
    const RelativePoseErrors rpe = relative_pose_errors(estimate, truth, 1);
    std::cout << "RPE per frame (evo_rpe, delta 1 frame): translation RMSE " << rpe.translation.rmse
              << " m, mean " << rpe.translation.mean << ", median " << rpe.translation.median
              << ", max " << rpe.translation.max << "; rotation RMSE " << rpe.rotation.rmse
              << " deg, mean " << rpe.rotation.mean << ", median " << rpe.rotation.median
              << ", max " << rpe.rotation.max << '\n';
    if (const auto drift = kitti_drift(estimate, truth)) {
      std::cout << "KITTI drift (devkit, 100..800 m segments, " << drift->segments
                << " segments): translation " << drift->translation_percent << " %, rotation "
                << drift->rotation_deg_per_m << " deg/m\n";
    } else {
      std::cout << "KITTI drift: not computed (the path, " << length
                << " m, is shorter than the devkit's shortest segment, 100 m)\n";
    }
  }
  const AbsoluteTrajectoryError ate = absolute_trajectory_error(estimate, truth);
  std::cout << "ATE (evo_ape, rigid alignment, no scale): RMSE " << ate.error.rmse << " m, mean "
            << ate.error.mean << ", median " << ate.error.median << ", max " << ate.error.max
            << '\n';
  const EndDrift end = end_drift(estimate, truth);
  std::cout << "end drift (first to last frame): " << end.translation_m << " m ("
            << end.translation_percent << " % of the path), " << end.rotation_deg << " deg\n";
  return ate;
}

// Registers frame `i`, or records it as skipped when it cannot be read; returns whether it could.
// Registering never throws but for lack of memory (Odometry::register_frame); nor does a bad file.
// Settings that the frames cannot be read with (a depth border wider than the image) show on the
// first frame: until a frame was read they end the run; after, they are the frame's (a depth image
// of another size in the folder).
bool register_or_skip(Odometry& odometry, const FrameSource& source, std::size_t i, bool any_read) {
  PointCloud frame;
  try {
    frame = naming_depth_options([&] { return source.read(i); });
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const InvalidSettingsError& e) {
    if (!any_read) throw;
    odometry.skip_frame(std::string("unreadable with these settings: ") + e.what());
    return false;
  } catch (const std::exception& e) {
    odometry.skip_frame(std::string("unreadable: ") + e.what());
    return false;
  }
  odometry.register_frame(frame);
  return true;
}

// SIGINT and SIGTERM stop the run after the frame in hand: the map, the summary and every pose so
// far are written. A second signal ends the process at once (the per-frame files are on disk).
volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void on_stop_signal(int signal) {
  g_stop_signal = signal;
  std::signal(signal, SIG_DFL);
}

class StopOnSignal {
 public:
  StopOnSignal() {
    g_stop_signal = 0;
    interrupt_ = std::signal(SIGINT, on_stop_signal);
    terminate_ = std::signal(SIGTERM, on_stop_signal);
  }
  ~StopOnSignal() {
    std::signal(SIGINT, interrupt_);
    std::signal(SIGTERM, terminate_);
  }
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;
  [[nodiscard]] static int received() noexcept { return g_stop_signal; }

 private:
  void (*interrupt_)(int);
  void (*terminate_)(int);
};

// A long run frees each frame's buffers (a few MB) as the next frame allocates its own. glibc's
// malloc raises its mmap threshold to the largest block it has freed, so those buffers then come
// from the heap, whose freed pages it keeps: on 10,000 7-Scenes frames played back and forth the
// resident memory grew by 32 MB after the first 1,000 frames, to a peak of 187 MB, while the
// memory in use grew by 13 MB (the map's new points and the frames' reports). With the threshold
// fixed at glibc's initial 128 kB, large buffers go back at their free: +17 MB, peak 96 MB, the
// frames' registration time unchanged (bench/soak_odometry.py; docs/long-runs.md, Long runs). A
// 4 MB threshold kept the frames' buffers in the heap and the memory as high as without.
constexpr int kMmapThresholdBytes = 128 * 1024;

void return_large_buffers_at_free() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, kMmapThresholdBytes);
#endif
}

struct RunCount {
  std::size_t frames = 0;  // registered or skipped
  std::size_t unreadable = 0;
};

// Runs the odometry over the first `frames` frames (fewer when a signal stops it), writing each
// frame's lines as it goes, with a line per lost frame and the progress on stderr (unless
// --quiet).
RunCount register_frames(const OdometryOptions& o, const FrameSource& source, std::size_t frames,
                         Odometry& odometry, FrameWriters& writers,
                         std::chrono::steady_clock::time_point start) {
  auto last_progress = start;
  RunCount count;
  bool progress_open = false;  // a progress line without its newline is on stderr
  for (std::size_t i = 0; i < frames && StopOnSignal::received() == 0; ++i) {
    if (!register_or_skip(odometry, source, i, count.unreadable < count.frames)) {
      ++count.unreadable;
    }
    ++count.frames;
    writers.write(source, odometry);
    const FrameReport& r = odometry.reports().back();
    if (r.failed && !o.quiet) {
      std::cerr << (progress_open ? "\n" : "") << "frame " << i << " ("
                << source.frames[i].filename().string()
                << "): LOST, predicted pose used: " << r.message << '\n';
      progress_open = false;
    }
    const auto now = std::chrono::steady_clock::now();
    if (!o.quiet && (now - last_progress > std::chrono::seconds(1) || i + 1 == frames)) {
      const double s = std::chrono::duration<double>(now - start).count();
      std::cerr << "\r" << i + 1 << "/" << frames << " frames, " << std::fixed
                << std::setprecision(1) << static_cast<double>(i + 1) / s << " frames/s"
                << std::defaultfloat << (i + 1 == frames ? "\n" : "") << std::flush;
      last_progress = now;
      progress_open = i + 1 != frames;
    }
  }
  if (progress_open) std::cerr << '\n';
  return count;
}

// The TUM timestamps of the first `frames` frames: the source's, else frame / rate.
std::vector<double> tum_timestamps_s(const FrameSource& source, std::size_t frames,
                                     double rate_hz) {
  std::vector<double> times = frame_times_s(source, frames);
  if (times.empty()) {
    for (std::size_t i = 0; i < frames; ++i) times.push_back(static_cast<double>(i) / rate_hz);
  }
  return times;
}

void write_map(const OdometryOptions& o, const Odometry& odometry) {
  if (o.map_out.empty()) return;
  const WholeMap* map = odometry.whole_map();
  write_point_cloud(o.map_out, map ? map->cloud() : PointCloud{});
}

// --map-out is checked before the run, so that a long run does not end in an unwritable name.
void check_map_options(const OdometryOptions& o) {
  if (!(o.map_voxel_m >= 0.0 && o.map_voxel_m <= 1e6)) {
    throw InvalidSettingsError("--map-voxel " + format_number(o.map_voxel_m) +
                               ": must be in [0, 1000000] m");
  }
  if (o.map_out.empty()) return;
  const FileFormat format = format_from_extension(o.map_out);
  if (format != FileFormat::ply && format != FileFormat::pcd && format != FileFormat::xyz) {
    throw InvalidSettingsError("--map-out " + o.map_out +
                               ": the map is written as PLY, PCD or XYZ, give it a .ply, .pcd or "
                               ".xyz name");
  }
}

// The local map's size, and the whole map's when one is kept (--map-out); the fixed map's, and
// its build time, when localizing.
std::string map_summary(const OdometryOptions& o, const Odometry& odometry) {
  const VoxelMap* local = odometry.map();
  if (!o.localize_in.empty()) {  // run() made a Localizer
    return "map: " + std::to_string(local ? local->size() : 0) + " points in " +
           std::to_string(local ? local->voxels() : 0) + " voxels, built in " +
           format_number(static_cast<const Localizer&>(odometry).map_build_ms()) + " ms";
  }
  std::string out = "local map: " + std::to_string(local ? local->size() : 0) + " points in " +
                    std::to_string(local ? local->voxels() : 0) + " voxels";
  if (const WholeMap* whole = odometry.whole_map()) {
    out += "; whole map: " + std::to_string(whole->size()) + " points (voxel " +
           format_number(whole->voxel_size_m()) + " m)";
  }
  return out;
}

// The run in numbers: frames, failures, time per frame, map size, files written.
void print_run_summary(const OdometryOptions& o, const std::string& method,
                       const FrameSource& source, const RunCount& count, const Odometry& odometry,
                       std::chrono::steady_clock::time_point start) {
  const std::size_t frames = count.frames;
  const std::size_t unreadable = count.unreadable;
  std::vector<double> times_ms;
  for (const auto& r : odometry.reports()) times_ms.push_back(r.time_ms);
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << std::setprecision(4) << "method: " << method << ", layout: " << source.layout
            << ", voxel " << odometry.voxel_size_m() << " m\n"
            << "frames: " << frames << ", lost: " << odometry.lost_frames()
            << " (unreadable: " << unreadable << "), recovered: " << odometry.recovered_frames()
            << ", doubtful: " << odometry.doubtful_frames() << ", time per frame: median "
            << median_of(times_ms) << " ms, max "
            << (times_ms.empty() ? 0.0 : *std::max_element(times_ms.begin(), times_ms.end()))
            << " ms, " << static_cast<double>(frames) / total_s << " frames/s (with reading)\n"
            << map_summary(o, odometry) << '\n'
            << "poses: " << o.poses_out << (o.tum.empty() ? "" : ", TUM: " + o.tum)
            << (o.covariances_out.empty() ? "" : ", covariances: " + o.covariances_out)
            << (o.map_out.empty() ? "" : ", map: " + o.map_out) << '\n';
}

// The errors against the ground truth when given, and the picture when asked for.
void evaluate_and_draw(const OdometryOptions& o, const std::vector<Eigen::Matrix4d>& poses,
                       const std::optional<GroundTruth>& truth) {
  if (truth) {
    std::vector<Eigen::Matrix4d> compared;
    for (const std::size_t k : truth->frames) compared.push_back(poses[k]);
    const AbsoluteTrajectoryError ate = print_evaluation(compared, truth->poses);
    if (!o.picture.empty()) {
      render_trajectories_png(o.picture, compared, truth->poses, ate.T_truth_estimate);
    }
  } else if (!o.picture.empty()) {
    render_trajectories_png(o.picture, poses, {}, Eigen::Matrix4d::Identity());
  }
  if (!o.picture.empty()) std::cout << "picture: " << o.picture << '\n';
}

// --init: "global" (none: the global registration places the first frame), or a pose file.
std::optional<Eigen::Matrix4d> first_pose_in_map(const OdometryOptions& o) {
  if (o.init == "global") return std::nullopt;
  try {
    return read_transform(o.init);
  } catch (const Error& e) {
    throw InvalidInputError("--init " + o.init + " (a pose file, or 'global'): " + e.what());
  }
}

// The map of `sgdicp localize`, read before any frame.
PointCloud read_map(const OdometryOptions& o) {
  ReadResult read = read_point_cloud(o.localize_in);
  if (read.cloud.empty()) throw InvalidInputError(o.localize_in + ": the map has no point");
  return std::move(read.cloud);
}

void run(const OdometryOptions& o) {
  const MethodSpec method = make_method(o.settings.method, o.settings);
  const OdometrySettings settings = odometry_settings(o);
  if (!o.covariances_out.empty() && method.sgd.uncertainty.method == UncertaintyType::none) {
    throw InvalidSettingsError("--covariances-out needs --uncertainty laplace, sgld or svgd");
  }
  if (!o.picture.empty()) check_picture_name(o.picture);
  check_map_options(o);
  if (!(o.rate_hz >= 0.0 && std::isfinite(o.rate_hz))) {
    throw InvalidSettingsError("--rate " + format_number(o.rate_hz) + ": must be positive");
  }
  const FrameSource source =
      open_frame_source(o.input, intrinsics_option(o.depth.intrinsics), o.depth.settings);
  const double rate_hz =
      o.rate_hz > 0.0 ? o.rate_hz : (source.nominal_rate_hz > 0.0 ? source.nominal_rate_hz : 10.0);
  const std::size_t frames = o.max_frames ? std::min(o.max_frames, source.size()) : source.size();
  if (frames == 0) throw InvalidInputError(o.input + ": no frames to register");
  std::optional<GroundTruth> truth;
  if (!o.ground_truth.empty()) truth = load_ground_truth(o, source, frames);

  return_large_buffers_at_free();
  // Localize: the same pipeline with its map fixed (localizer.hpp).
  std::optional<Odometry> tracking;
  std::optional<Localizer> localizing;
  if (o.localize_in.empty()) {
    tracking.emplace(settings, method.name, method.sgd, method.batch);
  } else {
    localizing.emplace(read_map(o), first_pose_in_map(o), settings, method.name, method.sgd,
                       method.batch);
  }
  Odometry& odometry = tracking ? *tracking : *localizing;
  if (!o.map_out.empty()) odometry.keep_whole_map(o.map_voxel_m);
  FrameWriters writers(o, tum_timestamps_s(source, frames, rate_hz));
  const StopOnSignal stop;
  const auto start = std::chrono::steady_clock::now();
  RunCount count;
  try {
    count = register_frames(o, source, frames, odometry, writers, start);
  } catch (...) {
    // Out of memory, or a file that cannot be written: the poses so far are on disk; the map too.
    try {
      write_map(o, odometry);
    } catch (const std::exception& e) {
      std::cerr << "sgdicp: could not write the map: " << e.what() << '\n';
    }
    throw;
  }
  if (count.frames > 0 && count.unreadable == count.frames) {
    throw FormatError(
        o.input + ": no frame could be read (first: " + odometry.reports().front().message + ")");
  }
  write_map(o, odometry);
  print_run_summary(o, method.name, source, count, odometry, start);
  if (count.frames < frames) {
    throw ExitStatus("stopped by signal " + std::to_string(StopOnSignal::received()) + " after " +
                         std::to_string(count.frames) + " of " + std::to_string(frames) +
                         " frames: their poses, report and the map are written",
                     128 + StopOnSignal::received());
  }
  evaluate_and_draw(o, odometry.poses(), truth);
}

}  // namespace

namespace {

// The options `odometry` and `localize` share: the frames, what is written per frame, the
// evaluation, the odometry's and the registration's settings.
void add_frame_options(CLI::App& cmd, const std::shared_ptr<OdometryOptions>& o) {
  cmd.add_option("INPUT", o->input,
                 "Folder of frames, sorted by name: point clouds of one format (.pcd .ply .bin "
                 ".xyz .txt .csv .vtk .f32), a KITTI sequence folder (velodyne/*.bin, "
                 "times.txt), or a 7-Scenes folder (frame-NNNNNN.depth.png, "
                 "camera-intrinsics.txt)")
      ->required();
  cmd.add_option("--poses-out", o->poses_out,
                 "Write the trajectory here, frame by frame as the run goes: one line per frame, "
                 "the 3x4 row-major pose (KITTI format): T_first_frame for odometry (the first "
                 "line is the identity), T_map_frame for localize")
      ->required();
  cmd.add_option("--tum", o->tum,
                 "Also write the trajectory in the TUM format (timestamp tx ty tz qx qy qz qw), "
                 "timestamps from the source when known, else frame / --rate");
  cmd.add_option("--rate", o->rate_hz,
                 "Frame rate for TUM timestamps when the source has none, Hz [default: 0 = the "
                 "layout's: 7-Scenes and TUM 30, else 10]");
  cmd.add_option("--ground-truth", o->ground_truth,
                 "Ground-truth poses, one per frame: a KITTI poses file (12 numbers per line), a "
                 "TUM file (8 numbers per line; matched to the frames by timestamp within "
                 "0.02 s when the frames have timestamps, as TUM's associate.py) or a 7-Scenes "
                 "folder (frame-*.pose.txt); prints RPE, KITTI drift, ATE and end drift");
  cmd.add_flag("--ground-truth-prefix", o->ground_truth_prefix,
               "Compare with the first poses of a longer ground truth (a KITTI poses file of the "
               "whole sequence for its first frames)");
  cmd.add_option("--ground-truth-calib", o->ground_truth_calib,
                 "KITTI calib.txt: the ground truth is of the camera, moved to the scanner with "
                 "its Tr (velodyne to camera)");
  cmd.add_option("--picture", o->picture,
                 "Write a PNG (the name must end in .png) of the trajectory, seen along z (x-y) "
                 "and along y (x-z), with the ground truth when given (the estimate aligned "
                 "onto it as for the ATE)");
  cmd.add_option("--report", o->report,
                 "Write one CSV row per frame (failed, recovered, start, converged, iterations, "
                 "points, overlap, inliers, threshold, times, constraint ratio, doubtful, "
                 "message)");
  cmd.add_option("--covariances-out", o->covariances_out,
                 "Write each frame's pose covariance relative to the map (m, rad): one line of "
                 "36 numbers, 6x6 row-major, nan for none; needs --uncertainty");
  cmd.add_option("--deskew", o->deskew,
                 "Motion compensation of each frame before it is registered and enters the map: "
                 "auto (when the frames carry per-point times: PCD/PLY time fields, docs/io.md), "
                 "none, or azimuth (times from each point's azimuth, for KITTI's .bin sweeps) "
                 "[default: auto]")
      ->check(CLI::IsMember(canonical_names<DeskewMode>()));
  cmd.add_option("--max-frames", o->max_frames, "Stop after this many frames [default: 0 = all]");
  cmd.add_flag("--quiet,-q", o->quiet, "No progress and no per-frame failure lines on stderr");
  add_table_options(cmd, odometry_settings_table(), OdometrySettings{}, o->odometry_values);
  cmd.add_option("--method", o->settings.method,
                 "Registration step: " + method_list(", ") +
                     " (methods of `sgdicp register`) "
                     "[default: sgd]");
  add_settings_options(cmd, o->settings, /*with_voxel_grid=*/false);
  add_depth_options(cmd, o->depth);
}

}  // namespace

void add_odometry_command(CLI::App& app) {
  auto o = std::make_shared<OdometryOptions>();
  CLI::App* cmd = app.add_subcommand(
      "odometry",
      "Scan-to-map odometry over a folder of frames: each frame registered to a local voxel map "
      "of the frames before it, from a predicted pose. Writes the pose of every frame in the "
      "first frame's coordinates (docs/odometry.md). The registration options below apply to "
      "each frame; giving --max-distance fixes d_max (no adaptive threshold). The registrations "
      "from the prediction and the last pose take Gauss-Newton steps unless --optimizer or "
      "--learning-rate is given; giving --learning-rate keeps it uncapped "
      "(Adam and RMSProp steps are otherwise capped at d_max / 4).");
  add_frame_options(*cmd, o);
  cmd->add_option("--map-out", o->map_out,
                  "Write the whole map at the end, or when a signal stops the run: every "
                  "registered frame's points in the first frame's coordinates, metres, one "
                  "centroid per --map-voxel (PLY, PCD or XYZ by the extension)");
  cmd->add_option("--map-voxel", o->map_voxel_m,
                  "Voxel of the written map: one centroid per voxel of this side, m [default: 0 = "
                  "the odometry's voxel]");
  // What a user of the command sets; every other option is in --help-all.
  static constexpr std::array<CommonOption, 13> kCommon{
      {{"poses-out", "Write each frame's pose here as the run goes (KITTI 3x4 format)"},
       {"tum", "Also write the trajectory in the TUM format"},
       kGroundTruthBrief,
       kReportBrief,
       kCovariancesBrief,
       {"map-out", "Write the whole map at the end (PLY, PCD or XYZ)"},
       {"quiet", ""},
       kMethodBrief,
       {"voxel-size", "Map voxel side, m; 0 = from the first frame's range"},
       kMaxRangeBrief,
       kThreadsBrief,
       kUncertaintyBrief,
       kIntrinsicsBrief}};
  arrange_help(*cmd, kCommon);
  cmd->callback([o] { run(*o); });
}

void add_localize_command(CLI::App& app) {
  auto o = std::make_shared<OdometryOptions>();
  CLI::App* cmd = app.add_subcommand(
      "localize",
      "Localization in a map made before: each frame of a folder registered to a fixed map (a "
      "point cloud: an odometry run's --map-out, or any PLY/PCD map), never extended. The first "
      "frame is placed by the global registration (or --init); every later one from the motion "
      "model's prediction, with the odometry's retries. A frame the map does not hold is "
      "reported lost, not placed. Writes each frame's pose in the map's coordinates "
      "(docs/localization.md).");
  cmd->add_option("MAP", o->localize_in, "The map: a point cloud file (PLY, PCD, ...), metres")
      ->required();
  add_frame_options(*cmd, o);
  cmd->add_option("--init", o->init,
                  "The first frame's pose in the map: a file with a 4x4 or 3x4 transform, or "
                  "'global' (the global registration finds it) [default: global]");
  static constexpr std::array<CommonOption, 11> kCommon{
      {{"poses-out", "Write each frame's pose in the map here as the run goes (KITTI 3x4)"},
       {"init", "The first frame's pose in the map (a 4x4 file), or 'global'"},
       kGroundTruthBrief,
       kReportBrief,
       kCovariancesBrief,
       {"quiet", ""},
       kMethodBrief,
       kMaxRangeBrief,
       kThreadsBrief,
       kUncertaintyBrief,
       kIntrinsicsBrief}};
  arrange_help(*cmd, kCommon);
  cmd->callback([o] {
    if (o->init.empty()) throw InvalidSettingsError("--init: a pose file, or 'global'");
    run(*o);
  });
}

}  // namespace sgdicp::cli
