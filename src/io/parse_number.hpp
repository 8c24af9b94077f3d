#pragma once
// The one number parser of the readers and the transform parser (internal).
#include <string_view>

namespace sgdicp {

/// A whole token as a double, correctly rounded from its decimal text by std::from_chars
/// (locale-independent, exact for mantissas of any length). Accepts one leading '+', and
/// "nan", "inf", "infinity" in any case. Rejects (returns false) hex floats, an empty token and
/// anything that is not one number to its end, such as "0.0.5", "+-1", "1e" or "1,5". Values
/// beyond the double range become +-inf (overflow, e.g. 1e399 written out in full) or +-0 (below
/// the smallest subnormal); the subnormals themselves are exact.
[[nodiscard]] bool parse_number(std::string_view token, double& out);

}  // namespace sgdicp
