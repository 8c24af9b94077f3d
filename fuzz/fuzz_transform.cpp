// libFuzzer target: parse_transform (transform files, --init / --ground-truth text).
// Documented failure: FormatError. The result must be a rigid transform (the documented
// promise), anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/pose.hpp"
#include "sgdicp/io/transform_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const Eigen::Matrix4d T = sgdicp::parse_transform(text, "fuzz");
    if (!sgdicp::is_rigid_transform(T, 1e-9)) {
      std::fputs("parse_transform returned a transform that is not rigid\n", stderr);
      std::abort();
    }
  } catch (const sgdicp::FormatError&) {
  }
  return 0;
}
