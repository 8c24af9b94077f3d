// Python values as settings: the typed parsing of Python values (bindings.hpp) and the flat
// keyword overrides shared by Settings(...), Settings.paper(...), Settings.replace(...),
// BatchSettings(...) and register(...), named after the library's settings table; the same for
// the odometry's and the global registration's tables (take_keywords).
#include <algorithm>
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <pybind11/native_enum.h>

#include "bindings.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/global/global_registration.hpp"
#include "sgdicp/odometry/odometry.hpp"
#include "sgdicp/registration/batch_icp.hpp"

namespace sgdicp::python {
namespace {

// ---- enums from Python values (the enum itself or one of its names, enum_names.hpp)

// The enum value if `value` is an instance of the bound enum E.
template <typename E>
std::optional<E> as_enum(const py::handle& value) {
  py::detail::make_caster<E> caster;
  if (!caster.load(value, /*convert=*/false)) return std::nullopt;
  return py::detail::cast_op<E>(caster);
}

// The Python class of each bound enum, for messages.
constexpr std::string_view python_class(OptimizerType) {
  return "OptimizerType";
}
constexpr std::string_view python_class(ScalingOrigin) {
  return "ScalingOrigin";
}
constexpr std::string_view python_class(CostType) {
  return "CostType";
}
constexpr std::string_view python_class(KernelType) {
  return "KernelType";
}
constexpr std::string_view python_class(UncertaintyType) {
  return "UncertaintyType";
}
constexpr std::string_view python_class(Distance::Unit) {
  return "DistanceUnit";
}

// "'a', 'b', 'c'": the names of E for a message.
template <typename E>
std::string quoted_names() {
  std::string out;
  for (const auto name : canonical_names<E>()) {
    out += (out.empty() ? "'" : ", '") + std::string(name) + "'";
  }
  return out;
}

}  // namespace

template <typename E>
E enum_from_object(const py::handle& value, std::string_view name) {
  if (const auto e = as_enum<E>(value)) return *e;
  if (py::isinstance<py::str>(value)) return parse_enum<E>(value.cast<std::string>());
  throw py::type_error(std::string(name) + " must be a " + std::string(python_class(E{})) +
                       " or one of " + quoted_names<E>() + ", got " + type_name(value));
}

template OptimizerType enum_from_object<OptimizerType>(const py::handle&, std::string_view);
template ScalingOrigin enum_from_object<ScalingOrigin>(const py::handle&, std::string_view);
template CostType enum_from_object<CostType>(const py::handle&, std::string_view);
template KernelType enum_from_object<KernelType>(const py::handle&, std::string_view);
template UncertaintyType enum_from_object<UncertaintyType>(const py::handle&, std::string_view);
template Distance::Unit enum_from_object<Distance::Unit>(const py::handle&, std::string_view);

Distance distance_from_object(const py::handle& value, std::string_view name) {
  if (py::isinstance<Distance>(value)) return value.cast<Distance>();
  throw py::type_error(std::string(name) +
                       " must be a Distance, e.g. Distance.metres(1.0) or Distance.scaled(0.5), "
                       "got " +
                       type_name(value));
}

std::string keyword_of(std::string_view name) {
  std::string keyword(name);
  std::replace(keyword.begin(), keyword.end(), '-', '_');
  return keyword;
}

namespace {

// ---- the flat keyword overrides: the names of the settings table (settings.hpp) with '_' for
// '-', i.e. the CLI's options

// A distance given as a number takes the unit of max_distance_unit; a Distance keeps its own.
Distance distance_or_number(const py::handle& value, Distance::Unit unit, std::string_view name) {
  if (py::isinstance<Distance>(value)) return value.cast<Distance>();
  return Distance{as_real(value, name), unit};
}

// A keyword's Python value as the value of its setting.
template <typename S>
SettingValue value_from_object(const Setting<S>& s, const py::handle& value, Distance::Unit unit,
                               std::string_view keyword) {
  switch (s.kind) {
    case SettingKind::count:
      return as_count(value, keyword);
    case SettingKind::real:
      return as_real(value, keyword);
    case SettingKind::flag:
      return as_bool(value, keyword);
    case SettingKind::distance:
      return distance_or_number(value, unit, keyword);
    case SettingKind::choice:
      break;
  }
  // Any of the enum's members (by its name) or one of its names.
  static const py::object enum_type = py::module_::import("enum").attr("Enum");
  if (py::isinstance(value, enum_type)) return value.attr("name").cast<std::string>();
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  std::string names;
  for (const auto name : s.choices())
    names += (names.empty() ? "'" : ", '") + std::string(name) + "'";
  throw py::type_error(std::string(keyword) + " must be one of " + names +
                       " (or the enum member), got " + type_name(value));
}

// Names a reader of the Settings attributes may try, and the keyword that means it.
constexpr std::array<std::pair<std::string_view, std::string_view>, 13> kSuggestions{{
    {"voxel_size_m", "voxel_size"},
    {"max_correspondence_distance", "max_distance"},
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

template <typename S>
std::string keyword_list(const std::vector<Setting<S>>& table) {
  std::string list = "max_distance_unit";
  for (const auto& s : table) list += ", " + keyword_of(s.name);
  return list;
}

[[noreturn]] void unknown_keyword(const std::string& name) {
  std::string message = "unknown setting '" + name + "'";
  for (const auto& [alias, keyword] : kSuggestions) {
    if (name == alias) message += " (did you mean '" + std::string(keyword) + "'?)";
  }
  if (is_retired_setting(name)) {
    message +=
        " (no longer a setting: a fixed rule of the default, or Settings.paper()'s; "
        "docs/registration.md)";
  }
  if (name.starts_with("global")) {
    message.append("; the keywords of register(init='global') are: ");
    for (const auto& s : global_settings_table()) {
      message.append(&s == &global_settings_table().front() ? "" : ", ").append(keyword_of(s.name));
    }
  }
  throw py::type_error(message +
                       "; the keyword settings are: " + keyword_list(sgd_settings_table()));
}

[[noreturn]] void not_a_batch_keyword(const std::string& name, std::string_view method) {
  const bool sgd_only = find_sgd_setting(name) != nullptr && name.find('-') == std::string::npos;
  std::string message = sgd_only ? "setting '" + name + "' applies to the SGD methods only, not to "
                                 : "unknown setting '" + name + "' for ";
  message += method.empty() ? std::string("BatchSettings")
                            : "the batch method '" + std::string(method) + "'";
  throw py::type_error(message +
                       "; the batch keyword settings are: " + keyword_list(batch_settings_table()));
}

// Sets the keywords of `overrides` that name a setting of `table`, in table order (so that
// optimizer= sets the learning rate before learning_rate= overrides it), range-checked, a
// distance given as a number in `unit`. Returns whether any distance was given as a number.
template <typename S>
bool set_keywords(S& s, const py::dict& overrides, const std::vector<Setting<S>>& table,
                  Distance::Unit unit) {
  bool numeric_distance = false;
  for (const auto& setting : table) {
    const std::string keyword = keyword_of(setting.name);
    if (!overrides.contains(keyword)) continue;
    const py::handle value = overrides[keyword.c_str()];
    const SettingValue v = value_from_object(setting, value, unit, keyword);
    numeric_distance = numeric_distance ||
                       (setting.kind == SettingKind::distance && !py::isinstance<Distance>(value));
    check_range(setting, v, SettingNames::python);
    setting.set(s, v);
  }
  return numeric_distance;
}

// set_keywords with the unit of max_distance_unit (an error when no distance uses it), then
// validates.
template <typename S>
S apply_keywords(S s, const py::dict& overrides, const std::vector<Setting<S>>& table) {
  Distance::Unit unit = Distance::Unit::scaled;
  const bool unit_given = overrides.contains("max_distance_unit");
  if (unit_given)
    unit = enum_from_object<Distance::Unit>(overrides["max_distance_unit"], "max_distance_unit");
  const bool numeric_distance = set_keywords(s, overrides, table, unit);
  if (unit_given && !numeric_distance) {
    std::vector<std::string> distances;
    for (const auto& setting : table) {
      if (setting.kind == SettingKind::distance) distances.push_back(keyword_of(setting.name));
    }
    std::string names;
    for (std::size_t i = 0; i < distances.size(); ++i) {
      names += (i == 0 ? "" : i + 1 == distances.size() ? " and " : ", ") + distances[i];
    }
    throw InvalidSettingsError("max_distance_unit applies to " + names +
                               " given as numbers, and none is");
  }
  s.validate(SettingNames::python);
  return s;
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
  if (PyErr_Occurred()) {
    PyErr_Clear();  // beyond 64 bits: never wrapped around
    throw InvalidSettingsError(std::string(name) + " must be at most 2^64-1, got " +
                               std::string(py::str(index)));
  }
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
  return enum_from_object<CostType>(value, name);
}

SgdSettings with_overrides(SgdSettings s, const py::dict& overrides) {
  for (const auto& [key, value] : overrides) {
    const std::string name = py::str(key);
    if (name != "max_distance_unit" &&
        (name.find('-') != std::string::npos || !find_sgd_setting(name))) {
      unknown_keyword(name);
    }
  }
  return apply_keywords(std::move(s), overrides, sgd_settings_table());
}

template <typename S>
S take_keywords(S base, py::dict& overrides, const std::vector<Setting<S>>& table) {
  set_keywords(base, overrides, table, Distance::Unit::scaled);
  for (const auto& setting : table) {
    const std::string keyword = keyword_of(setting.name);
    if (overrides.contains(keyword)) overrides.attr("pop")(keyword);
  }
  base.validate(SettingNames::python);
  return base;
}

template OdometrySettings take_keywords(OdometrySettings, py::dict&,
                                        const std::vector<Setting<OdometrySettings>>&);
template GlobalSettings take_keywords(GlobalSettings, py::dict&,
                                      const std::vector<Setting<GlobalSettings>>&);

BatchSettings with_batch_overrides(BatchSettings s, const py::dict& overrides,
                                   std::string_view method) {
  for (const auto& [key, value] : overrides) {
    const std::string name = py::str(key);
    if (name != "max_distance_unit" &&
        (name.find('-') != std::string::npos || !find_batch_setting(name))) {
      not_a_batch_keyword(name, method);
    }
  }
  return apply_keywords(std::move(s), overrides, batch_settings_table());
}

}  // namespace sgdicp::python
