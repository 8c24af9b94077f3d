#include "sgdicp/core/format_number.hpp"

#include <charconv>
#include <cmath>

namespace sgdicp {

std::string format_number(double value) {
  // Integers as integers (10000000, not 1e+07); others with 6 significant digits, like %g.
  if (std::isfinite(value) && value == std::floor(value) && std::abs(value) < 1e15) {
    return std::to_string(static_cast<long long>(value));
  }
  char buffer[64];
  const auto [end, ec] =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::general, 6);
  return ec == std::errc() ? std::string(buffer, end) : std::string("?");
}

}  // namespace sgdicp
