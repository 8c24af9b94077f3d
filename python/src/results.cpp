// sgd_icp.RegistrationResult, Trace and PoseMode: the C++ result as Python sees it, NumPy arrays
// and plain values.
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "bindings.hpp"

namespace sgdicp::python {
namespace {

Trace make_trace(const std::vector<TraceEntry>& entries) {
  const auto k = static_cast<py::ssize_t>(entries.size());
  Trace t{py::array_t<std::int64_t>(k),
          py::array_t<std::int64_t>(k),
          py::array_t<double>(std::vector<py::ssize_t>{k, 4, 4}),
          py::array_t<double>(k),
          py::array_t<double>(k),
          py::array_t<std::int64_t>(k),
          py::array_t<double>(k)};
  auto iteration = t.iteration.mutable_unchecked<1>();
  auto points = t.points_processed.mutable_unchecked<1>();
  auto pose = t.T_reference_source.mutable_unchecked<3>();
  auto step = t.step_size.mutable_unchecked<1>();
  auto distance = t.max_distance_m.mutable_unchecked<1>();
  auto inliers = t.inliers.mutable_unchecked<1>();
  auto cost = t.cost.mutable_unchecked<1>();
  for (py::ssize_t i = 0; i < k; ++i) {
    const TraceEntry& e = entries[static_cast<std::size_t>(i)];
    iteration(i) = static_cast<std::int64_t>(e.iteration);
    points(i) = static_cast<std::int64_t>(e.points_processed);
    for (py::ssize_t r = 0; r < 4; ++r) {
      for (py::ssize_t c = 0; c < 4; ++c) pose(i, r, c) = e.T_reference_source(r, c);
    }
    step(i) = e.step_size;
    distance(i) = e.max_distance_m;
    inliers(i) = static_cast<std::int64_t>(e.inliers);
    cost(i) = e.cost;
  }
  return t;
}

// A (rows, 6) array of `rows` values of `at(i, k)`.
template <typename F>
py::array_t<double> pose_rows(py::ssize_t rows, F&& at) {
  py::array_t<double> out(std::vector<py::ssize_t>{rows, 6});
  auto a = out.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < rows; ++i) {
    for (py::ssize_t k = 0; k < 6; ++k) a(i, k) = at(i, k);
  }
  return out;
}

py::array_t<double> pose_vector_array(const Eigen::Matrix<double, 6, 1>& v) {
  py::array_t<double> out(6);
  for (py::ssize_t k = 0; k < 6; ++k) out.mutable_at(k) = v[k];
  return out;
}

}  // namespace

Result make_result(RegistrationResult r) {
  Result out;
  out.T_reference_source = array_from_matrix(r.T_reference_source);
  out.trace = make_trace(r.trace);
  r.trace.clear();
  out.covariance = pose_rows(6, [&](auto i, auto k) { return r.covariance(i, k); });
  out.covariance_se3 = pose_rows(6, [&](auto i, auto k) { return r.covariance_se3(i, k); });
  out.samples = pose_rows(static_cast<py::ssize_t>(r.samples.size()), [&](auto i, auto k) {
    return r.samples[static_cast<std::size_t>(i)][k];
  });
  out.sample_mean = pose_vector_array(r.sample_mean);
  for (const PoseMode& m : r.modes) {
    out.modes.append(Mode{m.weight, pose_vector_array(m.mean),
                          pose_rows(6, [&](auto i, auto k) { return m.covariance(i, k); })});
  }
  r.samples.clear();
  out.fields = std::move(r);
  return out;
}

void bind_results(py::module_& m) {
  py::class_<Trace>(m, "Trace",
                    "Per-iteration record of a registration (Settings.record_trace), one array "
                    "element per iteration.")
      .def_readonly("iteration", &Trace::iteration, "(K,) int64, iteration number.")
      .def_readonly("points_processed", &Trace::points_processed,
                    "(K,) int64, source points drawn so far.")
      .def_readonly("T_reference_source", &Trace::T_reference_source,
                    "(K, 4, 4) float64, metric pose after each iteration.")
      .def_readonly("step_size", &Trace::step_size,
                    "(K,) float64, effective learning rate of each iteration.")
      .def_readonly("max_distance_m", &Trace::max_distance_m, "(K,) float64, d_max used, metres.")
      .def_readonly("inliers", &Trace::inliers, "(K,) int64, pairs kept in each mini-batch.")
      .def_readonly("cost", &Trace::cost, "(K,) float64, mini-batch cost F, scaled units^2.")
      .def("__len__", [](const Trace& t) { return t.iteration.size(); })
      .def("__repr__", [](const Trace& t) {
        return "<sgd_icp.Trace of " + std::to_string(t.iteration.size()) + " iterations>";
      });

  py::class_<Mode>(m, "PoseMode",
                   "One mode of the svgd particles (RegistrationResult.modes; "
                   "docs/uncertainty.md).")
      .def_readonly("weight", &Mode::weight, "Fraction of the particles in this mode.")
      .def_readonly("mean", &Mode::mean,
                    "(6,) float64: mean theta = (x, y, z, roll, pitch, yaw), metres and radians.")
      .def_readonly("covariance", &Mode::covariance,
                    "(6, 6) float64: covariance of theta in this mode, metres and radians.")
      .def("__repr__", [](const Mode& mode) {
        return std::string(py::str("<sgd_icp.PoseMode weight {:.3g}>").format(mode.weight));
      });

  py::class_<Result> result(
      m, "RegistrationResult",
      "What register() returns: the transform, why it stopped, the work done and "
      "the final inlier statistics (every field of the C++ RegistrationResult, "
      "plus the non-finite rows dropped and the KD-tree build time).");
  result
      .def_readonly("T_reference_source", &Result::T_reference_source,
                    "(4, 4) float64, metres: maps source points into the reference frame, p_ref "
                    "= R @ p_src + t.")
      .def_readonly("build_ms", &Result::build_ms,
                    "Wall time of the KD-tree build (and reference normals/covariances) for an "
                    "array reference, milliseconds (0 for a ReferenceIndex).")
      .def_readonly("source_non_finite_dropped", &Result::source_non_finite_dropped,
                    "Source rows dropped for a NaN or infinite coordinate.")
      .def_readonly("reference_non_finite_dropped", &Result::reference_non_finite_dropped,
                    "Reference rows dropped for a NaN or infinite coordinate.")
      .def_readonly("trace", &Result::trace, "Per-iteration Trace; empty unless record_trace=True.")
      .def_readonly("covariance", &Result::covariance,
                    "(6, 6) float64: covariance of theta = (x, y, z, roll, pitch, yaw) of "
                    "T_reference_source (R = Rz(yaw) Ry(pitch) Rx(roll)), metres and radians; "
                    "zeros unless uncertainty='laplace', 'sgld' or 'svgd' (svgd: the heaviest "
                    "mode's; docs/uncertainty.md).")
      .def_readonly("covariance_se3", &Result::covariance_se3,
                    "(6, 6) float64: the same in the tangent space of SE(3), xi = (rho, phi) "
                    "translation first, right perturbation T = T_reference_source @ Exp(xi).")
      .def_readonly("samples", &Result::samples,
                    "(K, 6) float64: the SGLD samples (sgld) or the particles (svgd) of theta (as "
                    "covariance); (0, 6) otherwise.")
      .def_readonly("sample_mean", &Result::sample_mean,
                    "(6,) float64: the mean of the samples (zeros without samples).")
      .def_readonly("modes", &Result::modes,
                    "uncertainty='svgd': the modes of the particles (PoseMode), heaviest first "
                    "(covariance is the first's); empty otherwise.")
      .def("__repr__", [](const Result& r) {
        return std::string(py::str("<sgd_icp.RegistrationResult {}: {} iterations, {} points "
                                   "processed, inlier RMSE {:.4g} m ({:.1%} inliers), {:.1f} ms>")
                               .format(to_string(r.fields.stop_reason), r.fields.iterations,
                                       r.fields.points_processed, r.fields.inlier_rmse_m,
                                       r.fields.inlier_ratio, r.fields.time_ms));
      });
  // The fields of the C++ result, from its one list (result.hpp).
  for_each_result_field([&](const char* name, auto member, const char* doc) {
    result.def_property_readonly(
        name,
        [member](const Result& r) {
          if constexpr (std::is_same_v<std::remove_cvref_t<decltype(r.fields.*member)>,
                                       StopReason>) {
            return std::string(to_string(r.fields.*member));
          } else {
            return r.fields.*member;
          }
        },
        doc);
  });
}

}  // namespace sgdicp::python
