#pragma once
// One name table per enum, read by to_string, the parsers, the CLI's choices, the Python bindings
// and the error messages. Each enum E declares, next to its definition,
//   constexpr std::array<EnumName<E>, N> kEName{{{E::a, "a"}, ...}};
//   constexpr const auto& enum_names(E) { return kEName; }
//   constexpr std::string_view enum_noun(E) { return "what an E is"; }
// (found by argument-dependent lookup); the first entry of a value is its canonical name, later
// entries of the same value are accepted spellings (aliases). Parsing ignores the difference
// between '-' and '_' ("gauss_newton" is "gauss-newton").
#include <string>
#include <string_view>
#include <vector>

#include "sgdicp/core/error.hpp"

namespace sgdicp {

template <typename E>
struct EnumName {
  E value;
  std::string_view name;
};

namespace detail {

constexpr bool same_name(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const char x = a[i] == '_' ? '-' : a[i];
    const char y = b[i] == '_' ? '-' : b[i];
    if (x != y) return false;
  }
  return true;
}

}  // namespace detail

/// The canonical name of a value ("?" for a value outside the table).
template <typename E>
[[nodiscard]] constexpr std::string_view enum_name(E value) {
  for (const auto& entry : enum_names(E{})) {
    if (entry.value == value) return entry.name;
  }
  return "?";
}

/// The canonical names, in table order (aliases left out).
template <typename E>
[[nodiscard]] std::vector<std::string_view> canonical_names() {
  std::vector<std::string_view> out;
  const auto& table = enum_names(E{});
  for (std::size_t i = 0; i < table.size(); ++i) {
    bool first = true;
    for (std::size_t j = 0; j < i; ++j) first = first && table[j].value != table[i].value;
    if (first) out.push_back(table[i].name);
  }
  return out;
}

/// "a, b or c": the canonical names for a message.
template <typename E>
[[nodiscard]] std::string name_list(std::string_view last_separator = " or ") {
  const auto names = canonical_names<E>();
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += i + 1 == names.size() ? std::string(last_separator) : std::string(", ");
    out += names[i];
  }
  return out;
}

/// The value of a name or alias, or nullptr.
template <typename E>
[[nodiscard]] constexpr const E* find_enum(std::string_view name) {
  for (const auto& entry : enum_names(E{})) {
    if (detail::same_name(entry.name, name)) return &entry.value;
  }
  return nullptr;
}

/// The value of a name or alias; InvalidSettingsError "unknown NOUN 'NAME' (expected ...)".
template <typename E>
[[nodiscard]] E parse_enum(std::string_view name) {
  if (const E* value = find_enum<E>(name)) return *value;
  throw InvalidSettingsError("unknown " + std::string(enum_noun(E{})) + " '" + std::string(name) +
                             "' (expected " + name_list<E>() + ")");
}

}  // namespace sgdicp
