// Depth images as point clouds (depth_image.hpp). PNG decoding is stb_image's (already used for
// the pictures, render.cpp): it decodes 16-bit greyscale PNG exactly (stbi_load_16), reports the
// size and bit depth from the header before decoding, and fails with a reason on a truncated or
// corrupt file, which is all this reader needs.
#include "sgdicp/io/depth_image.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "io/files.hpp"
#include "io/parse_number.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

// stb_image is third-party C code that does not compile warning-free with our flags; its
// functions are made static so they cannot clash with another copy in the program. Only the PNG
// decoder is compiled, and only from memory (the file is read by read_whole_file, bounded).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-but-set-variable"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_NO_STDIO
#define STBI_NO_LINEAR
#define STBI_NO_HDR
#define STBI_FAILURE_USERMSG
#include <stb_image.h>
#pragma GCC diagnostic pop

namespace sgdicp {
namespace {

// Ranges of the settings (validate() and its messages).
constexpr double kMaxUnitsPerMetre = 1e9;
constexpr double kMaxDepthLimit_m = 1e6;
constexpr int kMaxPixelStride = 65536;
constexpr double kMaxFocal_px = 1e9;

[[noreturn]] void bad_setting(const std::string& what) {
  throw InvalidSettingsError(what);
}

// The shortest text that reads back as v ("1000", "0.5", "nan").
std::string number_text(double v) {
  std::array<char, 32> text{};
  const auto end = std::to_chars(text.data(), text.data() + text.size(), v).ptr;
  return std::string(text.data(), end);
}

// Which of the four counts a depth (metres) falls in; true when it is valid.
struct DepthCheck {
  double min_m, max_m;
  DepthImageReport& report;

  bool accept(double z_m) {
    if (!std::isfinite(z_m)) {
      ++report.nonfinite;
    } else if (z_m == 0.0) {
      ++report.invalid_zero;
    } else if (z_m < min_m || z_m > max_m || z_m < 0.0) {
      ++report.invalid_range;
    } else {
      ++report.valid;
      return true;
    }
    return false;
  }
};

void check_size(int width, int height, const std::string& name) {
  if (width <= 0 || height <= 0) {
    throw InvalidInputError(name + ": a depth image of " + std::to_string(width) + " x " +
                            std::to_string(height) + " pixels (both must be positive)");
  }
  const auto pixels = static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  if (pixels > kMaxCloudPoints) {
    throw FormatError(name + ": " + std::to_string(width) + " x " + std::to_string(height) +
                      " pixels, more than the largest cloud read (" +
                      std::to_string(kMaxCloudPoints) + " points)");
  }
}

// Deflate expands at most 1032-fold (258 bytes from one 2-bit code), so a file whose header
// claims more 16-bit pixel bytes than that cannot hold them: refused before the decoder
// allocates what the header claims.
void check_compressed_size(int width, int height, std::size_t file_bytes, const std::string& name) {
  constexpr std::uint64_t kMaxDeflateRatio = 1032;
  const std::uint64_t raw =
      (2 * static_cast<std::uint64_t>(width) + 1) * static_cast<std::uint64_t>(height);
  if (raw > kMaxDeflateRatio * file_bytes + 1024) {
    throw FormatError(name + ": truncated: its header claims " + std::to_string(width) + " x " +
                      std::to_string(height) + " 16-bit pixels, more than " +
                      std::to_string(file_bytes) + " bytes of PNG can hold");
  }
}

// The one back-projection loop; `depth_m(i)` is the depth of pixel i in metres.
template <typename DepthOf>
PointCloud back_project(int width, int height, const PinholeIntrinsics& K,
                        const DepthImageSettings& settings, DepthImageReport* report,
                        DepthOf depth_m) {
  K.validate();
  settings.validate();
  check_size(width, height, "depth image");
  DepthImageReport counts;
  counts.width = width;
  counts.height = height;
  DepthCheck check{settings.min_depth_m, settings.max_depth_m, counts};
  const int stride = settings.pixel_stride;
  const int border = settings.border_px;
  if (2 * static_cast<std::int64_t>(border) >= std::min(width, height)) {
    bad_setting("border_px = " + std::to_string(border) + " leaves no pixel of a " +
                std::to_string(width) + " x " + std::to_string(height) + " depth image");
  }
  // The pixels (u, v) with u and v multiples of the stride, within the border.
  const int first = (border + stride - 1) / stride * stride;
  const auto visited = [stride, border, first](int size) {
    const int end = size - border;
    return static_cast<std::size_t>(first < end ? (end - first + stride - 1) / stride : 0);
  };
  PointCloud cloud;
  counts.pixels = visited(width) * visited(height);
  cloud.points.reserve(counts.pixels);
  for (int v = first; v < height - border; v += stride) {
    for (int u = first; u < width - border; u += stride) {
      const double z = depth_m(static_cast<std::size_t>(v) * static_cast<std::size_t>(width) +
                               static_cast<std::size_t>(u));
      if (!check.accept(z)) continue;
      cloud.points.emplace_back(to_float_saturating((u - K.cx) * z / K.fx),
                                to_float_saturating((v - K.cy) * z / K.fy), to_float_saturating(z));
    }
  }
  cloud.points.shrink_to_fit();
  if (report) *report = counts;
  return cloud;
}

struct StbFree {
  void operator()(stbi_us* p) const noexcept { stbi_image_free(p); }
};

// The PNG's chunks checked against the file before stb_image sees them, which 2.27 does not do:
// a chunk whose length runs past the end of the file is refused (stb_image would allocate the
// claimed length first, up to 4 GiB, for a file of a few bytes), and empty IDAT chunks (legal,
// no data) are dropped, as stb_image copies one with memcpy from a null pointer (undefined
// behaviour). Both found by fuzz_depth_png. Returns `data` itself unless a chunk was dropped.
std::string_view checked_png_chunks(std::string_view data, const std::string& name,
                                    std::string& storage) {
  constexpr std::size_t kSignature = 8, kFraming = 12;  // length, type, CRC
  const auto length_at = [&](std::size_t pos) {
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 4; ++k) v = (v << 8) | static_cast<unsigned char>(data[pos + k]);
    return std::size_t{v};
  };
  std::size_t pos = kSignature;
  bool dropped = false;
  std::string out(data.substr(0, std::min(kSignature, data.size())));
  while (pos + 8 <= data.size()) {  // a length and a type
    const std::size_t length = length_at(pos);
    const std::string_view type = data.substr(pos + 4, 4);
    if (pos + kFraming > data.size() || length > data.size() - pos - kFraming) {
      throw FormatError(name + ": byte " + std::to_string(pos) + ": truncated: the " +
                        std::string(type.substr(0, 4)) + " chunk claims " + std::to_string(length) +
                        " bytes, the file has " + std::to_string(data.size() - pos) +
                        " from there");
    }
    const bool empty_idat = length == 0 && type == "IDAT";
    if (!empty_idat) out.append(data.substr(pos, kFraming + length));
    dropped = dropped || empty_idat;
    pos += kFraming + length;
    if (type == "IEND") break;
  }
  if (!dropped) return data;
  out.append(data.substr(std::min(pos, data.size())));
  storage = std::move(out);
  return storage;
}

PointCloud decode_png(std::string_view file, const std::string& name, const PinholeIntrinsics& K,
                      const DepthImageSettings& settings, DepthImageReport* report) {
  K.validate();
  settings.validate();
  if (file.empty()) throw FormatError(name + ": empty file");
  std::string storage;
  const std::string_view data = checked_png_chunks(file, name, storage);
  if (data.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw FormatError(name + ": larger than the PNG decoder reads (2 GiB)");
  }
  const auto* bytes = reinterpret_cast<const stbi_uc*>(data.data());
  const int size = static_cast<int>(data.size());
  int width = 0, height = 0, channels = 0;
  if (stbi_info_from_memory(bytes, size, &width, &height, &channels) == 0) {
    throw FormatError(name + ": not a readable PNG depth image (" + stbi_failure_reason() + ")");
  }
  check_size(width, height, name);  // before decoding: the header alone may claim gigapixels
  if (stbi_is_16_bit_from_memory(bytes, size) == 0) {
    throw FormatError(name +
                      ": an 8-bit PNG; a depth image is 16-bit greyscale (an 8-bit one cannot "
                      "hold depth, it is likely a picture or a colour frame)");
  }
  if (channels != 1) {
    throw FormatError(name + ": a PNG with " + std::to_string(channels) +
                      " channels; a depth image has one (16-bit greyscale)");
  }
  check_compressed_size(width, height, data.size(), name);
  int w = 0, h = 0, c = 0;
  const std::unique_ptr<stbi_us, StbFree> pixels(
      stbi_load_16_from_memory(bytes, size, &w, &h, &c, 1));
  if (!pixels || w != width || h != height) {
    throw FormatError(name + ": cannot decode the PNG (" + stbi_failure_reason() + ")");
  }
  try {
    return depth_image_to_cloud(pixels.get(), w, h, K, settings, report);
  } catch (const InvalidInputError& e) {
    throw FormatError(name + ": " + e.what());
  }
}

// Numbers of a text separated by spaces, tabs, commas, semicolons or line breaks.
std::vector<double> numbers_of(std::string_view text, const std::string& name) {
  std::vector<double> out;
  std::size_t pos = 0;
  const auto separator = [](char ch) {
    return ch == ' ' || ch == '\t' || ch == ',' || ch == ';' || ch == '\r' || ch == '\n';
  };
  while (pos < text.size()) {
    while (pos < text.size() && separator(text[pos])) ++pos;
    std::size_t end = pos;
    while (end < text.size() && !separator(text[end])) ++end;
    if (end == pos) break;
    const std::string_view token = text.substr(pos, end - pos);
    double v = 0.0;
    if (!parse_number(token, v)) {
      const std::string shown(token.substr(0, 32));
      throw FormatError(name + ": expected a number, got '" + shown + "'");
    }
    if (out.size() > 16) throw FormatError(name + ": more numbers than intrinsics have");
    out.push_back(v);
    pos = end;
  }
  return out;
}

}  // namespace

void PinholeIntrinsics::validate() const {
  for (const auto& [value, what] : {std::pair{fx, "fx"}, std::pair{fy, "fy"}}) {
    if (!std::isfinite(value) || value <= 0.0 || value > kMaxFocal_px) {
      bad_setting(std::string("intrinsics: ") + what + " = " + number_text(value) +
                  " must be in (0, 1e9] pixels");
    }
  }
  for (const auto& [value, what] : {std::pair{cx, "cx"}, std::pair{cy, "cy"}}) {
    if (!std::isfinite(value) || std::abs(value) > kMaxFocal_px) {
      bad_setting(std::string("intrinsics: ") + what + " = " + number_text(value) +
                  " must be finite, in [-1e9, 1e9] pixels");
    }
  }
}

void DepthImageSettings::validate() const {
  if (!std::isfinite(depth_units_per_m) || depth_units_per_m < 0.0 ||
      depth_units_per_m > kMaxUnitsPerMetre) {
    bad_setting("depth_units_per_m = " + number_text(depth_units_per_m) +
                " must be 0 (the data's own) or in (0, 1e9] units per metre");
  }
  if (!std::isfinite(max_depth_m) || max_depth_m <= 0.0 || max_depth_m > kMaxDepthLimit_m) {
    bad_setting("max_depth_m = " + number_text(max_depth_m) + " must be in (0, 1e6] m");
  }
  if (!std::isfinite(min_depth_m) || min_depth_m < 0.0 || min_depth_m >= max_depth_m) {
    bad_setting("min_depth_m = " + number_text(min_depth_m) +
                " must be in [0, max_depth_m = " + number_text(max_depth_m) + ") m");
  }
  if (pixel_stride < 1 || pixel_stride > kMaxPixelStride) {
    bad_setting("pixel_stride = " + std::to_string(pixel_stride) + " must be in [1, 65536]");
  }
  if (border_px < 0 || border_px > kMaxPixelStride) {
    bad_setting("border_px = " + std::to_string(border_px) + " must be in [0, 65536] pixels");
  }
}

PinholeIntrinsics read_intrinsics(const std::filesystem::path& path) {
  const std::string name = path.string();
  const std::vector<char> bytes = read_whole_file(path, name);
  const std::vector<double> k = numbers_of(std::string_view(bytes.data(), bytes.size()), name);
  if (k.size() != 9) {
    throw FormatError(name + ": " + std::to_string(k.size()) +
                      " numbers; a camera matrix K has 9 (3 lines: fx 0 cx, 0 fy cy, 0 0 1)");
  }
  if (k[1] != 0.0 || k[3] != 0.0) {
    throw FormatError(name + ": K has skew or a rotated axis (K[0][1], K[1][0] must be 0)");
  }
  if (k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0) {
    throw FormatError(name + ": the last row of K must be 0 0 1");
  }
  const PinholeIntrinsics K{k[0], k[4], k[2], k[5]};
  try {
    K.validate();
  } catch (const InvalidSettingsError& e) {
    throw InvalidSettingsError(name + ": " + e.what());
  }
  return K;
}

PinholeIntrinsics parse_intrinsics(std::string_view text) {
  const std::string name = "intrinsics '" + std::string(text.substr(0, 64)) + "'";
  const std::vector<double> k = numbers_of(text, name);
  if (k.size() != 4) {
    throw FormatError(name + ": " + std::to_string(k.size()) +
                      " numbers; expected 4: fx,fy,cx,cy (pixels)");
  }
  const PinholeIntrinsics K{k[0], k[1], k[2], k[3]};
  K.validate();
  return K;
}

PointCloud read_depth_image(const std::filesystem::path& path, const PinholeIntrinsics& intrinsics,
                            const DepthImageSettings& settings, DepthImageReport* report) {
  intrinsics.validate();
  settings.validate();
  const std::string name = path.string();
  const std::vector<char> bytes = read_whole_file(path, name);
  return decode_png(std::string_view(bytes.data(), bytes.size()), name, intrinsics, settings,
                    report);
}

PointCloud read_depth_image_from_memory(std::span<const std::byte> bytes,
                                        const PinholeIntrinsics& intrinsics,
                                        const DepthImageSettings& settings,
                                        DepthImageReport* report, std::string_view name) {
  if (bytes.size() > kMaxFileBytes) {
    throw FormatError(std::string(name) + ": larger than the largest file read (" +
                      limit_text(kMaxFileBytes) + ")");
  }
  return decode_png(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
                    std::string(name), intrinsics, settings, report);
}

PointCloud depth_image_to_cloud(const std::uint16_t* depth, int width, int height,
                                const PinholeIntrinsics& intrinsics,
                                const DepthImageSettings& settings, DepthImageReport* report) {
  if (!depth) throw InvalidInputError("depth image: no pixel data");
  const double units =
      settings.depth_units_per_m > 0.0 ? settings.depth_units_per_m : kDefaultDepthUnitsPerMetre;
  return back_project(width, height, intrinsics, settings, report,
                      [&](std::size_t i) { return depth[i] / units; });
}

PointCloud depth_image_to_cloud(const float* depth_m, int width, int height,
                                const PinholeIntrinsics& intrinsics,
                                const DepthImageSettings& settings, DepthImageReport* report) {
  if (!depth_m) throw InvalidInputError("depth image: no pixel data");
  return back_project(width, height, intrinsics, settings, report,
                      [&](std::size_t i) { return static_cast<double>(depth_m[i]); });
}

}  // namespace sgdicp
