#include "io/parse_number.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <limits>
#include <system_error>

namespace sgdicp {
namespace {

// Decimal exponent of the leading significant digit of a number's text (sign stripped),
// saturated: it tells overflow from underflow when std::from_chars reports out of range.
// "1000e-1" -> 2, "0.001" -> -3.
std::int64_t decimal_magnitude(std::string_view text) {
  constexpr std::int64_t kSaturated = std::int64_t{1} << 40;
  std::int64_t magnitude = 0;
  bool seen_digit = false;
  bool in_fraction = false;
  std::size_t i = 0;
  for (; i < text.size() && text[i] != 'e' && text[i] != 'E'; ++i) {
    if (text[i] == '.') {
      in_fraction = true;
    } else if (in_fraction) {
      if (!seen_digit) --magnitude;
      seen_digit = seen_digit || text[i] != '0';
    } else if (seen_digit || text[i] != '0') {
      if (seen_digit) magnitude = std::min(magnitude + 1, kSaturated);
      seen_digit = true;
    }
  }
  std::int64_t exponent = 0;
  const bool negative = i + 1 < text.size() && text[i + 1] == '-';
  for (i += (i + 1 < text.size() && (text[i + 1] == '-' || text[i + 1] == '+')) ? 2 : 1;
       i < text.size(); ++i) {
    exponent = std::min(exponent * 10 + (text[i] - '0'), kSaturated);
  }
  return magnitude + (negative ? -exponent : exponent);
}

}  // namespace

bool parse_number(std::string_view token, double& out) {
  const char* first = token.data();
  const char* const last = first + token.size();
  if (first != last && *first == '+') {
    ++first;  // std::from_chars rejects an explicit plus sign
    if (first != last && (*first == '-' || *first == '+')) return false;
  }
  if (first == last) return false;
  double value = 0.0;
  const auto [end, error] = std::from_chars(first, last, value);
  if (end != last) return false;
  if (error == std::errc()) {
    out = value;
    return true;
  }
  if (error != std::errc::result_out_of_range) return false;
  const bool negative = *first == '-';
  const std::string_view text(first + (negative ? 1 : 0),
                              static_cast<std::size_t>(last - first) - (negative ? 1 : 0));
  const double magnitude =
      decimal_magnitude(text) > 0 ? std::numeric_limits<double>::infinity() : 0.0;
  out = negative ? -magnitude : magnitude;
  return true;
}

}  // namespace sgdicp
