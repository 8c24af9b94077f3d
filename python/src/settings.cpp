// Settings classes of sgd_icp (the C++ SgdSettings with the same names and defaults) and the flat
// keyword overrides shared by Settings(...), Settings.paper(...), Settings.replace(...) and
// register(...).
#include <algorithm>
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include <pybind11/native_enum.h>

#include "bindings.hpp"
#include "sgdicp/batch_icp.hpp"
#include "sgdicp/error.hpp"

namespace sgdicp::python {
namespace {

using namespace pybind11::literals;

// ---- enums from Python values (the enum itself or its name)

// The enum value if `value` is an instance of the bound enum E.
template <typename E>
std::optional<E> as_enum(const py::handle& value) {
  py::detail::make_caster<E> caster;
  if (!caster.load(value, /*convert=*/false)) return std::nullopt;
  return py::detail::cast_op<E>(caster);
}

OptimizerType optimizer_from_object(const py::handle& value, std::string_view name) {
  if (const auto e = as_enum<OptimizerType>(value)) return *e;
  if (py::isinstance<py::str>(value)) {
    std::string text = value.cast<std::string>();
    std::replace(text.begin(), text.end(), '_', '-');  // "gauss_newton" as well as "gauss-newton"
    return optimizer_from_string(text);
  }
  throw py::type_error(std::string(name) + " must be an OptimizerType or one of 'sgd', " +
                       "'momentum', 'rmsprop', 'adam', 'gauss-newton', got " + type_name(value));
}

ScalingOrigin scaling_origin_from_object(const py::handle& value, std::string_view name) {
  if (const auto e = as_enum<ScalingOrigin>(value)) return *e;
  if (py::isinstance<py::str>(value)) {
    const std::string text = value.cast<std::string>();
    if (text == "center") return ScalingOrigin::center;
    if (text == "lower_corner" || text == "corner") return ScalingOrigin::lower_corner;
    throw InvalidSettingsError(std::string(name) + ": unknown scaling origin '" + text +
                               "' (expected 'center' or 'lower_corner')");
  }
  throw py::type_error(std::string(name) +
                       " must be a ScalingOrigin, 'center' or 'lower_corner', got " +
                       type_name(value));
}

KernelType kernel_from_object(const py::handle& value, std::string_view name) {
  if (const auto e = as_enum<KernelType>(value)) return *e;
  if (py::isinstance<py::str>(value)) {
    std::string text = value.cast<std::string>();
    std::replace(text.begin(), text.end(), '_', '-');
    return kernel_from_string(text);
  }
  throw py::type_error(std::string(name) + " must be a KernelType or one of 'none', 'huber', " +
                       "'cauchy', 'geman-mcclure', 'welsch', got " + type_name(value));
}

Distance::Unit unit_from_object(const py::handle& value, std::string_view name) {
  if (const auto e = as_enum<Distance::Unit>(value)) return *e;
  if (py::isinstance<py::str>(value)) {
    const std::string text = value.cast<std::string>();
    if (text == "scaled") return Distance::Unit::scaled;
    if (text == "m" || text == "metres" || text == "meters") return Distance::Unit::metres;
    throw InvalidSettingsError(std::string(name) + ": unknown unit '" + text +
                               "' (expected 'm' or 'scaled')");
  }
  throw py::type_error(std::string(name) + " must be a DistanceUnit, 'm' or 'scaled', got " +
                       type_name(value));
}

Distance distance_from_object(const py::handle& value, std::string_view name) {
  if (py::isinstance<Distance>(value)) return value.cast<Distance>();
  throw py::type_error(std::string(name) +
                       " must be a Distance, e.g. Distance.metres(1.0) or Distance.scaled(0.5), "
                       "got " +
                       type_name(value));
}

// The step size each rule is usually run with; `optimizer=` in the overrides sets it unless
// `learning_rate=` is given too. The same table as the CLI's --optimizer (apps/cli_settings.hpp).
double usual_learning_rate(OptimizerType type, double momentum) {
  switch (type) {
    case OptimizerType::sgd:
      return 2.0;
    case OptimizerType::momentum:
      return 2.0 * (1.0 - momentum);
    case OptimizerType::gauss_newton:
      return 1.0;
    case OptimizerType::adam:
    case OptimizerType::rmsprop:
      break;
  }
  return SgdSettings{}.optimizer.learning_rate;
}

// ---- the flat keyword overrides: the CLI's option names with '_' for '-'

using Apply = void (*)(SgdSettings&, const py::handle&, Distance::Unit);

struct Keyword {
  std::string_view name;
  Apply apply;
};

// A distance given as a number takes the unit of max_distance_unit; a Distance keeps its own.
Distance distance_or_number(const py::handle& value, Distance::Unit unit, std::string_view name) {
  if (py::isinstance<Distance>(value)) return value.cast<Distance>();
  return Distance{as_real(value, name), unit};
}

// "optimizer" and "max_distance_unit" are handled before these (they affect others).
constexpr std::array kKeywords{
    Keyword{"batch_size", [](SgdSettings& s, const py::handle& v,
                             Distance::Unit) { s.batch_size = as_count(v, "batch_size"); }},
    Keyword{"max_distance",
            [](SgdSettings& s, const py::handle& v, Distance::Unit u) {
              s.max_correspondence_distance = distance_or_number(v, u, "max_distance");
            }},
    Keyword{"max_iterations",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.max_iterations = as_count(v, "max_iterations");
            }},
    Keyword{"seed", [](SgdSettings& s, const py::handle& v,
                       Distance::Unit) { s.seed = as_count(v, "seed"); }},
    Keyword{"learning_rate",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.optimizer.learning_rate = as_real(v, "learning_rate");
            }},
    Keyword{"momentum", [](SgdSettings& s, const py::handle& v,
                           Distance::Unit) { s.optimizer.momentum = as_real(v, "momentum"); }},
    Keyword{"beta1", [](SgdSettings& s, const py::handle& v,
                        Distance::Unit) { s.optimizer.beta1 = as_real(v, "beta1"); }},
    Keyword{"beta2", [](SgdSettings& s, const py::handle& v,
                        Distance::Unit) { s.optimizer.beta2 = as_real(v, "beta2"); }},
    Keyword{"rms_decay", [](SgdSettings& s, const py::handle& v,
                            Distance::Unit) { s.optimizer.rms_decay = as_real(v, "rms_decay"); }},
    Keyword{"epsilon", [](SgdSettings& s, const py::handle& v,
                          Distance::Unit) { s.optimizer.epsilon = as_real(v, "epsilon"); }},
    Keyword{"hessian_decay",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.optimizer.hessian_decay = as_real(v, "hessian_decay");
            }},
    Keyword{"damping", [](SgdSettings& s, const py::handle& v,
                          Distance::Unit) { s.optimizer.damping = as_real(v, "damping"); }},
    Keyword{"window", [](SgdSettings& s, const py::handle& v,
                         Distance::Unit) { s.convergence.window = as_count(v, "window"); }},
    Keyword{"chi2", [](SgdSettings& s, const py::handle& v,
                       Distance::Unit) { s.convergence.chi2 = as_real(v, "chi2"); }},
    Keyword{"path_efficiency",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.convergence.max_path_efficiency = as_real(v, "path_efficiency");
            }},
    Keyword{"translation_tolerance",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.convergence.translation_tolerance = as_real(v, "translation_tolerance");
            }},
    Keyword{"rotation_tolerance",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.convergence.rotation_tolerance = as_real(v, "rotation_tolerance");
            }},
    Keyword{"refine_stages",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.refinement.stages = as_count(v, "refine_stages");
            }},
    Keyword{"step_decay",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.refinement.step_decay = as_real(v, "step_decay");
            }},
    Keyword{"distance_factor",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.refinement.distance_factor = as_real(v, "distance_factor");
            }},
    Keyword{"min_distance",
            [](SgdSettings& s, const py::handle& v, Distance::Unit u) {
              s.refinement.min_distance = distance_or_number(v, u, "min_distance");
            }},
    Keyword{"cost", [](SgdSettings& s, const py::handle& v,
                       Distance::Unit) { s.cost = cost_from_object(v, "cost"); }},
    Keyword{"kernel", [](SgdSettings& s, const py::handle& v,
                         Distance::Unit) { s.kernel = kernel_from_object(v, "kernel"); }},
    Keyword{"kernel_scale",
            [](SgdSettings& s, const py::handle& v, Distance::Unit u) {
              s.kernel_scale = distance_or_number(v, u, "kernel_scale");
            }},
    Keyword{"trim", [](SgdSettings& s, const py::handle& v,
                       Distance::Unit) { s.trim_ratio = as_real(v, "trim"); }},
    Keyword{"neighbors", [](SgdSettings& s, const py::handle& v,
                            Distance::Unit) { s.neighborhood.k = as_count(v, "neighbors"); }},
    Keyword{"check_degeneracy",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.check_degeneracy = as_bool(v, "check_degeneracy");
            }},
    Keyword{"average", [](SgdSettings& s, const py::handle& v,
                          Distance::Unit) { s.average_iterates = as_bool(v, "average"); }},
    Keyword{"scaling_origin",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.scaling_origin = scaling_origin_from_object(v, "scaling_origin");
            }},
    Keyword{"evaluation_points",
            [](SgdSettings& s, const py::handle& v, Distance::Unit) {
              s.evaluation_points = as_count(v, "evaluation_points");
            }},
    Keyword{"record_trace", [](SgdSettings& s, const py::handle& v,
                               Distance::Unit) { s.record_trace = as_bool(v, "record_trace"); }},
};

// Names a reader of the Settings attributes may try, and the keyword that means it.
constexpr std::array<std::pair<std::string_view, std::string_view>, 13> kSuggestions{{
    {"max_correspondence_distance", "max_distance"},
    {"max_path_efficiency", "path_efficiency"},
    {"average_iterates", "average"},
    {"stages", "refine_stages"},
    {"refinement_stages", "refine_stages"},
    {"type", "optimizer"},
    {"optimizer_type", "optimizer"},
    {"lr", "learning_rate"},
    {"unit", "max_distance_unit"},
    {"trim_ratio", "trim"},
    {"k", "neighbors"},
    {"neighborhood", "neighbors"},
    {"method", "cost"},
}};

std::string keyword_list() {
  std::string list = "optimizer, max_distance_unit";
  for (const auto& k : kKeywords) list += ", " + std::string(k.name);
  return list;
}

[[noreturn]] void unknown_keyword(const std::string& name) {
  std::string message = "unknown setting '" + name + "'";
  for (const auto& [alias, keyword] : kSuggestions) {
    if (name == alias) message += " (did you mean '" + std::string(keyword) + "'?)";
  }
  throw py::type_error(message + "; the keyword settings are: " + keyword_list());
}

// ---- the keyword overrides of the batch methods (BatchSettings): the CLI's options that apply
// to them (apps/cli_settings.hpp, make_method), plus `cost` for BatchSettings(...) itself

using BatchApply = void (*)(BatchSettings&, const py::handle&, Distance::Unit);

struct BatchKeyword {
  std::string_view name;
  BatchApply apply;
};

constexpr std::array kBatchKeywords{
    BatchKeyword{"max_distance",
                 [](BatchSettings& s, const py::handle& v, Distance::Unit u) {
                   s.max_correspondence_distance = distance_or_number(v, u, "max_distance");
                 }},
    BatchKeyword{"max_iterations",
                 [](BatchSettings& s, const py::handle& v, Distance::Unit) {
                   s.max_iterations = as_count(v, "max_iterations");
                 }},
    BatchKeyword{"kernel", [](BatchSettings& s, const py::handle& v,
                              Distance::Unit) { s.kernel = kernel_from_object(v, "kernel"); }},
    BatchKeyword{"kernel_scale",
                 [](BatchSettings& s, const py::handle& v, Distance::Unit u) {
                   s.kernel_scale = distance_or_number(v, u, "kernel_scale");
                 }},
    BatchKeyword{"trim", [](BatchSettings& s, const py::handle& v,
                            Distance::Unit) { s.trim_ratio = as_real(v, "trim"); }},
    BatchKeyword{"neighbors", [](BatchSettings& s, const py::handle& v,
                                 Distance::Unit) { s.neighborhood.k = as_count(v, "neighbors"); }},
    BatchKeyword{"damping", [](BatchSettings& s, const py::handle& v,
                               Distance::Unit) { s.initial_damping = as_real(v, "damping"); }},
    BatchKeyword{"translation_tolerance",
                 [](BatchSettings& s, const py::handle& v, Distance::Unit) {
                   s.translation_tolerance = as_real(v, "translation_tolerance");
                 }},
    BatchKeyword{"rotation_tolerance",
                 [](BatchSettings& s, const py::handle& v, Distance::Unit) {
                   s.rotation_tolerance = as_real(v, "rotation_tolerance");
                 }},
    BatchKeyword{"evaluation_points",
                 [](BatchSettings& s, const py::handle& v, Distance::Unit) {
                   s.evaluation_points = as_count(v, "evaluation_points");
                 }},
    BatchKeyword{"check_degeneracy",
                 [](BatchSettings& s, const py::handle& v, Distance::Unit) {
                   s.check_degeneracy = as_bool(v, "check_degeneracy");
                 }},
    BatchKeyword{"record_trace",
                 [](BatchSettings& s, const py::handle& v, Distance::Unit) {
                   s.record_trace = as_bool(v, "record_trace");
                 }},
    BatchKeyword{"cost", [](BatchSettings& s, const py::handle& v,
                            Distance::Unit) { s.cost = cost_from_object(v, "cost"); }},
};

std::string batch_keyword_list() {
  std::string list = "max_distance_unit";
  for (const auto& k : kBatchKeywords) list += ", " + std::string(k.name);
  return list;
}

// ---- repr and equality

std::string repr(const Distance& d) {
  return std::string(d.unit == Distance::Unit::metres ? "Distance.metres(" : "Distance.scaled(") +
         std::string(py::repr(py::float_(d.value))) + ")";
}

std::string optimizer_name(OptimizerType t) {
  return t == OptimizerType::gauss_newton ? "gauss_newton" : std::string(to_string(t));
}

std::string repr(const OptimizerSettings& o) {
  return py::str(
             "OptimizerSettings(type=OptimizerType.{}, learning_rate={!r}, momentum={!r}, "
             "beta1={!r}, beta2={!r}, rms_decay={!r}, epsilon={!r}, hessian_decay={!r}, "
             "damping={!r})")
      .format(optimizer_name(o.type), o.learning_rate, o.momentum, o.beta1, o.beta2, o.rms_decay,
              o.epsilon, o.hessian_decay, o.damping);
}

std::string repr(const ConvergenceSettings& c) {
  return py::str(
             "ConvergenceSettings(window={!r}, chi2={!r}, max_path_efficiency={!r}, "
             "translation_tolerance={!r}, rotation_tolerance={!r})")
      .format(c.window, c.chi2, c.max_path_efficiency, c.translation_tolerance,
              c.rotation_tolerance);
}

std::string repr(const RefinementSettings& r) {
  return py::str(
             "RefinementSettings(stages={!r}, step_decay={!r}, distance_factor={!r}, "
             "min_distance={})")
      .format(r.stages, r.step_decay, r.distance_factor, repr(r.min_distance));
}

std::string repr(const NeighborhoodSettings& n) {
  return py::str(
             "NeighborhoodSettings(k={!r}, num_threads={!r}, regularize={!r}, epsilon={!r}, "
             "viewpoint=({!r}, {!r}, {!r}))")
      .format(n.k, n.num_threads, n.regularize, n.epsilon, n.viewpoint.x(), n.viewpoint.y(),
              n.viewpoint.z());
}

std::string cost_name(CostType t) {
  std::string name(to_string(t));
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

std::string kernel_name(KernelType t) {
  std::string name(to_string(t));
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

std::string repr(const SgdSettings& s) {
  return py::str(
             "Settings(batch_size={!r}, max_correspondence_distance={}, optimizer={}, "
             "convergence={}, refinement={}, cost=CostType.{}, kernel=KernelType.{}, "
             "kernel_scale={}, trim_ratio={!r}, neighborhood={}, scaling_origin=ScalingOrigin.{}, "
             "max_iterations={!r}, seed={!r}, average_iterates={!r}, evaluation_points={!r}, "
             "record_trace={!r}, check_degeneracy={!r})")
      .format(s.batch_size, repr(s.max_correspondence_distance), repr(s.optimizer),
              repr(s.convergence), repr(s.refinement), cost_name(s.cost), kernel_name(s.kernel),
              repr(s.kernel_scale), s.trim_ratio, repr(s.neighborhood),
              s.scaling_origin == ScalingOrigin::center ? "center" : "lower_corner",
              s.max_iterations, s.seed, s.average_iterates, s.evaluation_points, s.record_trace,
              s.check_degeneracy);
}

bool same(const Distance& a, const Distance& b) {
  return a.value == b.value && a.unit == b.unit;
}
bool same(const OptimizerSettings& a, const OptimizerSettings& b) {
  return a.type == b.type && a.learning_rate == b.learning_rate && a.momentum == b.momentum &&
         a.beta1 == b.beta1 && a.beta2 == b.beta2 && a.rms_decay == b.rms_decay &&
         a.epsilon == b.epsilon && a.hessian_decay == b.hessian_decay && a.damping == b.damping;
}
bool same(const ConvergenceSettings& a, const ConvergenceSettings& b) {
  return a.window == b.window && a.chi2 == b.chi2 &&
         a.max_path_efficiency == b.max_path_efficiency &&
         a.translation_tolerance == b.translation_tolerance &&
         a.rotation_tolerance == b.rotation_tolerance;
}
bool same(const RefinementSettings& a, const RefinementSettings& b) {
  return a.stages == b.stages && a.step_decay == b.step_decay &&
         a.distance_factor == b.distance_factor && same(a.min_distance, b.min_distance);
}
bool same(const NeighborhoodSettings& a, const NeighborhoodSettings& b) {
  return a.k == b.k && a.num_threads == b.num_threads && a.regularize == b.regularize &&
         a.epsilon == b.epsilon && a.viewpoint == b.viewpoint;
}
bool same(const SgdSettings& a, const SgdSettings& b) {
  return a.batch_size == b.batch_size &&
         same(a.max_correspondence_distance, b.max_correspondence_distance) &&
         same(a.optimizer, b.optimizer) && same(a.convergence, b.convergence) &&
         same(a.refinement, b.refinement) && a.cost == b.cost && a.kernel == b.kernel &&
         same(a.kernel_scale, b.kernel_scale) && a.trim_ratio == b.trim_ratio &&
         same(a.neighborhood, b.neighborhood) && a.scaling_origin == b.scaling_origin &&
         a.max_iterations == b.max_iterations && a.seed == b.seed &&
         a.average_iterates == b.average_iterates && a.evaluation_points == b.evaluation_points &&
         a.record_trace == b.record_trace && a.check_degeneracy == b.check_degeneracy;
}

std::string repr(const BatchSettings& s) {
  return py::str(
             "BatchSettings(cost=CostType.{}, max_correspondence_distance={}, "
             "kernel=KernelType.{}, kernel_scale={}, trim_ratio={!r}, max_iterations={!r}, "
             "translation_tolerance={!r}, rotation_tolerance={!r}, initial_damping={!r}, "
             "neighborhood={}, evaluation_points={!r}, check_degeneracy={!r}, "
             "record_trace={!r})")
      .format(cost_name(s.cost), repr(s.max_correspondence_distance), kernel_name(s.kernel),
              repr(s.kernel_scale), s.trim_ratio, s.max_iterations, s.translation_tolerance,
              s.rotation_tolerance, s.initial_damping, repr(s.neighborhood), s.evaluation_points,
              s.check_degeneracy, s.record_trace);
}
bool same(const BatchSettings& a, const BatchSettings& b) {
  return a.cost == b.cost && same(a.max_correspondence_distance, b.max_correspondence_distance) &&
         a.kernel == b.kernel && same(a.kernel_scale, b.kernel_scale) &&
         a.trim_ratio == b.trim_ratio && a.max_iterations == b.max_iterations &&
         a.translation_tolerance == b.translation_tolerance &&
         a.rotation_tolerance == b.rotation_tolerance && a.initial_damping == b.initial_damping &&
         same(a.neighborhood, b.neighborhood) && a.evaluation_points == b.evaluation_points &&
         a.check_degeneracy == b.check_degeneracy && a.record_trace == b.record_trace;
}

// Value semantics for every settings class: ==, repr, copy.copy and copy.deepcopy.
template <typename T>
void def_value_methods(py::class_<T>& c) {
  c.def("__eq__",
        [](const T& a, const py::handle& b) -> py::object {
          if (!py::isinstance<T>(b)) return py::reinterpret_borrow<py::object>(Py_NotImplemented);
          return py::bool_(same(a, b.cast<const T&>()));
        })
      .def("__repr__", [](const T& a) { return repr(a); })
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

template <typename Class>
void def_distance(py::class_<Class>& c, const char* name, Distance Class::*member,
                  const char* doc) {
  c.def_property(
      name, [member](const Class& s) { return s.*member; },
      [member, name](Class& s, const py::handle& v) { s.*member = distance_from_object(v, name); },
      doc);
}

}  // namespace

std::string type_name(const py::handle& value) {
  return Py_TYPE(value.ptr())->tp_name;
}

std::uint64_t as_count(const py::handle& value, std::string_view name) {
  if (PyBool_Check(value.ptr()) || !PyIndex_Check(value.ptr())) {
    throw py::type_error(std::string(name) + " must be an integer, got " + type_name(value));
  }
  const auto index = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
  if (!index) throw py::error_already_set();
  if (index < py::int_(0)) {
    throw InvalidSettingsError(std::string(name) + " must be >= 0, got " +
                               std::string(py::str(index)));
  }
  const unsigned long long v = PyLong_AsUnsignedLongLong(index.ptr());
  if (PyErr_Occurred()) throw py::error_already_set();
  return v;
}

double as_real(const py::handle& value, std::string_view name) {
  if (PyBool_Check(value.ptr()) || !PyNumber_Check(value.ptr())) {
    throw py::type_error(std::string(name) + " must be a number, got " + type_name(value));
  }
  const double v = PyFloat_AsDouble(value.ptr());
  if (PyErr_Occurred()) throw py::error_already_set();
  return v;
}

bool as_bool(const py::handle& value, std::string_view name) {
  if (PyBool_Check(value.ptr())) return value.ptr() == Py_True;
  static const py::object numpy_bool = py::module_::import("numpy").attr("bool_");
  if (py::isinstance(value, numpy_bool)) return value.cast<bool>();
  throw py::type_error(std::string(name) + " must be True or False, got " + type_name(value));
}

CostType cost_from_object(const py::handle& value, std::string_view name) {
  if (const auto e = as_enum<CostType>(value)) return *e;
  if (py::isinstance<py::str>(value)) {
    std::string text = value.cast<std::string>();
    std::replace(text.begin(), text.end(), '_', '-');
    for (const auto t :
         {CostType::point_to_point, CostType::point_to_plane, CostType::plane_to_plane}) {
      if (text == to_string(t)) return t;
    }
    throw InvalidSettingsError(std::string(name) + ": unknown cost '" + text +
                               "' (expected point-to-point, point-to-plane or plane-to-plane)");
  }
  throw py::type_error(std::string(name) + " must be a CostType or one of 'point-to-point', " +
                       "'point-to-plane', 'plane-to-plane', got " + type_name(value));
}

SgdSettings with_overrides(SgdSettings s, const py::dict& overrides) {
  bool numeric_distance = false;
  Distance::Unit unit = Distance::Unit::scaled;
  if (overrides.contains("max_distance_unit")) {
    unit = unit_from_object(overrides["max_distance_unit"], "max_distance_unit");
  }
  if (overrides.contains("optimizer")) {
    s.optimizer.type = optimizer_from_object(overrides["optimizer"], "optimizer");
    s.optimizer.learning_rate = usual_learning_rate(s.optimizer.type, s.optimizer.momentum);
  }
  for (const auto& [key, value] : overrides) {
    const std::string name = py::str(key);
    if (name == "optimizer" || name == "max_distance_unit") continue;
    const auto* keyword = std::find_if(kKeywords.begin(), kKeywords.end(),
                                       [&](const Keyword& k) { return k.name == name; });
    if (keyword == kKeywords.end()) unknown_keyword(name);
    if ((name == "max_distance" || name == "min_distance" || name == "kernel_scale") &&
        !py::isinstance<Distance>(value)) {
      numeric_distance = true;
    }
    keyword->apply(s, value, unit);
  }
  if (overrides.contains("max_distance_unit") && !numeric_distance) {
    throw InvalidSettingsError(
        "max_distance_unit applies to max_distance, min_distance and kernel_scale given as "
        "numbers, and none is");
  }
  s.validate();
  return s;
}

BatchSettings with_batch_overrides(BatchSettings s, const py::dict& overrides,
                                   std::string_view method) {
  bool numeric_distance = false;
  Distance::Unit unit = Distance::Unit::scaled;
  if (overrides.contains("max_distance_unit")) {
    unit = unit_from_object(overrides["max_distance_unit"], "max_distance_unit");
  }
  for (const auto& [key, value] : overrides) {
    const std::string name = py::str(key);
    if (name == "max_distance_unit") continue;
    const auto* keyword = std::find_if(kBatchKeywords.begin(), kBatchKeywords.end(),
                                       [&](const BatchKeyword& k) { return k.name == name; });
    if (keyword == kBatchKeywords.end()) {
      const bool sgd_only = std::any_of(kKeywords.begin(), kKeywords.end(),
                                        [&](const Keyword& k) { return k.name == name; }) ||
                            name == "optimizer";
      std::string message = sgd_only
                                ? "setting '" + name + "' applies to the SGD methods only, not to "
                                : "unknown setting '" + name + "' for ";
      message += method.empty() ? std::string("BatchSettings")
                                : "the batch method '" + std::string(method) + "'";
      throw py::type_error(message + "; the batch keyword settings are: " + batch_keyword_list());
    }
    if ((name == "max_distance" || name == "kernel_scale") && !py::isinstance<Distance>(value)) {
      numeric_distance = true;
    }
    keyword->apply(s, value, unit);
  }
  if (overrides.contains("max_distance_unit") && !numeric_distance) {
    throw InvalidSettingsError(
        "max_distance_unit applies to max_distance and kernel_scale given as numbers, and none "
        "is");
  }
  s.validate();
  return s;
}

void bind_settings(py::module_& m) {
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

  py::class_<Distance> distance(
      m, "Distance",
      "A length with its unit: metres, or scaled units (1 = the largest side of the joint "
      "bounding box of both clouds, the paper's [0, 1] space).\n\n"
      "Make one with Distance.metres(v) or Distance.scaled(v).");
  distance
      .def(py::init([](const py::handle& value, const py::handle& unit) {
             return Distance{as_real(value, "value"), unit_from_object(unit, "unit")};
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
          [](Distance& d, const py::handle& v) { d.unit = unit_from_object(v, "unit"); },
          "DistanceUnit.metres or DistanceUnit.scaled.")
      .def("to_scaled", &Distance::to_scaled, "metres_per_unit"_a,
           "The value in scaled units, given the metres per scaled unit "
           "(RegistrationResult.scale_m).");
  def_value_methods(distance);

  py::class_<OptimizerSettings> optimizer(
      m, "OptimizerSettings", "Step rule of eq. 3 and its parameters (Settings.optimizer).");
  optimizer.def(py::init<>(), "The C++ defaults: fixed step (sgd) with learning rate 2.")
      .def_property(
          "type", [](const OptimizerSettings& o) { return o.type; },
          [](OptimizerSettings& o, const py::handle& v) {
            o.type = optimizer_from_object(v, "type");
          },
          "Step rule: OptimizerType or its name ('sgd', 'momentum', 'rmsprop', 'adam', "
          "'gauss-newton').")
      .def_readwrite("learning_rate", &OptimizerSettings::learning_rate,
                     "alpha of eq. 3, scaled units per unit gradient (Settings() default 0.01 "
                     "with Adam; the paper's fixed step 2; Gauss-Newton: fraction of a Newton "
                     "step, 1).")
      .def_readwrite("momentum", &OptimizerSettings::momentum,
                     "Momentum: velocity decay, in [0, 1). Default 0.9.")
      .def_readwrite("beta1", &OptimizerSettings::beta1,
                     "Adam: decay of the mean of gradients, in [0, 1). Default 0.9.")
      .def_readwrite("beta2", &OptimizerSettings::beta2,
                     "Adam: decay of the mean of squared gradients, in [0, 1). Default 0.999.")
      .def_readwrite("rms_decay", &OptimizerSettings::rms_decay,
                     "RMSProp: decay of the mean of squared gradients, in [0, 1). Default 0.9.")
      .def_readwrite("epsilon", &OptimizerSettings::epsilon,
                     "Adam/RMSProp: added to the root mean square, scaled units. Default 1e-8.")
      .def_readwrite("hessian_decay", &OptimizerSettings::hessian_decay,
                     "Gauss-Newton: decay of the running average of the mini-batch Gauss-Newton "
                     "matrices, in [0, 1). Default 0.9.")
      .def_readwrite("damping", &OptimizerSettings::damping,
                     "Gauss-Newton: Levenberg damping relative to the mean diagonal. Default "
                     "1e-3.")
      .def("validate", &OptimizerSettings::validate,
           "Raises InvalidSettingsError (a ValueError) naming the first invalid value.");
  def_value_methods(optimizer);

  py::class_<ConvergenceSettings> convergence(
      m, "ConvergenceSettings",
      "When a stage is stationary: Hotelling's T^2 test on the window's mini-batch gradients and "
      "a path-efficiency guard, or an absolute tolerance on every step (Settings.convergence).");
  convergence.def(py::init<>());
  def_count(convergence, "window", &ConvergenceSettings::window,
            "Iterations per test window, >= 8; also the length of the final iterate average. "
            "Default 20.");
  convergence
      .def_readwrite("chi2", &ConvergenceSettings::chi2,
                     "Critical chi-square value (6 degrees of freedom) of the test; larger stops "
                     "earlier. Default 12.59 (95 %).")
      .def_readwrite("max_path_efficiency", &ConvergenceSettings::max_path_efficiency,
                     "Largest |sum of steps| / sum of |steps| of a stationary window, in (0, 1]. "
                     "Default 0.5.")
      .def_readwrite("translation_tolerance", &ConvergenceSettings::translation_tolerance,
                     "A window whose steps all move the translation less than this (scaled "
                     "units) ... Default 1e-6.")
      .def_readwrite("rotation_tolerance", &ConvergenceSettings::rotation_tolerance,
                     "... and the angles less than this (sum of |d roll|, |d pitch|, |d yaw|, "
                     "rad) is stationary. Default 1e-6.");
  def_value_methods(convergence);

  py::class_<RefinementSettings> refinement(
      m, "RefinementSettings",
      "Refinement stages after the paper's coarse phase: each shrinks d_max to the data and "
      "decays the step (Settings.refinement).");
  refinement.def(py::init<>());
  def_count(refinement, "stages", &RefinementSettings::stages,
            "Refinement stages after the coarse phase (0 = the paper's single phase). Default 3.");
  refinement
      .def_readwrite("step_decay", &RefinementSettings::step_decay,
                     "Step-size multiplier per stage, in (0, 1]. Default 0.5.")
      .def_readwrite("distance_factor", &RefinementSettings::distance_factor,
                     "New d_max = factor x median pair distance of the stage. Default 3.");
  def_distance(refinement, "min_distance", &RefinementSettings::min_distance,
               "Floor of d_max, a Distance. Default Distance.scaled(1e-4).");
  def_value_methods(refinement);

  py::class_<NeighborhoodSettings> neighborhood(
      m, "NeighborhoodSettings",
      "k-nearest neighbourhoods for the normals and covariances of the plane costs "
      "(Settings.neighborhood).");
  neighborhood.def(py::init<>());
  def_count(neighborhood, "k", &NeighborhoodSettings::k,
            "Neighbours per point, the point included, in [3, 1000]. Default 20.");
  def_count(neighborhood, "num_threads", &NeighborhoodSettings::num_threads,
            "Worker threads of the estimation; 0 = all cores (the results are the same for any "
            "count). Default 0.");
  def_flag(neighborhood, "regularize", &NeighborhoodSettings::regularize,
           "Replace each covariance by the GICP plane model (unitless). Default True.");
  neighborhood
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
            return with_overrides(SgdSettings::paper(optimizer_from_object(optimizer, "optimizer")),
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
      .def("validate", &SgdSettings::validate,
           "Raises InvalidSettingsError (a ValueError) naming the first invalid setting.");
  def_count(settings, "batch_size", &SgdSettings::batch_size,
            "m of the paper: source points per mini-batch. Default 160.");
  def_distance(
      settings, "max_correspondence_distance", &SgdSettings::max_correspondence_distance,
      "d_max: pairs farther apart are rejected, a Distance. Default Distance.scaled(0.5).");
  settings
      .def_readwrite("optimizer", &SgdSettings::optimizer,
                     "OptimizerSettings. Default Adam with learning rate 0.01.")
      .def_readwrite("convergence", &SgdSettings::convergence, "ConvergenceSettings.")
      .def_readwrite("refinement", &SgdSettings::refinement, "RefinementSettings.")
      .def_property(
          "cost", [](const SgdSettings& s) { return s.cost; },
          [](SgdSettings& s, const py::handle& v) { s.cost = cost_from_object(v, "cost"); },
          "Cost of a pair: CostType or its name ('point-to-point', 'point-to-plane', "
          "'plane-to-plane'). The plane costs need reference normals / covariances. Default "
          "CostType.point_to_point.")
      .def_property(
          "kernel", [](const SgdSettings& s) { return s.kernel; },
          [](SgdSettings& s, const py::handle& v) { s.kernel = kernel_from_object(v, "kernel"); },
          "Robust kernel on each pair's residual: KernelType or its name ('none', 'huber', "
          "'cauchy', 'geman-mcclure', 'welsch'). Default KernelType.none.")
      .def_property(
          "scaling_origin", [](const SgdSettings& s) { return s.scaling_origin; },
          [](SgdSettings& s, const py::handle& v) {
            s.scaling_origin = scaling_origin_from_object(v, "scaling_origin");
          },
          "Origin of the scaled space and pivot of the rotation. Default ScalingOrigin.center.");
  def_distance(settings, "kernel_scale", &SgdSettings::kernel_scale,
               "Scale of the kernel: the residual size where it starts to down-weight, a "
               "Distance. Default Distance.scaled(0.01).");
  settings
      .def_readwrite("trim_ratio", &SgdSettings::trim_ratio,
                     "Keep only this fraction of each mini-batch's pairs, the closest ones "
                     "(trimmed ICP, for partial overlap), in (0, 1]. Default 1.")
      .def_readwrite("neighborhood", &SgdSettings::neighborhood,
                     "NeighborhoodSettings for the normals and covariances of the plane costs.");
  def_count(settings, "max_iterations", &SgdSettings::max_iterations,
            "Iteration (mini-batch) limit; reaching it means not converged. Default 4000.");
  def_count(settings, "seed", &SgdSettings::seed,
            "Seed of the mini-batch sampler; same inputs and seed give the same result. Default "
            "2019.");
  def_flag(settings, "average_iterates", &SgdSettings::average_iterates,
           "Return the mean of the final stage's iterates instead of the last one. Default True.");
  def_count(
      settings, "evaluation_points", &SgdSettings::evaluation_points,
      "Source points (spread evenly) for the final inlier statistics; 0 = all. Default 2000.");
  def_flag(settings, "record_trace", &SgdSettings::record_trace,
           "Fill RegistrationResult.trace. Default False.");
  def_flag(settings, "check_degeneracy", &SgdSettings::check_degeneracy,
           "Check the final alignment for degenerate geometry (a plane, a corridor) and report "
           "it in RegistrationResult.constraint_ratio / degenerate. Default True.");
  def_value_methods(settings);

  py::class_<BatchSettings> batch(
      m, "BatchSettings",
      "Settings of the batch methods (register(method='icp' | 'icp-plane' | 'gicp')): the C++ "
      "sgdicp::BatchSettings, same names and defaults. Every iteration pairs all source points "
      "with their nearest reference point within d_max, then takes the closed-form SVD step "
      "(point-to-point) or one damped Gauss-Newton step (the plane costs).\n\n"
      "BatchSettings(**overrides) is the default (point-to-point) with the batch keyword "
      "overrides of register() applied (max_distance, max_distance_unit, max_iterations, kernel, "
      "kernel_scale, trim, neighbors, damping, translation_tolerance, rotation_tolerance, "
      "evaluation_points, check_degeneracy, cost).");
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
      .def("validate", &BatchSettings::validate,
           "Raises InvalidSettingsError (a ValueError) naming the first invalid setting.")
      .def_property(
          "cost", [](const BatchSettings& s) { return s.cost; },
          [](BatchSettings& s, const py::handle& v) { s.cost = cost_from_object(v, "cost"); },
          "Cost of a pair: CostType or its name. register(method=...) replaces it with the "
          "method's cost. Default CostType.point_to_point.");
  def_distance(batch, "max_correspondence_distance", &BatchSettings::max_correspondence_distance,
               "d_max: pairs farther apart are rejected, a Distance (scaled: fraction of the "
               "largest side of the joint bounding box). Default Distance.scaled(0.05).");
  batch.def_property(
      "kernel", [](const BatchSettings& s) { return s.kernel; },
      [](BatchSettings& s, const py::handle& v) { s.kernel = kernel_from_object(v, "kernel"); },
      "Robust kernel on each pair's residual: KernelType or its name. Default KernelType.none.");
  def_distance(batch, "kernel_scale", &BatchSettings::kernel_scale,
               "Scale of the kernel: the residual size where it starts to down-weight, a "
               "Distance. Default Distance.scaled(0.01).");
  batch.def_readwrite("trim_ratio", &BatchSettings::trim_ratio,
                      "Keep only this fraction of each iteration's pairs, the closest ones "
                      "(trimmed ICP), in (0, 1]. Default 1.");
  def_count(batch, "max_iterations", &BatchSettings::max_iterations,
            "Iteration limit (passes over the source); reaching it means not converged. "
            "Default 100.");
  batch
      .def_readwrite("translation_tolerance", &BatchSettings::translation_tolerance,
                     "Converged when an iteration moves the translation less than this (scaled "
                     "units) ... Default 1e-5.")
      .def_readwrite("rotation_tolerance", &BatchSettings::rotation_tolerance,
                     "... and the rotation less than this (rotation angle, rad). Default 1e-5.")
      .def_readwrite("initial_damping", &BatchSettings::initial_damping,
                     "Initial Levenberg-Marquardt damping, relative to the mean diagonal of "
                     "J^T J; 0 = plain Gauss-Newton; unused by point-to-point. Default 1e-6.")
      .def_readwrite("neighborhood", &BatchSettings::neighborhood,
                     "NeighborhoodSettings for the normals and covariances of the plane costs.");
  def_count(
      batch, "evaluation_points", &BatchSettings::evaluation_points,
      "Source points (spread evenly) for the final inlier statistics; 0 = all. Default 2000.");
  def_flag(batch, "check_degeneracy", &BatchSettings::check_degeneracy,
           "Check the final alignment for degenerate geometry and report it in "
           "RegistrationResult.constraint_ratio / degenerate. Default True.");
  def_flag(batch, "record_trace", &BatchSettings::record_trace,
           "Fill RegistrationResult.trace: one entry per iteration (pose, step size 1, d_max, "
           "pairs, mean squared pair distance). Default False.");
  def_value_methods(batch);
}

}  // namespace sgdicp::python
