// libFuzzer target: read_depth_image_from_memory, the 16-bit PNG depth-image decoder
// (stb_image) and the back-projection. Documented failure: FormatError. What is returned must
// keep the reader's promises: every visited pixel counted once (pixels = valid + invalid_zero +
// invalid_range + nonfinite), one finite point per valid pixel, the pixel count of the image's
// size. Anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>

#include "sgdicp/core/error.hpp"
#include "sgdicp/io/depth_image.hpp"

namespace {

void check(bool condition, const char* what) {
  if (condition) return;
  std::fprintf(stderr, "read_depth_image_from_memory: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
  const sgdicp::PinholeIntrinsics K{585.0, 585.0, 320.0, 240.0};
  sgdicp::DepthImageReport report;
  try {
    const sgdicp::PointCloud cloud =
        sgdicp::read_depth_image_from_memory(bytes, K, {}, &report, "fuzz");
    check(report.pixels ==
              report.valid + report.invalid_zero + report.invalid_range + report.nonfinite,
          "the counts do not add up to the pixels");
    check(report.pixels ==
              static_cast<std::size_t>(report.width) * static_cast<std::size_t>(report.height),
          "pixels != width * height at stride 1");
    check(cloud.size() == report.valid, "points != valid pixels");
    for (const auto& p : cloud.points) check(p.allFinite() && p.z() > 0, "a bad point returned");
  } catch (const sgdicp::FormatError&) {
  }
  return 0;
}
