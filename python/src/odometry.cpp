// sgd_icp.Odometry: the library's Odometry (odometry.hpp) fed one NumPy frame at a time, with the
// keywords of the CLI's `sgdicp odometry` options (the odometry table, then the registration's).
#include <algorithm>
#include <cmath>
#include <string>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/odometry/localizer.hpp"
#include "sgdicp/odometry/odometry.hpp"

namespace sgdicp::python {
namespace {

using namespace pybind11::literals;

// The odometry keywords of `overrides` applied to the defaults; the others left for the
// registration.
OdometrySettings take_odometry_keywords(py::dict& overrides) {
  OdometrySettings s = take_keywords(OdometrySettings{}, overrides, odometry_settings_table());
  s.adaptive_threshold = !overrides.contains("max_distance");
  s.step_within_threshold = !overrides.contains("learning_rate");
  s.tracking_gauss_newton =
      !overrides.contains("optimizer") && !overrides.contains("learning_rate");
  if (overrides.contains("deskew")) {
    s.deskew = parse_enum<DeskewMode>(py::cast<std::string>(overrides["deskew"]));
    overrides.attr("pop")("deskew");
  }
  return s;
}

// What a Settings given to the odometry chose itself counts as chosen, as its keyword would: a
// step rule of its own keeps the tracking's Gauss-Newton steps off and its step uncapped, a d_max
// of its own turns the adaptive threshold off.
void chosen_in_settings(const SgdSettings& sgd, OdometrySettings& odometry) {
  const SgdSettings defaults;
  if (sgd.optimizer.type != defaults.optimizer.type) odometry.tracking_gauss_newton = false;
  if (sgd.optimizer.learning_rate != defaults.optimizer.learning_rate) {
    odometry.tracking_gauss_newton = false;
    odometry.step_within_threshold = false;
  }
  if (sgd.pairing.max_correspondence_distance != defaults.pairing.max_correspondence_distance) {
    odometry.adaptive_threshold = false;
  }
}

// What Odometry's and Localizer's constructors take, from the method and the keywords.
struct OdometryArguments {
  OdometrySettings settings;
  std::string method;
  SgdSettings sgd;
  BatchSettings batch;
};

// `settings` (a Settings, a BatchSettings or None) is the registration's base, as register()'s;
// a step rule or d_max it sets is the user's, as the keywords' are (take_odometry_keywords).
OdometryArguments odometry_arguments(const std::string& method, const py::object& settings,
                                     const py::kwargs& kwargs) {
  py::dict overrides(kwargs);
  OdometrySettings odometry = take_odometry_keywords(overrides);
  // voxel_size= was taken as the map's; the registration's own grid has no place here.
  if (overrides.contains("downsample_to")) {
    throw InvalidSettingsError(
        "downsample_to= does not apply to the odometry: it thins frames and map on its own "
        "voxel grid (voxel_size=)");
  }
  const Method& m = method_from_string(method);
  if (m.cost && overrides.contains("cost")) {
    throw InvalidSettingsError("method='" + std::string(m.name) +
                               "' sets the cost; drop cost= (or use method='sgd' with cost=)");
  }
  SgdSettings sgd;
  BatchSettings batch;
  try {
    if (m.solver == Solver::sgd) {
      sgd = settings_or_default(settings, m);
      chosen_in_settings(sgd, odometry);
      apply_method_cost(m, sgd, batch);
      sgd = with_overrides(sgd, overrides);
    } else {
      batch = batch_settings_or_default(settings, m);
      batch.cost = *m.cost;
      batch = with_batch_overrides(batch, overrides, m.name);
    }
  } catch (const py::type_error& e) {
    std::string names;
    for (const auto& s : odometry_settings_table()) {
      names += (names.empty() ? "" : ", ") + keyword_of(s.name);
    }
    throw py::type_error(std::string(e.what()) + "; the odometry keywords: " + names);
  }
  return {odometry, std::string(m.name), sgd, batch};
}

Odometry make_odometry(const std::string& method, const py::object& settings,
                       const py::kwargs& kwargs) {
  const OdometryArguments a = odometry_arguments(method, settings, kwargs);
  return Odometry(a.settings, a.method, a.sgd, a.batch);
}

Localizer make_localizer(const py::handle& map, const py::object& init, const std::string& method,
                         const py::object& settings, const py::kwargs& kwargs) {
  ConvertedCloud cloud = cloud_from_array(map, "map", NonFinite::drop, /*allow_empty=*/true);
  std::optional<Eigen::Matrix4d> T_map_first_frame;
  if (!init.is_none()) T_map_first_frame = matrix_from_array(init, "init");
  const OdometryArguments a = odometry_arguments(method, settings, kwargs);
  return Localizer(std::move(cloud.cloud), T_map_first_frame, a.settings, a.method, a.sgd, a.batch);
}

py::array_t<double> stacked(const std::vector<Eigen::Matrix4d>& poses) {
  py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}, py::ssize_t{4}});
  auto a = out.mutable_unchecked<3>();
  for (std::size_t k = 0; k < poses.size(); ++k) {
    for (py::ssize_t i = 0; i < 4; ++i) {
      for (py::ssize_t j = 0; j < 4; ++j) {
        a(static_cast<py::ssize_t>(k), i, j) = poses[k](i, j);
      }
    }
  }
  return out;
}

// The frame, with its points' times (seconds, relative to the earliest, computed in double) when
// given: rows with a non-finite coordinate are kept then, so that the times stay aligned, and the
// odometry's range crop drops them.
ConvertedCloud frame_with_times(const py::handle& points, const py::object& times) {
  if (times.is_none()) return cloud_from_array(points, "frame", NonFinite::drop, true);
  ConvertedCloud frame = cloud_from_array(points, "frame", NonFinite::keep, true);
  frame.cloud.times_s = times_from_array(times, frame.cloud.size()).relative_s;
  return frame;
}

}  // namespace

void bind_odometry(py::module_& m) {
  py::class_<FrameReport>(m, "FrameReport", "What happened to one frame of an Odometry.")
      .def_readonly("index", &FrameReport::index, "Frame number, from 0.")
      .def_property_readonly(
          "T_first_frame", [](const FrameReport& r) { return array_from_matrix(r.T_first_frame); },
          "(4, 4) float64 pose of the frame in the first frame's coordinates.")
      .def_readonly("failed", &FrameReport::failed,
                    "True if the frame is lost: no start registered it, the pose is the "
                    "motion model's prediction (see message), and neither the map nor the "
                    "motion model took it in.")
      .def_readonly("recovered", &FrameReport::recovered,
                    "True if a retry registered the frame after the registration from the "
                    "prediction was rejected (message says why; start says which retry).")
      .def_property_readonly(
          "start", [](const FrameReport& r) { return std::string(enum_name(r.start)); },
          ("Where the accepted registration started: " + name_list<FrameStart>() + ".").c_str())
      .def_readonly("overlap", &FrameReport::overlap,
                    "Fraction of the registered frame's points with a map point within one map "
                    "voxel (a frame below half the recent frames' is rejected); 0 when not "
                    "registered.")
      .def_readonly("doubtful", &FrameReport::doubtful,
                    "Registered, but the pose may be off (message says why after 'doubtful: '): "
                    "the scene leaves some motion unconstrained while the prediction was "
                    "uncertain, or no start overlapped the map like the last frames.")
      .def_readonly("constraint_ratio", &FrameReport::constraint_ratio,
                    "The registration's smallest over largest eigenvalue of its point-to-plane "
                    "information (RegistrationResult.constraint_ratio); 0 when not registered.")
      .def_readonly("converged", &FrameReport::converged,
                    "True if the registration's convergence test passed.")
      .def_readonly("message", &FrameReport::message,
                    "Why the frame failed, or the registration's stop message.")
      .def_readonly("iterations", &FrameReport::iterations, "Iterations of the registration.")
      .def_readonly("source_points", &FrameReport::source_points,
                    "Frame points registered (after cropping and thinning).")
      .def_readonly("map_points", &FrameReport::map_points, "Map points registered to.")
      .def_readonly("inlier_ratio", &FrameReport::inlier_ratio, "Inlier ratio of the registration.")
      .def_readonly("inlier_rmse_m", &FrameReport::inlier_rmse_m,
                    "Inlier RMSE of the registration, metres.")
      .def_readonly(
          "threshold_m", &FrameReport::threshold_m,
          "d_max given to the registration (3 sigma of the adaptive threshold), metres; 0 when "
          "max_distance= fixes it.")
      .def_readonly("index_build_ms", &FrameReport::index_build_ms,
                    "KD-tree build over the map (plus normals or covariances), milliseconds.")
      .def_readonly("time_ms", &FrameReport::time_ms,
                    "The whole frame (thinning, index, registration, map update), milliseconds.")
      .def_property_readonly(
          "covariance",
          [](const FrameReport& r) {
            py::array_t<double> out({py::ssize_t{6}, py::ssize_t{6}});
            auto a = out.mutable_unchecked<2>();
            for (py::ssize_t i = 0; i < 6; ++i) {
              for (py::ssize_t j = 0; j < 6; ++j) a(i, j) = r.covariance(i, j);
            }
            return out;
          },
          "(6, 6) float64 covariance of the frame's pose relative to the map it was registered "
          "against (uncertainty='laplace', 'sgld' or 'svgd'): the registration's covariance_se3, "
          "translation first, xi in the frame's own tangent space (T_first_frame = T_hat @ "
          "Exp(xi)), metres and radians; the map's own error is not in it. The first frame: "
          "zeros; a repeated frame: the previous frame's; a frame without one (lost, no "
          "point, or no uncertainty asked): NaN.")
      .def("__repr__", [](const FrameReport& r) {
        return "<sgd_icp.FrameReport " + std::to_string(r.index) + (r.failed ? " FAILED: " : ": ") +
               r.message + ">";
      });

  std::string keywords;
  for (const auto& s : odometry_settings_table()) {
    keywords += (keywords.empty() ? "" : ", ") + keyword_of(s.name) + " (" +
                format_value(s.get(OdometrySettings{})) + (s.unit.empty() ? "" : " ") +
                std::string(s.unit) + ")";
  }
  py::class_<Odometry>(m, "Odometry",
                       "Scan-to-map odometry: frames (points in their sensor frame) registered one "
                       "at a time to a local voxel map, from the last motion's share that carried "
                       "over between frames, with an adaptive correspondence threshold "
                       "(docs/odometry.md).")
      .def(py::init(
               [](const std::string& method, const py::object& settings, const py::kwargs& kwargs) {
                 return make_odometry(method, settings, kwargs);
               }),
           "method"_a = "sgd", py::kw_only(), "settings"_a = py::none(),
           ("method: the registration step, a --method of the CLI (" + method_list() +
            "). settings: the registration's base settings, as register()'s (a Settings, or a "
            "BatchSettings for a batch method; None = the defaults). Keywords: the odometry "
            "settings of `sgdicp odometry` (" +
            keywords +
            "; 0 = derived from the data, docs/odometry.md), deskew= ('auto', 'none', "
            "'azimuth') and the keywords of register() for the method; most runs set at most "
            "voxel_size=, max_range=, threads= and uncertainty=. max_distance= fixes d_max and "
            "turns the adaptive "
            "threshold off. Raises TypeError for an unknown keyword, InvalidSettingsError for an "
            "invalid value.")
               .c_str())
      .def(
          "register_frame",
          [](Odometry& o, const py::handle& points, const py::object& times) {
            const ConvertedCloud frame = frame_with_times(points, times);
            const Eigen::Matrix4d T = [&] {
              const py::gil_scoped_release release;
              return o.register_frame(frame.cloud);
            }();
            return array_from_matrix(T);
          },
          "points"_a, "times"_a = py::none(),
          "Registers the next frame, an (N, 3) float32/float64 array in its sensor frame "
          "(metres), and returns its (4, 4) pose in the first frame's coordinates (the first "
          "frame: the identity). times: None, or each point's time (N,), seconds, any origin: the "
          "frame is then deskewed (deskew='auto', docs/deskewing.md). A frame that fails (see "
          "last_report) gets the predicted pose.")
      .def(
          "skip_frame",
          [](Odometry& o, const std::string& message) {
            return array_from_matrix(o.skip_frame(message));
          },
          "message"_a,
          "Records a frame that could not be read: it gets the predicted pose and a failed "
          "report with `message`.")
      .def_property_readonly(
          "poses", [](const Odometry& o) { return stacked(o.poses()); },
          "(K, 4, 4) float64 poses of the frames so far, in the first frame's coordinates.")
      .def_property_readonly(
          "reports", [](const Odometry& o) { return o.reports(); },
          "A FrameReport per frame so far.")
      .def_property_readonly(
          "last_report",
          [](const Odometry& o) -> py::object {
            if (o.reports().empty()) return py::none();
            return py::cast(o.reports().back());
          },
          "The FrameReport of the last frame, or None before the first.")
      .def_property_readonly(
          "voxel_size", [](const Odometry& o) { return o.voxel_size_m(); },
          "The map's voxel size in use, metres (0 before the first frame when derived).")
      .def_property_readonly(
          "map_points", [](const Odometry& o) { return o.map() ? o.map()->size() : 0; },
          "Points in the local map.")
      .def(
          "map_cloud",
          [](const Odometry& o, double voxel_size) {
            if (!(voxel_size >= 0.0 && std::isfinite(voxel_size))) {
              throw InvalidSettingsError("voxel_size=" + format_number(voxel_size) +
                                         ": must be 0 or a positive length in metres");
            }
            return array_from_cloud(o.map_cloud(voxel_size));
          },
          "voxel_size"_a = 0.0,
          "The local map's points (what the next frame is registered to: the voxels within "
          "max_range of the last pose), an (N, 3) float32 array in the first frame's coordinates "
          "(metres), thinned to one centroid per voxel of voxel_size metres when above 0. The "
          "whole map: whole_map().")
      .def("keep_whole_map", &Odometry::keep_whole_map, "voxel_size"_a = 0.0,
           "From the next frame on, keeps the whole map: every registered frame's points in the "
           "first frame's coordinates, one centroid per voxel of voxel_size metres (0 = the "
           "odometry's voxel, following it when it grows), as `sgdicp odometry --map-out "
           "--map-voxel` writes it. Lost frames do not enter it; its memory grows with the space "
           "covered, not with the frames.")
      .def(
          "whole_map",
          [](const Odometry& o) {
            const WholeMap* map = o.whole_map();
            return array_from_cloud(map ? map->cloud() : PointCloud{});
          },
          "The whole map kept since keep_whole_map(): an (N, 3) float32 array in the first "
          "frame's coordinates (metres); empty before keep_whole_map() or any registered frame.")
      .def_property_readonly("lost_frames", &Odometry::lost_frames,
                             "Frames lost so far (no start registered them, or unreadable).")
      .def_property_readonly("doubtful_frames", &Odometry::doubtful_frames,
                             "Frames registered but doubtful so far (FrameReport.doubtful).")
      .def_property_readonly("recovered_frames", &Odometry::recovered_frames,
                             "Frames registered by a retry so far.")
      .def_property_readonly(
          "method", [](const Odometry& o) { return std::string(o.method()); },
          "The registration method's name.")
      .def("__len__", [](const Odometry& o) { return o.poses().size(); });
  py::class_<Localizer, Odometry>(
      m, "Localizer",
      "Localization in a map made before: an Odometry whose map is fixed (never extended), the "
      "first frame placed by the global registration (or from init), every later one from the "
      "motion model's prediction; a frame the map does not hold is lost, not placed. Poses are "
      "in the map's coordinates (docs/localization.md).")
      .def(py::init([](const py::handle& map, const py::object& init, const std::string& method,
                       const py::object& settings, const py::kwargs& kwargs) {
             return make_localizer(map, init, method, settings, kwargs);
           }),
           "map"_a, "init"_a = py::none(), "method"_a = "sgd", py::kw_only(),
           "settings"_a = py::none(),
           "map: (N, 3) float32/float64 array of the map's points, metres. init: the first "
           "frame's (4, 4) pose in the map, or None (the global registration places it). method "
           "and the keywords: as Odometry's. Raises InvalidInputError for a map without a finite "
           "point or georeferenced (coordinates beyond 16 km, not supported yet).")
      .def_property_readonly("map_build_ms", &Localizer::map_build_ms,
                             "The time the map's voxels and surfaces took to build (at the first "
                             "frame), ms; 0 before.");
}

}  // namespace sgdicp::python
