#pragma once
// How numbers appear in messages, --help and the docs: one spelling everywhere.
#include <string>

namespace sgdicp {

/// A number in its shortest round-trip form (0.01, 1e-06, 12.59); integers as integers
/// (10000000, not 1e+07).
[[nodiscard]] std::string format_number(double value);

}  // namespace sgdicp
