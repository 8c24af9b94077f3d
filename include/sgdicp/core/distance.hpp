#pragma once
// A length with an explicit unit, the one type every distance setting uses.
#include <array>

#include "sgdicp/core/enum_names.hpp"

namespace sgdicp {

/// A length with an explicit unit: metres, or units of the paper's [0, 1] scaled space
/// (1 scaled unit = the largest side of the joint bounding box of both clouds).
struct Distance {
  enum class Unit { metres, scaled };
  double value = 0.0;
  Unit unit = Unit::scaled;

  static constexpr Distance metres(double v) { return {v, Unit::metres}; }
  static constexpr Distance scaled(double v) { return {v, Unit::scaled}; }
  /// The value in scaled units, given the metres per scaled unit.
  [[nodiscard]] double to_scaled(double metres_per_unit) const {
    return unit == Unit::scaled ? value : value / metres_per_unit;
  }
  /// The value in metres, given the metres per scaled unit.
  [[nodiscard]] double to_metres(double metres_per_unit) const {
    return unit == Unit::metres ? value : value * metres_per_unit;
  }

  friend bool operator==(const Distance&, const Distance&) = default;
};

inline constexpr std::array<EnumName<Distance::Unit>, 4> kDistanceUnitNames{{
    {Distance::Unit::metres, "m"},
    {Distance::Unit::scaled, "scaled"},
    {Distance::Unit::metres, "metres"},
    {Distance::Unit::metres, "meters"},
}};
constexpr const auto& enum_names(Distance::Unit) {
  return kDistanceUnitNames;
}
constexpr std::string_view enum_noun(Distance::Unit) {
  return "unit";
}

}  // namespace sgdicp
