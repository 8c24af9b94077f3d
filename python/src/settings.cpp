// Settings classes of sgd_icp (the C++ SgdSettings and BatchSettings with the same names and
// defaults, their parts and enums) with value semantics. Their attributes' docstrings come from
// the library's settings table (settings_docs.cpp), their keyword overrides from keywords.cpp.
#include <string>
#include <type_traits>

#include <pybind11/native_enum.h>

#include "bindings.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/registration/batch_icp.hpp"

namespace sgdicp::python {
namespace {

using namespace pybind11::literals;

// ---- repr and equality

std::string repr(const Distance& d) {
  return std::string(d.unit == Distance::Unit::metres ? "Distance.metres(" : "Distance.scaled(") +
         std::string(py::repr(py::float_(d.value))) + ")";
}

// "Class(attribute=value, ...)" over the properties the class binds, in binding order, so that a
// new setting appears without a second hand-kept field list.
std::string attributes_repr(const py::handle& self) {
  static const py::object property = py::module_::import("builtins").attr("property");
  const py::handle cls = py::type::handle_of(self);
  std::string out = py::str(cls.attr("__name__")).cast<std::string>() + "(";
  bool first = true;
  for (const auto& item : cls.attr("__dict__").attr("items")()) {
    const auto entry = item.cast<py::tuple>();
    if (!py::isinstance(entry[1], property)) continue;
    out += (first ? "" : ", ") + py::str(entry[0]).cast<std::string>() + "=" +
           python_literal(self.attr(entry[0]));
    first = false;
  }
  return out + ")";
}

// The attributes that the library's settings tables describe (settings.hpp) are bound with an
// empty docstring here: document_settings() (settings_docs.cpp) sets each from its table entry
// (help, unit, range, keyword, default), so that the text has one source. The others are written
// here.

// Value semantics for every settings class: ==, repr, copy.copy and copy.deepcopy.
template <typename T>
void def_value_methods(py::class_<T>& c) {
  c.def("__eq__",
        [](const T& a, const py::handle& b) -> py::object {
          if (!py::isinstance<T>(b)) return py::reinterpret_borrow<py::object>(Py_NotImplemented);
          return py::bool_(a == b.cast<const T&>());
        })
      .def("__repr__",
           [](const py::handle& a) {
             if constexpr (std::is_same_v<T, Distance>) return repr(a.cast<const Distance&>());
             return attributes_repr(a);
           })
      .def("__copy__", [](const T& a) { return T(a); })
      .def(
          "__deepcopy__", [](const T& a, const py::handle&) { return T(a); }, "memo"_a);
  c.attr("__hash__") = py::none();  // mutable
}

// An integer attribute whose setter checks the value (ValueError for -1, TypeError for 1.5).
template <typename Class, typename Field>
void def_count(py::class_<Class>& c, const char* name, Field Class::*member, const char* doc) {
  c.def_property(
      name, [member](const Class& s) { return s.*member; },
      [member, name](Class& s, const py::handle& v) {
        s.*member = static_cast<Field>(as_count(v, name));
      },
      doc);
}

template <typename Class>
void def_flag(py::class_<Class>& c, const char* name, bool Class::*member, const char* doc) {
  c.def_property(
      name, [member](const Class& s) { return s.*member; },
      [member, name](Class& s, const py::handle& v) { s.*member = as_bool(v, name); }, doc);
}

// The same for a member of a group (SgdSettings::sampling.batch_size), which Python keeps as a
// flat attribute of the settings class (settings_docs.cpp, python_attribute); `convert` turns the
// Python value into the member's type, naming the attribute in its error.
template <typename Class, typename Group, typename Field, typename Convert>
void def_group_member(py::class_<Class>& c, const char* name, Group Class::*group,
                      Field Group::*member, const char* doc, Convert convert) {
  c.def_property(
      name, [group, member](const Class& s) { return s.*group.*member; },
      [group, member, name, convert](Class& s, const py::handle& v) {
        s.*group.*member = convert(v, name);
      },
      doc);
}

template <typename Class, typename Group, typename Field>
void def_count(py::class_<Class>& c, const char* name, Group Class::*group, Field Group::*member,
               const char* doc) {
  def_group_member(c, name, group, member, doc, [](const py::handle& v, const char* n) {
    return static_cast<Field>(as_count(v, n));
  });
}

template <typename Class, typename Group>
void def_flag(py::class_<Class>& c, const char* name, Group Class::*group, bool Group::*member,
              const char* doc) {
  def_group_member(c, name, group, member, doc,
                   [](const py::handle& v, const char* n) { return as_bool(v, n); });
}

template <typename Class, typename Group>
void def_real(py::class_<Class>& c, const char* name, Group Class::*group, double Group::*member,
              const char* doc) {
  c.def_property(
      name, [group, member](const Class& s) { return s.*group.*member; },
      [group, member](Class& s, double v) { s.*group.*member = v; }, doc);
}

template <typename Class, typename Group, typename Enum>
void def_enum(py::class_<Class>& c, const char* name, Group Class::*group, Enum Group::*member,
              const char* doc) {
  def_group_member(c, name, group, member, doc,
                   [](const py::handle& v, const char* n) { return enum_from_object<Enum>(v, n); });
}

// voxel_size_m and downsample_to, the downsampling group both settings classes have
// (settings.hpp), as flat attributes.
template <typename Class>
void def_voxel_grid(py::class_<Class>& c) {
  c.def_property(
      "voxel_size_m", [](const Class& s) { return s.downsampling.voxel_size_m; },
      [](Class& s, const py::handle& v) {
        s.downsampling.voxel_size_m = as_real(v, "voxel_size_m");
      },
      "");
  def_count(c, "downsample_to", &Class::downsampling, &DownsamplingSettings::downsample_to, "");
}

template <typename Class>
void def_distance(py::class_<Class>& c, const char* name, Distance Class::*member,
                  const char* doc) {
  c.def_property(
      name, [member](const Class& s) { return s.*member; },
      [member, name](Class& s, const py::handle& v) { s.*member = distance_from_object(v, name); },
      doc);
}

template <typename Class, typename Group>
void def_distance(py::class_<Class>& c, const char* name, Group Class::*group,
                  Distance Group::*member, const char* doc) {
  c.def_property(
      name, [group, member](const Class& s) { return s.*group.*member; },
      [group, member, name](Class& s, const py::handle& v) {
        s.*group.*member = distance_from_object(v, name);
      },
      doc);
}

void bind_enums(py::module_& m) {
  // Native Python enums (enum.Enum): the stubs can say so, and they pickle and compare as usual.
  py::native_enum<Distance::Unit>(m, "DistanceUnit", "enum.Enum", "Unit of a Distance.")
      .value("metres", Distance::Unit::metres, "metres")
      .value("scaled", Distance::Unit::scaled,
             "fractions of the largest side of the joint bounding box of both clouds (the "
             "paper's [0, 1] space)")
      .finalize();

  py::native_enum<OptimizerType>(m, "OptimizerType", "enum.Enum", "Step rule of the paper's eq. 3.")
      .value("sgd", OptimizerType::sgd, "fixed step (the paper's vanilla SGD, alpha = 2)")
      .value("momentum", OptimizerType::momentum, "heavy-ball momentum")
      .value("rmsprop", OptimizerType::rmsprop, "RMSProp")
      .value("adam", OptimizerType::adam, "Adam (the paper's Adam-SGD; the default)")
      .value("gauss_newton", OptimizerType::gauss_newton,
             "step pre-conditioned by the averaged mini-batch Gauss-Newton matrix")
      .finalize();

  py::native_enum<ScalingOrigin>(m, "ScalingOrigin", "enum.Enum",
                                 "Origin of the scaled space, which is also the pivot of the "
                                 "rotation.")
      .value("lower_corner", ScalingOrigin::lower_corner,
             "the paper: the lower corner of the joint box, points in [0, 1]")
      .value("center", ScalingOrigin::center,
             "the centre of the joint box, points in [-0.5, 0.5] (the default)")
      .finalize();

  py::native_enum<CostType>(m, "CostType", "enum.Enum",
                            "Cost of a pair (source point moved to q, reference point r).")
      .value("point_to_point", CostType::point_to_point,
             "|q - r|^2, the paper's (Besl-McKay); the default")
      .value("point_to_plane", CostType::point_to_plane,
             "(n . (q - r))^2 with the reference normal n (Chen-Medioni)")
      .value("plane_to_plane", CostType::plane_to_plane,
             "e^T (C_r + R C_s R^T)^-1 e with the plane covariances (GICP, Segal et al.)")
      .finalize();

  py::native_enum<KernelType>(m, "KernelType", "enum.Enum",
                              "Robust kernel on each pair's squared residual.")
      .value("none", KernelType::none, "no kernel (least squares); the default")
      .value("huber", KernelType::huber, "Huber")
      .value("cauchy", KernelType::cauchy, "Cauchy")
      .value("geman_mcclure", KernelType::geman_mcclure, "Geman-McClure")
      .value("welsch", KernelType::welsch, "Welsch")
      .finalize();

  py::native_enum<UncertaintyType>(m, "UncertaintyType", "enum.Enum",
                                   "Pose uncertainty of a registration (docs/uncertainty.md).")
      .value("none", UncertaintyType::none, "no covariance; the default")
      .value("laplace", UncertaintyType::laplace,
             "inverse Gauss-Newton matrix at the optimum times the residual variance")
      .value("sgld", UncertaintyType::sgld,
             "Bayesian ICP: pre-conditioned stochastic gradient Langevin samples")
      .value("svgd", UncertaintyType::svgd,
             "Stein ICP: Stein variational gradient descent particles, clustered into modes")
      .finalize();
}

void bind_uncertainty(py::module_& m) {
  py::class_<UncertaintySettings> u(
      m, "UncertaintySettings",
      "Pose uncertainty of the result and its sampler and calibration (Settings.uncertainty; "
      "docs/uncertainty.md).");
  u.def(py::init<>());
  u.def_property(
      "method", [](const UncertaintySettings& s) { return s.method; },
      [](UncertaintySettings& s, const py::handle& v) {
        s.method = enum_from_object<UncertaintyType>(v, "method");
      },
      "");
  def_count(u, "samples", &UncertaintySettings::samples, "");
  def_count(u, "burn_in", &UncertaintySettings::burn_in, "");
  def_count(u, "thinning", &UncertaintySettings::thinning, "");
  u.def_readwrite("step", &UncertaintySettings::step, "");
  def_count(u, "particles", &UncertaintySettings::particles, "");
  def_count(u, "svgd_iterations", &UncertaintySettings::svgd_iterations, "");
  u.def_readwrite("svgd_step", &UncertaintySettings::svgd_step, "");
  u.def_readwrite("svgd_spread", &UncertaintySettings::svgd_spread, "");
  def_flag(u, "temper", &UncertaintySettings::temper, "");
  def_distance(u, "block_size", &UncertaintySettings::block_size, "");
  u.def_readwrite("softening", &UncertaintySettings::softening, "");
  def_value_methods(u);
}

void bind_distance(py::module_& m) {
  py::class_<Distance> distance(
      m, "Distance",
      "A length with its unit: metres, or scaled units (1 = the largest side of the joint "
      "bounding box of both clouds, the paper's [0, 1] space).\n\n"
      "Make one with Distance.metres(v) or Distance.scaled(v).");
  distance
      .def(py::init([](const py::handle& value, const py::handle& unit) {
             return Distance{as_real(value, "value"),
                             enum_from_object<Distance::Unit>(unit, "unit")};
           }),
           "value"_a, "unit"_a = "scaled",
           "A distance of `value` in `unit` ('m', 'scaled' or a DistanceUnit; default "
           "'scaled').")
      .def_static(
          "metres", [](double v) { return Distance::metres(v); }, "value"_a,
          "A distance in metres.")
      .def_static(
          "scaled", [](double v) { return Distance::scaled(v); }, "value"_a,
          "A distance in scaled units (fraction of the largest side of the joint box).")
      .def_readwrite("value", &Distance::value, "The length, in `unit`.")
      .def_property(
          "unit", [](const Distance& d) { return d.unit; },
          [](Distance& d, const py::handle& v) {
            d.unit = enum_from_object<Distance::Unit>(v, "unit");
          },
          "DistanceUnit.metres or DistanceUnit.scaled.")
      .def("to_scaled", &Distance::to_scaled, "metres_per_unit"_a,
           "The value in scaled units, given the metres per scaled unit "
           "(RegistrationResult.scale_m).");
  def_value_methods(distance);
}

void bind_optimizer(py::module_& m) {
  py::class_<OptimizerSettings> optimizer(
      m, "OptimizerSettings", "Step rule of eq. 3 and its parameters (Settings.optimizer).");
  optimizer.def(py::init<>(), "The C++ defaults: fixed step (sgd) with learning rate 2.")
      .def_property(
          "type", [](const OptimizerSettings& o) { return o.type; },
          [](OptimizerSettings& o, const py::handle& v) {
            o.type = enum_from_object<OptimizerType>(v, "type");
          },
          "")
      .def_readwrite("learning_rate", &OptimizerSettings::learning_rate, "")
      .def_readwrite("damping", &OptimizerSettings::damping, "")
      .def("validate", &OptimizerSettings::validate,
           "Raises InvalidSettingsError (a ValueError) naming the first invalid value.");
  def_value_methods(optimizer);
}

void bind_convergence(py::module_& m) {
  py::class_<ConvergenceSettings> convergence(
      m, "ConvergenceSettings",
      "When a stage is stationary: Hotelling's T^2 test on the window's mini-batch gradients and "
      "a path-efficiency guard, or an absolute tolerance on every step (Settings.convergence).");
  convergence.def(py::init<>());
  def_count(convergence, "window", &ConvergenceSettings::window, "");
  convergence.def_readwrite("chi2", &ConvergenceSettings::chi2, "")
      .def_readwrite("max_path_efficiency", &ConvergenceSettings::max_path_efficiency, "")
      .def_readwrite("translation_tolerance", &ConvergenceSettings::translation_tolerance, "")
      .def_readwrite("rotation_tolerance", &ConvergenceSettings::rotation_tolerance, "");
  def_value_methods(convergence);

  py::class_<RefinementSettings> refinement(
      m, "RefinementSettings",
      "Refinement stages after the paper's coarse phase: each shrinks d_max to the data and "
      "decays the step (Settings.refinement).");
  refinement.def(py::init<>());
  def_count(refinement, "stages", &RefinementSettings::stages, "");
  refinement.def_readwrite("step_decay", &RefinementSettings::step_decay, "")
      .def_readwrite("distance_factor", &RefinementSettings::distance_factor, "");
  def_flag(refinement, "gauss_newton", &RefinementSettings::gauss_newton, "");
  def_distance(refinement, "min_distance", &RefinementSettings::min_distance, "");
  refinement.def_readwrite("settle_tolerance", &RefinementSettings::settle_tolerance, "");
  def_value_methods(refinement);
}

void bind_neighborhood(py::module_& m) {
  py::class_<NeighborhoodSettings> neighborhood(
      m, "NeighborhoodSettings",
      "k-nearest neighbourhoods for the normals and covariances of the plane costs "
      "(Settings.neighborhood).");
  neighborhood.def(py::init<>());
  def_count(neighborhood, "k", &NeighborhoodSettings::k, "");
  def_count(neighborhood, "flat_k", &NeighborhoodSettings::flat_k,
            "Neighbours of a point whose nearest ones already lie flat (surface variation at "
            "most flatness): those alone give its normal and covariance; 0 = always k. Settings: "
            "10, BatchSettings: 0 (docs/preprocessing.md).");
  def_count(neighborhood, "num_threads", &NeighborhoodSettings::num_threads,
            "Worker threads of the estimation; 0 = all cores (the results are the same for any "
            "count). Default 0.");
  def_flag(neighborhood, "regularize", &NeighborhoodSettings::regularize,
           "Replace each covariance by the GICP plane model (unitless). Default True.");
  neighborhood
      .def_readwrite("flatness", &NeighborhoodSettings::flatness,
                     "The largest surface variation of a flat neighbourhood, in [0, 1/3]. "
                     "Default 0.05.")
      .def_readwrite("epsilon", &NeighborhoodSettings::epsilon,
                     "Variance along the normal in the plane model, relative to 1 in the plane, "
                     "in (0, 1]. Default 1e-3.")
      .def_property(
          "viewpoint",
          [](const NeighborhoodSettings& n) {
            py::array_t<double> v(3);
            for (py::ssize_t i = 0; i < 3; ++i) v.mutable_at(i) = n.viewpoint[i];
            return v;
          },
          [](NeighborhoodSettings& n, const py::handle& value) {
            const py::array_t<double> v =
                py::module_::import("numpy").attr("asarray")(value, "dtype"_a = "float64");
            if (v.ndim() != 1 || v.shape(0) != 3) {
              throw InvalidSettingsError("viewpoint must be 3 numbers (x, y, z, metres)");
            }
            for (py::ssize_t i = 0; i < 3; ++i) n.viewpoint[i] = static_cast<float>(v.at(i));
          },
          "Normals are flipped to face this point, (3,) array, metres. Default (0, 0, 0).");
  def_value_methods(neighborhood);
}

void bind_sgd_settings(py::module_& m) {
  py::class_<SgdSettings> settings(
      m, "Settings",
      "Every setting of a registration: the C++ sgdicp::SgdSettings, same names and defaults.\n\n"
      "Settings(**overrides) is the measured default (Adam 0.01, refinement) with the flat "
      "keyword overrides of register() applied; Settings.paper() is the paper's. Attributes can "
      "be changed in place, nested ones too (s.optimizer.learning_rate = 0.02).");
  settings
      .def(py::init([](const py::kwargs& overrides) {
             return with_overrides(SgdSettings{}, overrides);
           }),
           "The default settings with the flat keyword overrides applied (see register()).")
      .def_static(
          "paper",
          [](const py::handle& optimizer, const py::kwargs& overrides) {
            return with_overrides(
                SgdSettings::paper(enum_from_object<OptimizerType>(optimizer, "optimizer")),
                overrides);
          },
          "optimizer"_a = "sgd",
          "The paper's settings: m = 160, d_max = 0.5 scaled, fixed step alpha = 2 ('sgd') or "
          "Adam 0.01 ('adam'), no refinement, the last iterate, the lower-corner scaling origin; "
          "then the keyword overrides.")
      .def(
          "replace",
          [](const SgdSettings& s, const py::kwargs& overrides) {
            return with_overrides(s, overrides);
          },
          "A copy with the flat keyword overrides of register() applied.")
      .def(
          "validate", [](const SgdSettings& s) { s.validate(); },
          "Raises InvalidSettingsError (a ValueError) naming the first invalid setting.");
  // The groups sampling, pairing, scaling, evaluation and downsampling are flat attributes here,
  // as they are flat keywords.
  def_count(settings, "batch_size", &SgdSettings::sampling, &SamplingSettings::batch_size, "");
  def_flag(settings, "adapt_small_sources", &SgdSettings::adapt_small_sources,
           "The small-source rules (Settings.paper(): False): a capped mini-batch and "
           "Gauss-Newton coarse steps for sources of fewer than batch_size x window / 2 points.");
  def_distance(settings, "max_correspondence_distance", &SgdSettings::pairing,
               &PairingSettings::max_correspondence_distance, "");
  settings
      .def_readwrite("optimizer", &SgdSettings::optimizer,
                     "OptimizerSettings. Default Adam with learning rate 0.01.")
      .def_readwrite("convergence", &SgdSettings::convergence, "ConvergenceSettings.")
      .def_readwrite("refinement", &SgdSettings::refinement, "RefinementSettings.")
      .def_readwrite("uncertainty", &SgdSettings::uncertainty,
                     "UncertaintySettings. Default: no uncertainty.")
      .def_property(
          "cost", [](const SgdSettings& s) { return s.cost; },
          [](SgdSettings& s, const py::handle& v) { s.cost = cost_from_object(v, "cost"); }, "")
      .def_property(
          "coarse_cost", [](const SgdSettings& s) { return s.coarse_cost; },
          [](SgdSettings& s, const py::handle& v) {
            s.coarse_cost = cost_from_object(v, "coarse_cost");
          },
          "");
  def_enum(settings, "kernel", &SgdSettings::pairing, &PairingSettings::kernel, "");
  def_enum(settings, "scaling_origin", &SgdSettings::scaling, &ScalingSettings::origin, "");
  def_distance(settings, "kernel_scale", &SgdSettings::pairing, &PairingSettings::kernel_scale, "");
  def_real(settings, "trim_ratio", &SgdSettings::pairing, &PairingSettings::trim_ratio, "");
  settings.def_readwrite(
      "neighborhood", &SgdSettings::neighborhood,
      "NeighborhoodSettings for the normals and covariances of the plane costs.");
  def_count(settings, "max_iterations", &SgdSettings::max_iterations, "");
  def_count(settings, "seed", &SgdSettings::sampling, &SamplingSettings::seed, "");
  def_flag(settings, "average_iterates", &SgdSettings::average_iterates, "");
  def_count(settings, "evaluation_points", &SgdSettings::evaluation,
            &EvaluationSettings::evaluation_points, "");
  def_flag(settings, "record_trace", &SgdSettings::record_trace, "");
  def_flag(settings, "robust_scaling", &SgdSettings::scaling, &ScalingSettings::robust,
           "Scale from the bulk of each cloud, not hostage to a few far points "
           "(Settings.paper(): False, the bounding box of every point). Default True.");
  def_count(settings, "num_threads", &SgdSettings::num_threads, "");
  def_voxel_grid(settings);
  def_value_methods(settings);
}

void bind_batch_settings(py::module_& m) {
  py::class_<BatchSettings> batch(
      m, "BatchSettings",
      "Settings of the batch methods (register(method='icp' | 'icp-plane' | 'gicp')): the C++ "
      "sgdicp::BatchSettings, same names and defaults. Every iteration pairs all source points "
      "with their nearest reference point within d_max, then takes the closed-form SVD step "
      "(point-to-point) or one damped Gauss-Newton step (the plane costs).\n\n"
      "BatchSettings(**overrides) is the default (point-to-point) with the batch keyword "
      "overrides of register() applied (max_distance, max_distance_unit, max_iterations, kernel, "
      "kernel_scale, trim, neighbors, damping, translation_tolerance, rotation_tolerance, "
      "evaluation_points, cost).");
  batch
      .def(py::init([](const py::kwargs& overrides) {
             return with_batch_overrides(BatchSettings{}, overrides, "");
           }),
           "The default settings (point-to-point ICP) with the batch keyword overrides applied.")
      .def_static(
          "icp",
          [](const py::kwargs& overrides) {
            return with_batch_overrides(BatchSettings::icp(), overrides, "");
          },
          "Point-to-point ICP (Besl-McKay; closed-form SVD step), then the keyword overrides.")
      .def_static(
          "icp_plane",
          [](const py::kwargs& overrides) {
            return with_batch_overrides(BatchSettings::icp_plane(), overrides, "");
          },
          "Point-to-plane ICP (Chen-Medioni; Levenberg-Marquardt step), then the keyword "
          "overrides.")
      .def_static(
          "gicp",
          [](const py::kwargs& overrides) {
            return with_batch_overrides(BatchSettings::gicp(), overrides, "");
          },
          "Plane-to-plane GICP (Segal et al.; Levenberg-Marquardt step), then the keyword "
          "overrides.")
      .def(
          "replace",
          [](const BatchSettings& s, const py::kwargs& overrides) {
            return with_batch_overrides(s, overrides, "");
          },
          "A copy with the batch keyword overrides applied.")
      .def(
          "validate", [](const BatchSettings& s) { s.validate(); },
          "Raises InvalidSettingsError (a ValueError) naming the first invalid setting.")
      .def_property(
          "cost", [](const BatchSettings& s) { return s.cost; },
          [](BatchSettings& s, const py::handle& v) { s.cost = cost_from_object(v, "cost"); }, "");
  def_distance(batch, "max_correspondence_distance", &BatchSettings::pairing,
               &PairingSettings::max_correspondence_distance, "");
  def_enum(batch, "kernel", &BatchSettings::pairing, &PairingSettings::kernel, "");
  def_distance(batch, "kernel_scale", &BatchSettings::pairing, &PairingSettings::kernel_scale, "");
  def_real(batch, "trim_ratio", &BatchSettings::pairing, &PairingSettings::trim_ratio, "");
  def_count(batch, "max_iterations", &BatchSettings::max_iterations, "");
  batch.def_readwrite("translation_tolerance", &BatchSettings::translation_tolerance, "")
      .def_readwrite("rotation_tolerance", &BatchSettings::rotation_tolerance, "")
      .def_readwrite("initial_damping", &BatchSettings::initial_damping, "")
      .def_readwrite("neighborhood", &BatchSettings::neighborhood,
                     "NeighborhoodSettings for the normals and covariances of the plane costs.");
  def_count(batch, "evaluation_points", &BatchSettings::evaluation,
            &EvaluationSettings::evaluation_points, "");
  def_flag(batch, "robust_scaling", &BatchSettings::robust_scaling,
           "Scale from the bulk of each cloud, not hostage to a few far points. Default True.");
  def_count(batch, "num_threads", &BatchSettings::num_threads, "");
  def_voxel_grid(batch);
  def_flag(batch, "record_trace", &BatchSettings::record_trace, "");
  def_value_methods(batch);
}

}  // namespace

void bind_settings(py::module_& m) {
  bind_enums(m);
  bind_distance(m);
  bind_optimizer(m);
  bind_convergence(m);
  bind_neighborhood(m);
  bind_uncertainty(m);
  bind_sgd_settings(m);
  bind_batch_settings(m);
  document_settings(m);
  bind_settings_keywords(m);
}

}  // namespace sgdicp::python
