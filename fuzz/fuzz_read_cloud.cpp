// libFuzzer target: read_point_cloud_from_memory for one format, FileFormat::SGDICP_FUZZ_FORMAT
// (one executable per format, see CMakeLists.txt). Documented failure: FormatError. What is
// returned must keep the reader's promises: only finite points, every point of the file either
// returned or counted as dropped, the format that was asked for, times (if any) one per point,
// finite and from the earliest. Anything else is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>

#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

#ifndef SGDICP_FUZZ_FORMAT
#error "define SGDICP_FUZZ_FORMAT to a FileFormat enumerator (pcd, ply, ...)"
#endif

namespace {

constexpr sgdicp::FileFormat kFormat = sgdicp::FileFormat::SGDICP_FUZZ_FORMAT;

void check(bool condition, const char* what) {
  if (condition) return;
  std::fprintf(stderr, "read_point_cloud_from_memory(%s): %s\n", sgdicp::to_string(kFormat).c_str(),
               what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
  try {
    const sgdicp::ReadResult result = sgdicp::read_point_cloud_from_memory(bytes, kFormat, "fuzz");
    check(result.format == kFormat, "result names another format");
    check(result.cloud.size() + result.non_finite_dropped == result.points_in_file,
          "points returned + dropped != points in file");
    for (const auto& p : result.cloud.points) check(p.allFinite(), "a non-finite point returned");
    const auto& times = result.cloud.times_s;
    check(times.empty() || times.size() == result.cloud.size(), "times not one per point");
    for (const float t : times) check(std::isfinite(t) && t >= 0.0f, "a time not finite or < 0");
  } catch (const sgdicp::FormatError&) {
  }
  return 0;
}
