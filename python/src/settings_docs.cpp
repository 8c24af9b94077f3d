// The library's settings table (settings.hpp) as Python text: each settings attribute's
// docstring (help, unit, range, keyword, default) and the keyword lists of register()'s docstring,
// so that the text has one source; and as data, for the keyword parameters of the type stub.
#include <algorithm>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "sgdicp/global/global_registration.hpp"
#include "sgdicp/odometry/odometry.hpp"
#include "sgdicp/registration/batch_icp.hpp"

namespace sgdicp::python {

// A value as Python writes it, for repr and "Default X." (which the package tests evaluate):
// enums as Class.member, arrays as tuples.
std::string python_literal(const py::object& value) {
  static const py::object enum_type = py::module_::import("enum").attr("Enum");
  if (py::isinstance(value, enum_type)) {
    return py::str("{}.{}").format(py::type::handle_of(value).attr("__name__"), value.attr("name"));
  }
  if (py::hasattr(value, "tolist")) return py::repr(py::tuple(value.attr("tolist")()));
  return py::repr(value);
}

namespace {

// The Python path of a setting's C++ member: the groups sampling, pairing, scaling, evaluation and
// downsampling are flat attributes of the settings class (settings.cpp), under the member's own
// name except for the scaling's two; the other groups are nested classes (optimizer.type).
std::string python_path(std::string_view field) {
  if (field == "scaling.origin") return "scaling_origin";
  if (field == "scaling.robust") return "robust_scaling";
  for (const std::string_view group : {"sampling.", "pairing.", "evaluation.", "downsampling."}) {
    if (field.starts_with(group)) return std::string(field.substr(group.size()));
  }
  return std::string(field);
}

// The Python class holding a setting's attribute, by the part of its Python path before the dot.
std::string class_of(std::string_view field, std::string_view top) {
  const auto dot = field.find('.');
  if (dot == std::string_view::npos) return std::string(top);
  const std::string_view part = field.substr(0, dot);
  if (part == "optimizer") return "OptimizerSettings";
  if (part == "convergence") return "ConvergenceSettings";
  if (part == "refinement") return "RefinementSettings";
  if (part == "uncertainty") return "UncertaintySettings";
  return "NeighborhoodSettings";
}

// The value of a setting's member (its field, e.g. "optimizer.type") in `defaults`.
template <typename S>
py::object value_of(const Setting<S>& s, const py::object& defaults) {
  py::object value = defaults;
  const std::string path = python_path(s.field);
  std::string_view rest = path;
  for (auto dot = rest.find('.'); dot != std::string_view::npos; dot = rest.find('.')) {
    value = value.attr(std::string(rest.substr(0, dot)).c_str());
    rest = rest.substr(dot + 1);
  }
  return value.attr(std::string(rest).c_str());
}

// The name of the Python class of a value (the enum of a choice).
std::string class_name(const py::object& value) {
  return py::str(py::type::handle_of(value).attr("__name__")).cast<std::string>();
}

// The docstring of a setting's attribute: the table's help, range and unit, and the default read
// from a default-constructed `defaults`.
template <typename S>
std::string attribute_doc(const Setting<S>& s, const py::object& defaults) {
  const py::object value = value_of(s, defaults);
  std::string doc(s.help);
  switch (s.kind) {
    case SettingKind::count:
    case SettingKind::real:
      doc += (s.unit.empty() ? ", in " : ", " + std::string(s.unit) + " in ") + s.range.to_string();
      break;
    case SettingKind::distance:
      doc += ", a Distance in " + s.range.to_string() + " scaled units or " +
             s.metres_range.to_string() + " m";
      break;
    case SettingKind::choice:
      doc += " (" + class_name(value) + " or one of its names)";
      break;
    case SettingKind::flag:
      break;
  }
  // The fixed rules (sgd_fixed_rules_table) are named by their C++ member: no keyword sets them.
  const bool keyword = s.name.find('.') == std::string_view::npos;
  return doc + (keyword ? ". Keyword " + keyword_of(s.name) + "=" : std::string(". A fixed rule")) +
         ". Default " + python_literal(value) + ".";
}

// Gives every attribute of the settings table its docstring from the table (settings.hpp).
template <typename S>
void document_attributes(py::module_& m, const std::vector<Setting<S>>& table, const char* top) {
  const py::object defaults = m.attr(top)();
  const py::object property = py::module_::import("builtins").attr("property");
  for (const auto& s : table) {
    const std::string field = python_path(s.field);
    const std::string cls_name = class_of(field, top);
    if (cls_name != top && std::string_view(top) == "BatchSettings") continue;  // nested: SGD's
    const py::object cls = m.attr(cls_name.c_str());
    const std::string attribute =
        field.substr(field.find('.') == std::string::npos ? 0 : field.find('.') + 1);
    const py::object old = cls.attr("__dict__")[attribute.c_str()];
    std::string doc = attribute_doc(s, defaults);
    // A part of Settings documents Settings' value; say so where its own default differs.
    if (cls_name != top) {
      const std::string own = python_literal(cls().attr(attribute.c_str()));
      if (doc.substr(doc.rfind("Default ") + 8) != own + ".") {
        doc += " (That is Settings()'s; a " + cls_name + "() of its own has " + own + ".)";
      }
    }
    py::setattr(cls, attribute.c_str(),
                property(old.attr("fget"), old.attr("fset"), old.attr("fdel"), doc));
  }
}

// "keyword (default, range), ..." wrapped at 96 columns; default_of(s) is a setting's default
// as Python writes it.
template <typename S, typename DefaultOf>
std::string summary_of(const std::vector<const Setting<S>*>& rows, const DefaultOf& default_of,
                       std::string_view indent) {
  std::string out;
  std::string line(indent);
  for (const Setting<S>* row : rows) {
    const Setting<S>& s = *row;
    std::string item = keyword_of(s.name) + " (" + default_of(s);
    if (s.kind == SettingKind::count || s.kind == SettingKind::real) {
      item += ", " + s.range.to_string();
    }
    item += ")";
    if (row != rows.back()) item += ",";
    if (line.size() + item.size() + 1 > 96 && line.size() > indent.size()) {
      out += line + "\n";
      line = std::string(indent);
    }
    line += (line.size() > indent.size() ? " " : "") + item;
  }
  return out + line;
}

template <typename S, typename DefaultOf>
std::string summary_of(const std::vector<Setting<S>>& table, const DefaultOf& default_of,
                       std::string_view indent) {
  std::vector<const Setting<S>*> rows;
  for (const auto& s : table) rows.push_back(&s);
  return summary_of(rows, default_of, indent);
}

// The common settings of `table` (SettingDescription::common), then the others under the heading
// of the part that reads them (setting_part), in table order within a part.
template <typename S, typename DefaultOf>
std::string grouped_summary(const std::vector<Setting<S>>& table, const DefaultOf& default_of,
                            std::string_view indent) {
  std::vector<const Setting<S>*> common;
  std::vector<std::pair<std::string_view, std::vector<const Setting<S>*>>> parts;
  for (const auto& s : table) {
    if (s.common) {
      common.push_back(&s);
      continue;
    }
    const std::string_view part = setting_part(s.field);
    auto it =
        std::find_if(parts.begin(), parts.end(), [&](const auto& p) { return p.first == part; });
    if (it == parts.end()) it = parts.insert(parts.end(), {part, {}});
    it->second.push_back(&s);
  }
  std::string out = std::string(indent) + "The common ones:\n" +
                    summary_of(common, default_of, std::string(indent) + "  ") + ".\n" +
                    std::string(indent) + "The others, by the part of the run that reads them:";
  for (const auto& [part, rows] : parts) {
    out += "\n" + std::string(indent) + std::string(part) + ":\n" +
           summary_of(rows, default_of, std::string(indent) + "  ") + ";";
  }
  out.pop_back();
  return out;
}

// The kind as Python code names it.
constexpr std::string_view kind_name(SettingKind kind) {
  switch (kind) {
    case SettingKind::count:
      return "count";
    case SettingKind::real:
      return "real";
    case SettingKind::flag:
      return "flag";
    case SettingKind::distance:
      return "distance";
    case SettingKind::choice:
      break;
  }
  return "choice";
}

// The keywords that the overrides of a table accept (keywords.cpp), in table order, as
// (keyword, kind, the enum class of a choice or None); max_distance_unit, the unit of the
// distances given as numbers, follows the first distance. `defaults` (the settings class's
// instance) names a choice's enum: None for the tables without choices.
template <typename S>
py::list keyword_rows(const std::vector<Setting<S>>& table, const py::object& defaults) {
  py::list rows;
  bool unit_listed = false;
  for (const auto& s : table) {
    py::object choice = py::none();
    if (s.kind == SettingKind::choice) choice = py::str(class_name(value_of(s, defaults)));
    rows.append(py::make_tuple(keyword_of(s.name), kind_name(s.kind), choice, s.common));
    if (s.kind == SettingKind::distance && !unit_listed) {
      rows.append(py::make_tuple("max_distance_unit", "choice", "DistanceUnit", false));
      unit_listed = true;
    }
  }
  return rows;
}

}  // namespace

std::string keyword_summary(const py::module_& core, Solver solver, std::string_view indent) {
  // The default as the attribute's docstring says it ("Default X.").
  const auto from_doc = [](const py::object& defaults) {
    return [defaults](const auto& s) {
      const std::string doc = attribute_doc(s, defaults);
      const std::string value = doc.substr(doc.rfind("Default ") + 8);
      return value.substr(0, value.size() - 1);
    };
  };
  if (solver == Solver::sgd) {
    return grouped_summary(sgd_settings_table(), from_doc(core.attr("Settings")()), indent);
  }
  return summary_of(batch_settings_table(), from_doc(core.attr("BatchSettings")()), indent);
}

std::string global_keyword_summary(std::string_view indent) {
  return summary_of(
      global_settings_table(),
      [](const Setting<GlobalSettings>& s) {
        const SettingValue v = s.get(GlobalSettings{});
        if (const auto* real = std::get_if<double>(&v))
          return std::string(py::repr(py::float_(*real)));
        return format_value(v);
      },
      indent);
}

void document_settings(py::module_& m) {
  document_attributes(m, sgd_settings_table(), "Settings");
  document_attributes(m, sgd_fixed_rules_table(), "Settings");
  document_attributes(m, batch_settings_table(), "BatchSettings");
}

void bind_settings_keywords(py::module_& m) {
  m.def(
      "_settings_keywords",
      [](const std::string& solver) {
        if (solver == "sgd")
          return keyword_rows(sgd_settings_table(), py::type::of<SgdSettings>()());
        if (solver == "odometry") return keyword_rows(odometry_settings_table(), py::none());
        if (solver == "global") return keyword_rows(global_settings_table(), py::none());
        if (solver != "batch") {
          throw py::value_error("solver must be 'sgd', 'batch', 'odometry' or 'global'");
        }
        return keyword_rows(batch_settings_table(), py::type::of<BatchSettings>()());
      },
      py::arg("solver"),
      "The keywords of Settings(**overrides) (solver 'sgd'), BatchSettings(**overrides) "
      "('batch'), Odometry's own ('odometry') or register(init='global')'s ('global') as "
      "(keyword, kind, enum class name or None, common) in the table's order; kind is 'count', "
      "'real', 'flag', 'distance' or 'choice'; common: one of the few a user sets, listed first. "
      "Read by python/tools/stub_signatures.py.");
}

}  // namespace sgdicp::python
