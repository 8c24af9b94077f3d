// sgd_icp.register: SGD-ICP or a batch method on two clouds (arrays, Open3D clouds or a
// ReferenceIndex), with a settings object and the flat keyword overrides; its docstring.
#include <algorithm>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "bindings.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/global/global_registration.hpp"
#include "sgdicp/registration/batch_icp.hpp"
#include "sgdicp/registration/deskew.hpp"
#include "sgdicp/registration/methods.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"

namespace sgdicp::python {

using namespace pybind11::literals;

/// A --method of the CLI (methods.hpp), by name.
const Method& method_from_object(const py::handle& value) {
  if (!py::isinstance<py::str>(value)) {
    throw py::type_error("method must be a str (" + method_list() + "), got " + type_name(value));
  }
  return method_from_string(value.cast<std::string>());
}

/// A copy of `settings` (a Settings), or the defaults for None.
SgdSettings settings_or_default(const py::handle& settings, const Method& method) {
  if (settings.is_none()) return SgdSettings{};
  if (!py::isinstance<SgdSettings>(settings)) {
    throw py::type_error("settings must be a sgd_icp.Settings or None, got " + type_name(settings) +
                         (py::isinstance<BatchSettings>(settings)
                              ? " (a BatchSettings is for method='icp', 'icp-plane' or 'gicp'; "
                                "method='" +
                                    std::string(method.name) + "' takes a Settings)"
                              : std::string()));
  }
  return settings.cast<SgdSettings>();
}

/// A copy of `settings` (a BatchSettings), or the defaults for None.
BatchSettings batch_settings_or_default(const py::handle& settings, const Method& method) {
  if (settings.is_none()) return BatchSettings{};
  if (!py::isinstance<BatchSettings>(settings)) {
    throw py::type_error("settings must be a sgd_icp.BatchSettings or None for the batch method '" +
                         std::string(method.name) + "', got " + type_name(settings));
  }
  return settings.cast<BatchSettings>();
}

namespace {

template <typename Settings>
ReferenceNeeds needs_of(const Settings& s, bool cost_in_index) {
  return {cost_in_index ? std::optional<CostType>(s.cost) : std::nullopt,
          [s](PointCloud cloud) { return reference_index_for(std::move(cloud), s); }};
}

/// Registration with either solver: the index (given, or built as `needs` says), then
/// `run(index)` with the GIL released.
template <typename Run>
Result register_with(const ConvertedCloud& src, const py::handle& reference,
                     const ReferenceNeeds& needs, Run run) {
  std::shared_ptr<const SharedIndex> index;
  double build_ms = 0.0;
  if (py::isinstance<SharedIndex>(reference)) {
    index = reference.cast<std::shared_ptr<SharedIndex>>();  // keeps it alive during the run
    if (needs.cost) check_prepared(*index, *needs.cost);
  } else {
    auto built =
        build_index(cloud_from_array(reference, "reference", NonFinite::drop), needs.build);
    build_ms = built->build_ms;
    index = std::move(built);
  }

  const RegistrationResult r = [&] {
    const py::gil_scoped_release release;
    return run(index->index);
  }();
  Result out = make_result(r);
  out.build_ms = build_ms;
  out.source_non_finite_dropped = src.non_finite_dropped;
  out.reference_non_finite_dropped = index->non_finite_dropped;
  return out;
}

/// The settings of a method with the user's settings object and keyword overrides.
SgdSettings sgd_settings_of(const Method& m, const py::handle& settings,
                            const py::dict& overrides) {
  SgdSettings base = settings_or_default(settings, m);
  BatchSettings unused;
  apply_method_cost(m, base, unused);
  return with_overrides(base, overrides);
}
BatchSettings batch_settings_of(const Method& m, const py::handle& settings,
                                const py::dict& overrides) {
  BatchSettings base = batch_settings_or_default(settings, m);
  base.cost = *m.cost;
  return with_batch_overrides(base, overrides, std::string(m.name));
}

/// The global registration's keywords (global_settings_table) taken out of `overrides`; given
/// without init='global', an error.
GlobalSettings take_global_keywords(py::dict& overrides, bool global) {
  for (const auto& s : global_settings_table()) {
    const std::string keyword = keyword_of(s.name);
    if (!global && overrides.contains(keyword)) {
      throw InvalidSettingsError(keyword + "=" + std::string(py::repr(overrides[keyword.c_str()])) +
                                 ": only with init='global'");
    }
  }
  return take_keywords(GlobalSettings{}, overrides, global_settings_table());
}

Result register_clouds(const py::handle& source, const py::handle& reference,
                       const py::handle& init, const py::handle& settings, const py::handle& method,
                       const py::kwargs& kwargs) {
  const Method& m = method_from_object(method);
  if (m.cost && kwargs.contains("cost")) {
    throw InvalidSettingsError("method='" + std::string(m.name) +
                               "' sets the cost; drop cost= (or use method='sgd' with cost=)");
  }
  const bool global = py::isinstance<py::str>(init);
  if (global && init.cast<std::string>() != "global") {
    throw InvalidInputError("init must be a (4, 4) array of numbers or 'global', got '" +
                            init.cast<std::string>() + "'");
  }
  if (global && m.solver != Solver::sgd) {
    throw InvalidSettingsError("init='global': only with an SGD method (method='" +
                               std::string(m.name) + "')");
  }
  py::dict overrides = kwargs.attr("copy")();
  const GlobalSettings global_settings = take_global_keywords(overrides, global);
  const auto T_init = [&] {
    return init.is_none() ? Eigen::Matrix4d::Identity().eval() : matrix_from_array(init, "init");
  };
  if (global) {
    const SgdSettings s = sgd_settings_of(m, settings, overrides);
    const ConvertedCloud src = cloud_from_array(source, "source", NonFinite::drop);
    return register_with(src, reference, needs_of(s, false), [&](const ReferenceIndex& index) {
      return align_global(src.cloud, index, s, global_settings);
    });
  }
  if (m.solver == Solver::sgd) {
    const SgdSettings s = sgd_settings_of(m, settings, overrides);
    const Eigen::Matrix4d T = T_init();
    const ConvertedCloud src = cloud_from_array(source, "source", NonFinite::drop);
    return register_with(src, reference, needs_of(s, false), [&](const ReferenceIndex& index) {
      return align(src.cloud, index, s, T);
    });
  }
  const BatchSettings b = batch_settings_of(m, settings, overrides);
  const Eigen::Matrix4d T = T_init();
  const ConvertedCloud src = cloud_from_array(source, "source", NonFinite::drop);
  return register_with(src, reference, needs_of(b, true), [&](const ReferenceIndex& index) {
    return align_batch(src.cloud, index, b, T);
  });
}

// ---- docstrings

constexpr const char* kRegisterDocTemplate =
    R"doc(Registers `source` to `reference` with SGD-ICP, or with a batch ICP method.

Returns a RegistrationResult whose T_reference_source (4x4, float64, metres) maps source points
into the reference frame: p_ref = R @ p_src + t.

Parameters
----------
source : (N, 3) float32 or float64 array, metres
    The cloud that moves. Any memory layout (C, Fortran, strided slices). It is copied once into
    the library's float32 storage (float64 georeferenced coordinates, e.g. UTM, are stored from an
    origin near the cloud, exactly: docs/io.md); rows with a NaN or infinite coordinate are dropped
    and counted (result.source_non_finite_dropped).
reference : (M, 3) array like `source`, or ReferenceIndex
    The fixed cloud. A ReferenceIndex is built once and reused by any number of registrations,
    also from several threads at once; an array builds one for this call (result.build_ms),
    with the normals or covariances the cost needs.
init : (4, 4) array, None or 'global', default None (identity)
    Initial T_reference_source; must be rigid. 'global': no initial guess; a global estimate
    (FPFH features and RANSAC, verified against the reference; docs/global.md), then the SGD
    registration from it. The result's global_* fields name the winning hypothesis, its score
    and the runner-up's; global_reliable False means no reliable global solution (too few
    points, no structure, an ambiguous scene): do not use the transform. SGD methods only.
settings : Settings, BatchSettings or None, default None
    The base settings: a Settings for the SGD methods (None = Settings()), a BatchSettings for
    the batch methods (None = BatchSettings(), whose cost the method sets).
method : str, default 'sgd'
    The CLI's --method: 'sgd' (SGD-ICP with the settings' cost, point-to-plane by default,
    point-to-point with Settings.paper()), 'sgd-point' / 'sgd-plane' / 'sgd-gicp' (SGD-ICP on
    point-to-point / point-to-plane / plane-to-plane), 'icp' (batch
    point-to-point, closed-form SVD step), 'icp-plane' (batch point-to-plane) or 'gicp' (batch
    plane-to-plane), both Levenberg-Marquardt. All but 'sgd' set the cost (cost= is then an
    error). An unknown name raises InvalidSettingsError.
**overrides
    Keyword settings applied on top of `settings`, named like the CLI's options (the library's
    settings table), each with its default and valid range. The common ones come first; the
    others are better kept together in `settings`, which any number of calls can share
    (settings=sgd_icp.Settings(refine_stages=2, trim=0.8)). A distance given as a number is in
    max_distance_unit ('scaled', the default, or 'm'); a Distance keeps its own unit.
    optimizer= also sets learning_rate to that rule's own step unless learning_rate= is given.
    For the batch methods (any other keyword raises TypeError):
@BATCH@.
    For the SGD methods:
@SGD@.
    With init='global' (an error without it), the global estimate's settings, named like the
    CLI's --global-* options (docs/global.md):
@GLOBAL@.
    See docs/python-settings.md for the settings each one sets.

The GIL is released during the registration (and the KD-tree build), so registrations in
several Python threads run in parallel.

Raises
------
InvalidInputError (ValueError)
    A wrong shape or dtype, no finite points, fewer source points than batch_size, a non-rigid
    init, a ReferenceIndex without the normals or covariances of a batch method's cost (build
    it with ReferenceIndex(points, cost=...); the SGD methods estimate what they use).
InvalidSettingsError (ValueError)
    An invalid setting or method name, or a global_* keyword without init='global'.
TypeError
    An unknown keyword, a keyword of the other solver, or a value of the wrong type.
)doc";

// kRegisterDocTemplate with the keyword lists of both solvers filled in.
std::string register_doc(const py::module_& m) {
  std::string doc = kRegisterDocTemplate;
  const auto fill = [&](const std::string& marker, const std::string& text) {
    doc.replace(doc.find(marker), marker.size(), text);
  };
  fill("@BATCH@", keyword_summary(m, Solver::batch, "    "));
  fill("@SGD@", keyword_summary(m, Solver::sgd, "    "));
  fill("@GLOBAL@", global_keyword_summary("    "));
  return doc;
}

}  // namespace

/// What the reference index that register_clouds builds for an array reference holds, for the
/// same method, settings and overrides.
ReferenceNeeds reference_needs(const Method& m, const py::handle& settings,
                               const py::dict& overrides) {
  // The global keywords do not change the index: checked, then left out.
  py::dict rest = overrides.attr("copy")();
  (void)take_global_keywords(rest, true);
  if (m.solver == Solver::sgd) return needs_of(sgd_settings_of(m, settings, rest), false);
  return needs_of(batch_settings_of(m, settings, rest), true);
}

// register_sweep: the rigid registration (the defaults) from init, then the pose and the velocity
// within the sweep together (align_deskewed), as `sgdicp register --deskew`.
py::dict register_sweep(const py::handle& source, const py::handle& reference,
                        const py::handle& times, const py::object& init) {
  ConvertedCloud src = cloud_from_array(source, "source", NonFinite::keep);
  TimesArray t = times_from_array(times, src.cloud.size());
  src.cloud.times_s = std::move(t.relative_s);
  const double earliest = t.earliest_s;
  const Eigen::Matrix4d T_init =
      init.is_none() ? Eigen::Matrix4d::Identity() : matrix_from_array(init, "init");
  const PointCloud ref = cloud_from_array(reference, "reference", NonFinite::drop).cloud;
  const auto [deskewed, aligned] = [&] {
    const py::gil_scoped_release release;
    ReferenceIndex index = reference_index_for(ref, SgdSettings{});
    prepare_reference(index, CostType::point_to_plane);
    const RegistrationResult rigid = align(src.cloud, index, SgdSettings{}, T_init);
    const DeskewedRegistration d =
        align_deskewed(src.cloud, src.cloud.times_s, index, rigid.T_reference_source);
    return std::pair{d, deskewed_in_reference(src.cloud, src.cloud.times_s, d)};
  }();
  py::dict out;
  out["T_reference_source"] = array_from_matrix(deskewed.T_reference_source);
  out["velocity"] = py::array_t<double>(6, deskewed.velocity.data());
  out["mid_time"] = deskewed.mid_time_s + earliest;
  out["converged"] = deskewed.converged;
  out["iterations"] = deskewed.iterations;
  out["message"] = deskewed.message;
  out["aligned"] = array_from_cloud(PointCloud(aligned));
  return out;
}

void bind_registration(py::module_& m) {
  // The keyword lists come from the settings table; the docstring must outlive the module.
  static const std::string doc = register_doc(m);
  m.def("register", &register_clouds, doc.c_str(), "source"_a, "reference"_a, "init"_a = py::none(),
        "settings"_a = py::none(), "method"_a = "sgd");
  m.def("register_sweep", &register_sweep, "source"_a, "reference"_a, "times"_a,
        "init"_a = py::none(),
        "Registers a sweep measured while the sensor moved (as `sgdicp register --deskew`): "
        "source (N, 3) with each point's time, times (N,) seconds (any origin), to reference "
        "(M, 3), from init (a (4, 4) pose, or None). The pose and the sensor's constant velocity "
        "within the sweep are estimated together (docs/registration.md, Moving sensors). "
        "Returns a dict: T_reference_source (4, 4), the pose at the sweep's middle mid_time "
        "(seconds, in the times' clock); velocity (6,), m/s then rad/s in the sensor's frame; "
        "converged, iterations, message; aligned (N, 3), every source point in input order "
        "deskewed into the reference frame.");
}

}  // namespace sgdicp::python
