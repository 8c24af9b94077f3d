// Depth images: back-projection against hand-computed points, stride, the counts of dropped
// pixels, intrinsics parsing, hostile PNG files, and a real 7-Scenes frame against the points
// bench/make_sevenscenes_pairs.py wrote for it (decoded by Pillow, back-projected by numpy).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "sgdicp/core/error.hpp"
#include "sgdicp/io/depth_image.hpp"
#include "sgdicp/io/frame_source.hpp"
#include "sgdicp/io/io.hpp"
#include "sgdicp/metrics/trajectory_metrics.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

namespace fs = std::filesystem;

// ---- A minimal PNG writer (stored deflate blocks, no compression): the test's own encoder, so
// the files are independent of the decoder under test.

std::uint32_t crc32(const std::string& bytes) {
  std::uint32_t crc = 0xFFFFFFFFU;
  for (const char ch : bytes) {
    crc ^= static_cast<unsigned char>(ch);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320U & (0U - (crc & 1U)));
  }
  return crc ^ 0xFFFFFFFFU;
}

void put32(std::string& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8)
    out.push_back(static_cast<char>((v >> shift) & 0xFF));
}

void chunk(std::string& out, const std::string& type, const std::string& data) {
  put32(out, static_cast<std::uint32_t>(data.size()));
  const std::string body = type + data;
  out += body;
  put32(out, crc32(body));
}

std::string zlib_stored(const std::string& raw) {
  std::string out = "\x78\x01";
  std::size_t pos = 0;
  do {
    const std::size_t n = std::min<std::size_t>(65535, raw.size() - pos);
    out.push_back(pos + n == raw.size() ? '\x01' : '\x00');
    out.push_back(static_cast<char>(n & 0xFF));
    out.push_back(static_cast<char>(n >> 8));
    out.push_back(static_cast<char>(~n & 0xFF));
    out.push_back(static_cast<char>((~n >> 8) & 0xFF));
    out += raw.substr(pos, n);
    pos += n;
  } while (pos < raw.size());
  std::uint32_t a = 1, b = 0;
  for (const char ch : raw) {
    a = (a + static_cast<unsigned char>(ch)) % 65521U;
    b = (b + a) % 65521U;
  }
  put32(out, (b << 16) | a);
  return out;
}

// A PNG of `width` x `height` samples (big endian when 16-bit), `channels` samples per pixel
// (1 grey, 3 RGB), each pixel's samples all `values[i]`.
std::string png(int width, int height, const std::vector<std::uint16_t>& values, int bit_depth = 16,
                int channels = 1, std::uint32_t claimed_width = 0) {
  std::string ihdr;
  put32(ihdr, claimed_width ? claimed_width : static_cast<std::uint32_t>(width));
  put32(ihdr, static_cast<std::uint32_t>(height));
  ihdr += static_cast<char>(bit_depth);
  ihdr += static_cast<char>(channels == 1 ? 0 : 2);
  ihdr += std::string("\0\0\0", 3);
  std::string raw;
  for (int v = 0; v < height; ++v) {
    raw.push_back('\0');  // filter: none
    for (int u = 0; u < width; ++u) {
      const std::uint16_t d = values[static_cast<std::size_t>(v * width + u)];
      for (int c = 0; c < channels; ++c) {
        if (bit_depth == 16) raw.push_back(static_cast<char>(d >> 8));
        raw.push_back(static_cast<char>(d & 0xFF));
      }
    }
  }
  std::string out = "\x89PNG\r\n\x1a\n";
  chunk(out, "IHDR", ihdr);
  chunk(out, "IDAT", zlib_stored(raw));
  chunk(out, "IEND", "");
  return out;
}

fs::path write_file(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

constexpr PinholeIntrinsics kK{500.0, 480.0, 3.5, 2.0};

template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

// ---- Back-projection

TEST(DepthImage, PlaneAtTwoMetresGivesTheHandComputedPoints) {
  const int w = 8, h = 5;
  const std::vector<std::uint16_t> depth(w * h, 2000);  // 2 m in millimetres
  DepthImageReport report;
  const PointCloud cloud = depth_image_to_cloud(depth.data(), w, h, kK, {}, &report);
  ASSERT_EQ(cloud.size(), static_cast<std::size_t>(w * h));
  EXPECT_EQ(report.pixels, 40U);
  EXPECT_EQ(report.valid, 40U);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3f& p = cloud.points[static_cast<std::size_t>(v * w + u)];
      // x = (u - cx) z / fx, y = (v - cy) z / fy: e.g. pixel (0, 0) -> (-0.014, -0.008333, 2).
      EXPECT_EQ(p.x(), static_cast<float>((u - 3.5) * 2.0 / 500.0));
      EXPECT_EQ(p.y(), static_cast<float>((v - 2.0) * 2.0 / 480.0));
      EXPECT_EQ(p.z(), 2.0F);
    }
  }
  EXPECT_FLOAT_EQ(cloud.points[0].x(), -0.014F);
  EXPECT_FLOAT_EQ(cloud.points[0].y(), -1.0F / 120.0F);
}

TEST(DepthImage, TiltedPlaneInMetresStaysOnThePlane) {
  // Plane n . p = d with n = (0.3, -0.2, 1)/|.|, d = 1.5 m: the depth of pixel (u, v) is
  // z = d / (n . ((u - cx)/fx, (v - cy)/fy, 1)).
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  const double d = 1.5;
  const PinholeIntrinsics K{525.0, 525.0, 319.5, 239.5};
  const int w = 640, h = 480;
  std::vector<float> depth(static_cast<std::size_t>(w * h));
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3d ray((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
      depth[static_cast<std::size_t>(v * w + u)] = static_cast<float>(d / n.dot(ray));
    }
  }
  const PointCloud cloud = depth_image_to_cloud(depth.data(), w, h, K, {}, nullptr);
  ASSERT_EQ(cloud.size(), depth.size());
  double worst = 0.0;
  for (const auto& p : cloud.points) worst = std::max(worst, std::abs(n.dot(p.cast<double>()) - d));
  EXPECT_LT(worst, 1e-6);
}

// A w x h image whose pixel i (row by row) is 1000 + i millimetres deep: each point tells its
// pixel.
std::vector<std::uint16_t> numbered_depth(int w, int h) {
  std::vector<std::uint16_t> depth(static_cast<std::size_t>(w * h));
  for (int i = 0; i < w * h; ++i)
    depth[static_cast<std::size_t>(i)] = static_cast<std::uint16_t>(1000 + i);
  return depth;
}

// Back-projects numbered_depth(w, h) with `settings`: the pixels visited and the points are
// exactly the pixels `taken` (indices row by row), in that order.
PointCloud expect_pixels_taken(int w, int h, const DepthImageSettings& settings,
                               const std::vector<int>& taken) {
  const std::vector<std::uint16_t> depth = numbered_depth(w, h);
  DepthImageReport report;
  PointCloud cloud = depth_image_to_cloud(depth.data(), w, h, kK, settings, &report);
  EXPECT_EQ(report.pixels, taken.size());
  EXPECT_EQ(cloud.size(), taken.size());
  for (std::size_t k = 0; k < std::min(taken.size(), cloud.size()); ++k) {
    EXPECT_EQ(cloud.points[k].z(), static_cast<float>((1000 + taken[k]) / 1000.0)) << k;
  }
  return cloud;
}

TEST(DepthImage, StrideTakesEveryNthPixelFromTheTopLeft) {
  DepthImageSettings settings;
  settings.pixel_stride = 3;
  // 7 x 5: columns 0 3 6, rows 0 3.
  const PointCloud cloud = expect_pixels_taken(7, 5, settings, {0, 3, 6, 21, 24, 27});
  ASSERT_EQ(cloud.size(), 6U);
  EXPECT_EQ(cloud.points[4].x(), static_cast<float>((3 - 3.5) * 1.024 / 500.0));
}

TEST(DepthImage, BorderDropsABandAlongEachEdgeBeforeTheStride) {
  const int w = 9, h = 7;
  DepthImageSettings settings;
  settings.border_px = 2;
  std::vector<int> inside;  // columns 2-6 of rows 2-4
  for (int v = 2; v <= 4; ++v)
    for (int u = 2; u <= 6; ++u) inside.push_back(v * w + u);
  (void)expect_pixels_taken(w, h, settings, inside);
  // With a stride, the multiples of it within the border: columns 3 and 6 of row 3.
  settings.pixel_stride = 3;
  (void)expect_pixels_taken(w, h, settings, {3 * w + 3, 3 * w + 6});
  // Two borders as wide as the image's height leave nothing: refused, not an empty cloud.
  settings = {};
  settings.border_px = 4;
  const std::vector<std::uint16_t> depth = numbered_depth(w, h);
  const std::string why =
      error_of([&] { (void)depth_image_to_cloud(depth.data(), w, h, kK, settings, nullptr); });
  EXPECT_NE(why.find("border_px = 4 leaves no pixel of a 9 x 7"), std::string::npos) << why;
  settings.border_px = 3;  // columns 3-5 of row 3 left
  (void)expect_pixels_taken(w, h, settings, {3 * w + 3, 3 * w + 4, 3 * w + 5});
}

TEST(DepthImage, InvalidPixelsAreDroppedAndCounted) {
  // 0 (no reading), 65535 (65.5 m: beyond max_depth_m), 300 mm (below min_depth_m 0.5 m).
  const std::vector<std::uint16_t> depth{0, 1000, 65535, 300, 0, 2500};
  DepthImageSettings settings;
  settings.min_depth_m = 0.5;
  DepthImageReport report;
  const PointCloud cloud = depth_image_to_cloud(depth.data(), 3, 2, kK, settings, &report);
  EXPECT_EQ(cloud.size(), 2U);
  EXPECT_EQ(report.valid, 2U);
  EXPECT_EQ(report.invalid_zero, 2U);
  EXPECT_EQ(report.invalid_range, 2U);
  EXPECT_EQ(report.nonfinite, 0U);
  EXPECT_EQ(report.pixels, 6U);

  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> metres{nan, 1.0F, -2.0F, inf, 0.0F, 11.0F};
  const PointCloud from_float = depth_image_to_cloud(metres.data(), 3, 2, kK, {}, &report);
  EXPECT_EQ(from_float.size(), 1U);
  EXPECT_EQ(report.nonfinite, 2U);
  EXPECT_EQ(report.invalid_zero, 1U);
  EXPECT_EQ(report.invalid_range, 2U);  // negative, and beyond the default 10 m
}

TEST(DepthImage, DepthScaleIsUnitsPerMetre) {
  const std::vector<std::uint16_t> depth{5000};
  DepthImageSettings tum;
  tum.depth_units_per_m = 5000.0;
  const PointCloud cloud = depth_image_to_cloud(depth.data(), 1, 1, kK, tum, nullptr);
  ASSERT_EQ(cloud.size(), 1U);
  EXPECT_EQ(cloud.points[0].z(), 1.0F);
}

TEST(DepthImage, BadSettingsAndIntrinsicsAreTypedErrors) {
  const std::vector<std::uint16_t> depth{1000};
  const auto run = [&](const PinholeIntrinsics& K, const DepthImageSettings& s) {
    return error_of([&] { (void)depth_image_to_cloud(depth.data(), 1, 1, K, s, nullptr); });
  };
  EXPECT_NE(run({0.0, 500, 0, 0}, {}).find("fx"), std::string::npos);
  EXPECT_NE(run({500, -1, 0, 0}, {}).find("fy"), std::string::npos);
  EXPECT_NE(run({500, 500, std::nan(""), 0}, {}).find("cx"), std::string::npos);
  DepthImageSettings s;
  s.pixel_stride = 0;
  EXPECT_NE(run(kK, s).find("pixel_stride"), std::string::npos);
  s = {};
  s.border_px = -1;
  EXPECT_NE(run(kK, s).find("border_px"), std::string::npos);
  s = {};
  s.max_depth_m = std::nan("");
  EXPECT_NE(run(kK, s).find("max_depth_m"), std::string::npos);
  s = {};
  s.min_depth_m = 20.0;
  EXPECT_NE(run(kK, s).find("min_depth_m"), std::string::npos);
  s = {};
  s.depth_units_per_m = -1.0;
  EXPECT_NE(run(kK, s).find("depth_units_per_m"), std::string::npos);
  EXPECT_THROW((void)depth_image_to_cloud(depth.data(), 0, 1, kK, {}, nullptr), InvalidInputError);
  EXPECT_THROW(
      (void)depth_image_to_cloud(static_cast<const std::uint16_t*>(nullptr), 1, 1, kK, {}, nullptr),
      InvalidInputError);
}

// ---- Intrinsics

TEST(DepthIntrinsics, ParsesFourNumbers) {
  EXPECT_EQ(parse_intrinsics("585,585,320,240"), (PinholeIntrinsics{585, 585, 320, 240}));
  EXPECT_EQ(parse_intrinsics(" 525.0 , 525.5 319.5 239.5"),
            (PinholeIntrinsics{525.0, 525.5, 319.5, 239.5}));
  EXPECT_THROW((void)parse_intrinsics("585,585,320"), FormatError);
  EXPECT_THROW((void)parse_intrinsics("585,585,320,240,1"), FormatError);
  EXPECT_THROW((void)parse_intrinsics("585,abc,320,240"), FormatError);
  EXPECT_THROW((void)parse_intrinsics("nan,585,320,240"), InvalidSettingsError);
  EXPECT_THROW((void)parse_intrinsics("-585,585,320,240"), InvalidSettingsError);
}

TEST(DepthIntrinsics, ReadsACameraMatrixFile) {
  const test::TempDir dir;
  const fs::path good = write_file(dir.path() / "K.txt", "585 0 320\n0 586 240\n0 0 1\n");
  EXPECT_EQ(read_intrinsics(good), (PinholeIntrinsics{585, 586, 320, 240}));
  const fs::path skew = write_file(dir.path() / "skew.txt", "585 1 320\n0 586 240\n0 0 1\n");
  EXPECT_NE(error_of([&] { (void)read_intrinsics(skew); }).find("skew.txt"), std::string::npos);
  const fs::path short_file = write_file(dir.path() / "short.txt", "585 0 320\n0 586 240\n");
  EXPECT_THROW((void)read_intrinsics(short_file), FormatError);
  const fs::path zero = write_file(dir.path() / "zero.txt", "0 0 320\n0 586 240\n0 0 1\n");
  EXPECT_NE(error_of([&] { (void)read_intrinsics(zero); }).find("zero.txt: intrinsics: fx"),
            std::string::npos);
  EXPECT_THROW((void)read_intrinsics(dir.path() / "missing.txt"), IoError);
  EXPECT_THROW((void)read_intrinsics(dir.path()), IoError);
}

// ---- PNG files

TEST(DepthPng, ReadsA16BitGreyscalePng) {
  const test::TempDir dir;
  std::vector<std::uint16_t> depth(6 * 4, 1500);
  depth[5] = 0;
  depth[6] = 0x1234;  // both bytes matter: big endian in the file
  const fs::path path = write_file(dir.path() / "d.png", png(6, 4, depth));
  DepthImageReport report;
  const PointCloud cloud = read_depth_image(path, kK, {}, &report);
  EXPECT_EQ(report.width, 6);
  EXPECT_EQ(report.height, 4);
  EXPECT_EQ(report.invalid_zero, 1U);
  ASSERT_EQ(cloud.size(), 23U);
  EXPECT_EQ(cloud.points[5].z(), static_cast<float>(0x1234 / 1000.0));  // pixel 6
  EXPECT_EQ(cloud.points[0].z(), 1.5F);
}

TEST(DepthPng, EmptyIdatChunksAreSkipped) {
  // Legal PNG, no data in the empty chunk: the same points as without it.
  const std::vector<std::uint16_t> depth{1000, 0, 2000, 3000};
  const std::string plain = png(2, 2, depth);
  std::string empty_idat;
  chunk(empty_idat, "IDAT", "");
  const std::string with_empty = plain.substr(0, 33) + empty_idat + plain.substr(33);
  const auto read = [](const std::string& bytes) {
    const auto* data = reinterpret_cast<const std::byte*>(bytes.data());
    return read_depth_image_from_memory({data, bytes.size()}, kK).points;
  };
  EXPECT_EQ(read(with_empty), read(plain));
  EXPECT_EQ(read(plain).size(), 3U);
}

TEST(DepthPng, ChunkLongerThanTheFileIsTruncated) {
  // An IDAT chunk claiming 2 GiB in a file of ~80 bytes: refused before anything is allocated.
  const std::vector<std::uint16_t> depth{1000, 0, 2000, 3000};
  std::string bytes = png(2, 2, depth);
  bytes[33] = static_cast<char>(0x80);  // the IDAT length, first byte (at 33: after IHDR)
  const auto* data = reinterpret_cast<const std::byte*>(bytes.data());
  const std::string what = error_of([&] {
    (void)read_depth_image_from_memory({data, bytes.size()}, kK, {}, nullptr, "long");
  });
  EXPECT_NE(what.find("long: byte 33: truncated: the IDAT chunk claims 2147483"), std::string::npos)
      << what;
}

TEST(DepthPng, HostileFilesAreFormatErrorsNamingTheFile) {
  const test::TempDir dir;
  const std::vector<std::uint16_t> depth(4 * 3, 1000);
  const auto error = [&](const std::string& file, const std::string& bytes) {
    const fs::path path = write_file(dir.path() / file, bytes);
    try {
      (void)read_depth_image(path, kK);
    } catch (const FormatError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path.string()), std::string::npos) << what;
      return what;
    }
    return std::string("(no FormatError)");
  };
  EXPECT_NE(error("eight.png", png(4, 3, depth, 8)).find("8-bit"), std::string::npos);
  EXPECT_NE(error("rgb.png", png(4, 3, depth, 16, 3)).find("3 channels"), std::string::npos);
  const std::string good = png(4, 3, depth);
  EXPECT_NE(error("truncated.png", good.substr(0, good.size() - 30)).find("truncated: the IDAT"),
            std::string::npos);
  std::string corrupt = good;
  corrupt[41] = static_cast<char>(0xFF);  // inside the IDAT data: the zlib stream breaks
  EXPECT_NE(error("corrupt.png", corrupt).find("cannot decode"), std::string::npos);
  EXPECT_NE(error("empty.png", "").find("empty"), std::string::npos);
  EXPECT_NE(error("text.png", "585 0 320\n").find("not a readable PNG"), std::string::npos);
  EXPECT_THROW((void)read_depth_image(dir.path() / "missing.png", kK), IoError);
  EXPECT_THROW((void)read_depth_image(dir.path(), kK), IoError);
}

TEST(DepthPng, HugeHeaderIsRefusedBeforeDecoding) {
  // A header claiming 16384 x 16385 pixels, just over kMaxCloudPoints = 2^28, over one pixel of
  // data: refused from the header, before anything is decoded or allocated.
  const std::vector<std::uint16_t> depth(1, 1000);
  const std::string bytes = png(1, 1, depth, 16, 1, 16384);
  std::string ihdr = bytes.substr(12, 17);  // "IHDR" + 13 bytes; the height at 8..11
  ihdr[8] = 0;
  ihdr[9] = 0;
  ihdr[10] = 0x40;
  ihdr[11] = 0x01;
  std::string patched = bytes.substr(0, 12) + ihdr;
  put32(patched, crc32(ihdr));
  patched += bytes.substr(33);
  const test::TempDir dir;
  const fs::path path = write_file(dir.path() / "huge.png", patched);
  const std::string what = error_of([&] { (void)read_depth_image(path, kK); });
  EXPECT_NE(what.find(path.string() + ": 16384 x 16385 pixels, more than the largest cloud"),
            std::string::npos)
      << what;
}

TEST(DepthPng, HeaderClaimingMoreThanTheFileCanHoldIsTruncated) {
  // 4000 x 3000 16-bit pixels need 24 MB; deflate cannot expand a ~100-byte file that far.
  const std::vector<std::uint16_t> depth(1, 1000);
  const std::string bytes = png(1, 1, depth, 16, 1, 4000);
  std::string ihdr = bytes.substr(12, 17);
  ihdr[10] = 0x0B;  // height 3000 = 0x0BB8
  ihdr[11] = static_cast<char>(0xB8);
  std::string patched = bytes.substr(0, 12) + ihdr;
  put32(patched, crc32(ihdr));
  patched += bytes.substr(33);
  const auto* data = reinterpret_cast<const std::byte*>(patched.data());
  const std::string what = error_of([&] {
    (void)read_depth_image_from_memory({data, patched.size()}, kK, {}, nullptr, "claims.png");
  });
  EXPECT_NE(what.find("claims.png: truncated: its header claims 4000 x 3000"), std::string::npos)
      << what;
}

// ---- A real 7-Scenes frame

const fs::path kSevenScenes = fs::path(SGDICP_SHARED_DATA) / "sevenscenes_redkitchen";
const fs::path kGenerated = fs::path(SGDICP_GENERATED_DATA) / "sevenscenes_redkitchen";

TEST(DepthSevenScenes, FrameMatchesThePythonBackProjection) {
  const fs::path png_path = kSevenScenes / "frame-000000.depth.png";
  const fs::path ply_path = kGenerated / "frame-000000.ply";
  if (!fs::exists(png_path)) GTEST_SKIP() << "missing " << png_path;
  const PinholeIntrinsics K = read_intrinsics(kSevenScenes / "camera-intrinsics.txt");
  EXPECT_EQ(K, (PinholeIntrinsics{585, 585, 320, 240}));
  DepthImageReport report;
  const PointCloud cloud = read_depth_image(png_path, K, {}, &report);
  EXPECT_EQ(report.pixels, 640U * 480U);
  EXPECT_EQ(report.valid + report.invalid_zero, report.pixels);  // 0.8-4 m: nothing out of range
  EXPECT_GT(report.valid, 225000U);
  EXPECT_LT(report.valid, 296001U);
  if (!fs::exists(ply_path)) {
    GTEST_SKIP() << "missing " << ply_path << " (python3 bench/make_sevenscenes_pairs.py)";
  }
  const PointCloud python = read_point_cloud(ply_path).cloud;
  ASSERT_EQ(python.size(), cloud.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    worst = std::max(worst, static_cast<double>((cloud.points[i] - python.points[i]).norm()));
  }
  EXPECT_LT(worst, 1e-6);
}

// ---- TUM RGB-D sequences (frame_source.hpp)

// A TUM-layout folder: depth.txt (with the benchmark's comment header) listing three 4 x 3
// frames of depth 5000 (1 m at TUM's 5000 units per metre).
fs::path tum_folder(const test::TempDir& dir, const std::string& list) {
  fs::create_directories(dir.path() / "depth");
  const std::vector<std::uint16_t> depth(4 * 3, 5000);
  for (const char* name : {"1305031102.160407", "1305031102.194330", "1305031102.226738"}) {
    write_file(dir.path() / "depth" / (std::string(name) + ".png"), png(4, 3, depth));
  }
  write_file(dir.path() / "depth.txt", list);
  return dir.path();
}

const char* const kTumList =
    "# depth maps\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n# timestamp filename\n"
    "1305031102.160407 depth/1305031102.160407.png\n"
    "1305031102.194330 depth/1305031102.194330.png\r\n"
    "\n1305031102.226738 depth/1305031102.226738.png\n";

TEST(TumSequence, DepthListGivesFramesTimestampsAndTheTumDepthScale) {
  const test::TempDir dir;
  const fs::path folder = tum_folder(dir, kTumList);
  const FrameSource source = open_frame_source(folder, kK);
  EXPECT_EQ(source.layout, "tum");
  ASSERT_EQ(source.size(), 3U);
  EXPECT_EQ(source.frames[1], folder / "depth" / "1305031102.194330.png");
  ASSERT_EQ(source.timestamps_s.size(), 3U);
  EXPECT_DOUBLE_EQ(source.timestamps_s[2], 1305031102.226738);
  EXPECT_EQ(source.nominal_rate_hz, 30.0);
  EXPECT_EQ(source.read(0).points[0].z(), 1.0F);  // 5000 / 5000 units per metre
  DepthImageSettings millimetres;
  millimetres.depth_units_per_m = 1000.0;  // given: used as it is
  EXPECT_EQ(open_frame_source(folder, kK, millimetres).read(0).points[0].z(), 5.0F);
}

TEST(TumSequence, BadListsAndMissingIntrinsicsAreClearErrors) {
  const test::TempDir dir;
  const fs::path folder = tum_folder(dir, kTumList);
  EXPECT_NE(error_of([&] { (void)open_frame_source(folder); }).find("TUM"), std::string::npos);
  for (const auto& [list, what] :
       {std::pair<std::string, std::string>{"banana depth/a.png\n", "line 1"},
        {"1.0\n", "line 1"},
        {"# c\n2.0 depth/a.png\n1.0 depth/b.png\n", "line 3: timestamps must increase"},
        {"1.0 depth/a b.png\n", "line 1"},
        {"# only comments\n", "no frame listed"}}) {
    write_file(folder / "depth.txt", list);
    EXPECT_NE(error_of([&] { (void)open_frame_source(folder, kK); }).find(what), std::string::npos)
        << list;
  }
}

TEST(TumSequence, GroundTruthIsAssociatedByTimestamp) {
  // Ground truth at 100 Hz from t = 10.000 s; frames at 30 Hz, one beyond the truth's end.
  std::vector<double> truth;
  for (int k = 0; k < 50; ++k) truth.push_back(10.0 + 0.01 * k);
  const std::vector<double> frames{10.003, 10.036, 10.0449, 10.8};
  const auto matches = associate_timestamps(frames, truth);
  ASSERT_EQ(matches.size(), 4U);
  EXPECT_EQ(matches[0], std::optional<std::size_t>(0));
  EXPECT_EQ(matches[1], std::optional<std::size_t>(4));  // 10.04 is nearer than 10.03
  EXPECT_EQ(matches[2], std::optional<std::size_t>(4));
  EXPECT_FALSE(matches[3].has_value());  // 0.31 s after the last pose
  EXPECT_FALSE(associate_timestamps({10.003}, truth, 0.001)[0].has_value());
  EXPECT_THROW((void)associate_timestamps(frames, {2.0, 1.0}), InvalidInputError);
  EXPECT_THROW((void)associate_timestamps(frames, truth, -1.0), InvalidInputError);
}

}  // namespace
}  // namespace sgdicp
