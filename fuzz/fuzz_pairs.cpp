// libFuzzer target: parse_pairs (the text of a pairs file, as read_pairs_file reads it).
// Documented failure: FormatError. Every pair returned has two paths, a rigid ground truth and
// a line number within the text; anything else is a finding.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/pose.hpp"
#include "sgdicp/tools/pairs.hpp"

namespace {

void check(bool condition, const char* what) {
  if (condition) return;
  std::fprintf(stderr, "parse_pairs: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const auto pairs = sgdicp::parse_pairs(text, "folder", "fuzz");
    check(!pairs.empty(), "no pairs but no error");
    const auto lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1;
    for (const auto& pair : pairs) {
      check(pair.line >= 1 && pair.line <= lines, "line number outside the text");
      check(!pair.source.empty() && !pair.reference.empty(), "empty path");
      check(sgdicp::is_rigid_transform(pair.T_reference_source_gt, 1e-9), "ground truth not rigid");
    }
  } catch (const sgdicp::FormatError&) {
  }
  return 0;
}
