#pragma once
// The registration methods by name, as the CLI's --method and Python's method= spell them: which
// solver runs and with which cost. One table, read by the CLI, the Python bindings and the docs.
#include <array>
#include <optional>
#include <string>
#include <string_view>

#include "sgdicp/core/enum_names.hpp"
#include "sgdicp/costs/cost.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp {

enum class Solver {
  sgd,    ///< SGD-ICP, align() with SgdSettings
  batch,  ///< the batch baselines, align_batch() with BatchSettings
};

struct Method {
  std::string_view name;
  Solver solver;
  /// The cost the method sets; none for "sgd", which keeps the cost of its settings
  /// (point-to-plane by default; the paper preset's point-to-point).
  std::optional<CostType> cost;
  std::string_view help;
};

inline constexpr std::array<Method, 7> kMethods{{
    {"sgd", Solver::sgd, std::nullopt,
     "SGD-ICP with the settings' cost: point-to-plane by default, point-to-point with the "
     "paper preset"},
    {"sgd-point", Solver::sgd, CostType::point_to_point,
     "SGD-ICP on point-to-point (the paper's cost)"},
    {"sgd-plane", Solver::sgd, CostType::point_to_plane, "SGD-ICP on point-to-plane"},
    {"sgd-gicp", Solver::sgd, CostType::plane_to_plane, "SGD-ICP on plane-to-plane (GICP)"},
    {"icp", Solver::batch, CostType::point_to_point,
     "batch point-to-point ICP, closed-form SVD step"},
    {"icp-plane", Solver::batch, CostType::point_to_plane,
     "batch point-to-plane ICP, Levenberg-Marquardt step"},
    {"gicp", Solver::batch, CostType::plane_to_plane,
     "batch plane-to-plane (GICP), Levenberg-Marquardt step"},
}};

/// Sets the cost a method fixes, in every stage: a method named for its cost pairs with that cost
/// from the first mini-batch to the last (SgdSettings::coarse_cost too); "sgd" keeps the
/// settings' costs (by default point-to-point coarse, point-to-plane refinement).
inline void apply_method_cost(const Method& method, SgdSettings& sgd, BatchSettings& batch) {
  if (!method.cost) return;
  sgd.cost = sgd.coarse_cost = batch.cost = *method.cost;
}

/// "sgd, sgd-plane, ... or gicp".
[[nodiscard]] inline std::string method_list(std::string_view last_separator = " or ") {
  std::string out;
  for (std::size_t i = 0; i < kMethods.size(); ++i) {
    if (i > 0) out += i + 1 == kMethods.size() ? std::string(last_separator) : std::string(", ");
    out += kMethods[i].name;
  }
  return out;
}

/// Throws InvalidSettingsError when `sgd` asks for a pose uncertainty (SgdSettings::uncertainty)
/// and `method` is a batch one: only the SGD methods estimate one (docs/uncertainty.md). The
/// setting and the method are spelled as `names` says. The CLI's methods and Odometry check it.
inline void check_method_uncertainty(const Method& method, const SgdSettings& sgd,
                                     SettingNames names = SettingNames::field) {
  const UncertaintyType asked = sgd.uncertainty.method;
  if (method.solver == Solver::sgd || asked == UncertaintyType::none) return;
  const std::string value(to_string(asked));
  const std::string setting = names == SettingNames::cli      ? "--uncertainty " + value
                              : names == SettingNames::python ? "uncertainty='" + value + "'"
                                                              : "uncertainty.method " + value;
  const std::string name(method.name);
  throw InvalidSettingsError(
      setting + ": only the SGD methods estimate an uncertainty, not " +
      (names == SettingNames::cli ? "--method " + name : "method '" + name + "'"));
}

/// The method of a name ('_' may stand for '-'); InvalidSettingsError for an unknown one.
[[nodiscard]] inline const Method& method_from_string(std::string_view name) {
  for (const Method& m : kMethods) {
    if (detail::same_name(m.name, name)) return m;
  }
  throw InvalidSettingsError("unknown method '" + std::string(name) + "' (expected " +
                             method_list() + ")");
}

}  // namespace sgdicp
