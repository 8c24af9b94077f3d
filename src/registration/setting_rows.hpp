#pragma once
// How a settings table (settings.hpp's Setting<S>) is made and read, for every table: the SGD and
// batch solvers' (settings_table.cpp), the odometry's and the global registration's. A row is
// built from its member path alone (its kind, get and set follow from the member's type);
// check_table and find_in are the validation and the look-up by name that each table's struct
// uses.
#include <cstdint>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "sgdicp/core/enum_names.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp::detail {

// Every distance in metres: a micrometre to a thousand kilometres (a 15 cm scan to a km map).
inline constexpr ValueRange kMetresRange{1e-6, 1e6};

template <typename T>
constexpr SettingKind kind_of() {
  if constexpr (std::is_same_v<T, bool>) {
    return SettingKind::flag;
  } else if constexpr (std::is_unsigned_v<T>) {
    return SettingKind::count;
  } else if constexpr (std::is_floating_point_v<T>) {
    return SettingKind::real;
  } else if constexpr (std::is_same_v<T, Distance>) {
    return SettingKind::distance;
  } else {
    static_assert(std::is_enum_v<T>);
    return SettingKind::choice;
  }
}

template <typename T>
SettingValue to_value(const T& v) {
  if constexpr (kind_of<T>() == SettingKind::count) {
    return static_cast<std::uint64_t>(v);
  } else if constexpr (kind_of<T>() == SettingKind::choice) {
    return std::string(enum_name(v));
  } else {
    return v;
  }
}

template <typename T>
T from_value(const SettingValue& v) {
  if constexpr (kind_of<T>() == SettingKind::count) {
    return static_cast<T>(std::get<std::uint64_t>(v));
  } else if constexpr (kind_of<T>() == SettingKind::choice) {
    return parse_enum<T>(std::get<std::string>(v));
  } else {
    return std::get<T>(v);
  }
}

template <typename S, auto... Members>
struct Field {
  static auto& ref(S& s) { return (s.*....*Members); }
  static const auto& ref(const S& s) { return (s.*....*Members); }
  using Type = std::remove_cvref_t<decltype(ref(std::declval<S&>()))>;
};

// What a row says beyond its member: names, range, unit, help.
struct Describe {
  std::string_view name;
  std::string_view field;
  ValueRange range{};
  std::string_view unit{};
  std::string_view help{};
  bool keyword_only = false;
};

// `row` marked common (SettingDescription::common).
template <typename S>
Setting<S> common(Setting<S> row) {
  row.common = true;
  return row;
}

// The row of the member S.*Members... (nested members in order).
template <typename S, auto... Members>
Setting<S> setting(const Describe& d) {
  using F = Field<S, Members...>;
  using T = typename F::Type;
  Setting<S> s;
  s.name = d.name;
  s.field = d.field;
  s.kind = kind_of<T>();
  s.range = d.range;
  s.metres_range = kMetresRange;
  s.unit = d.unit;
  s.help = d.help;
  s.keyword_only = d.keyword_only;
  if constexpr (kind_of<T>() == SettingKind::choice) {
    s.choices = [] { return canonical_names<T>(); };
  }
  s.get = [](const S& x) { return to_value(F::ref(x)); };
  s.set = [](S& x, const SettingValue& v) { F::ref(x) = from_value<T>(v); };
  return s;
}

// The row called `name` ('_' may stand for '-'), or nullptr.
template <typename S>
const Setting<S>* find_in(const std::vector<Setting<S>>& table, std::string_view name) {
  for (const auto& s : table) {
    if (same_name(s.name, name)) return &s;
  }
  return nullptr;
}

// Every value of `settings` in its row's range (check_range), in table order.
template <typename S>
void check_table(const S& settings, const std::vector<Setting<S>>& table, SettingNames names) {
  for (const auto& s : table) check_range(s, s.get(settings), names);
}

}  // namespace sgdicp::detail
