// Tests of the point-cloud readers and writers: round trips, hand-written files of every
// variant, rejections of broken files (type and position in the message), and the real data.
#include <lzf.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <clocale>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <new>
#include <ostream>
#include <random>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <sys/stat.h>

#include <gtest/gtest.h>

#include "allocation_tracker.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

namespace sgdicp {
namespace {

namespace fs = std::filesystem;

const fs::path kSharedData = SGDICP_SHARED_DATA;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// ---------------------------------------------------------------------------------------------
// Helpers

// Builds binary file content in either byte order.
class Bytes {
 public:
  template <typename T>
  Bytes& le(T value) {
    return put(value, false);
  }
  template <typename T>
  Bytes& be(T value) {
    return put(value, true);
  }
  Bytes& text(std::string_view s) {
    data_.append(s);
    return *this;
  }
  [[nodiscard]] const std::string& str() const { return data_; }

 private:
  template <typename T>
  Bytes& put(T value, bool big_endian) {
    auto raw = std::bit_cast<std::array<char, sizeof(T)>>(value);
    if (big_endian != (std::endian::native == std::endian::big)) {
      std::reverse(raw.begin(), raw.end());
    }
    data_.append(raw.data(), raw.size());
    return *this;
  }
  std::string data_;
};

// A fresh directory per test, removed afterwards.
class IoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string test_name = info->name();
    std::replace(test_name.begin(), test_name.end(), '/', '_');  // parameterised test names
    dir_ = fs::temp_directory_path() /
           ("sgdicp_test_io_" + test_name + "_" + std::to_string(std::random_device{}()) + "_" +
            std::to_string(counter++));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  fs::path write(const std::string& file_name, std::string_view content) const {
    const fs::path path = dir_ / file_name;
    std::ofstream out(path, std::ios::binary);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    EXPECT_TRUE(out.good()) << path;
    return path;
  }

  fs::path dir_;
};

bool same_bits(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

// A coordinate of a read point in the file's frame: the readers store points from an origin
// (0 unless the first point lies beyond 16 km: georeferencing_origin in point_cloud.hpp).
double absolute(const PointCloud& cloud, std::size_t i, int k) {
  return static_cast<double>(cloud.points[i][k]) + cloud.origin_m[k];
}

void expect_points(const ReadResult& r, std::initializer_list<std::array<float, 3>> expected) {
  ASSERT_EQ(r.cloud.size(), expected.size());
  std::size_t i = 0;
  for (const auto& e : expected) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_FLOAT_EQ(static_cast<float>(absolute(r.cloud, i, k)), e[static_cast<std::size_t>(k)])
          << "point " << i << " coordinate " << k;
    }
    ++i;
  }
}

// Runs the reader and checks the exception type and that the message names the file and
// contains every given part (typically "line 7" or "byte 123").
template <typename E>
std::string expect_error(const fs::path& path, std::initializer_list<std::string_view> parts,
                         FileFormat format = FileFormat::automatic) {
  try {
    const auto r = read_point_cloud(path, format);
    ADD_FAILURE() << "no exception for " << path << " (" << r.cloud.size() << " points)";
  } catch (const E& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    for (const auto part : parts) {
      EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
    }
    return message;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type for " << path << ": " << e.what();
  }
  return {};
}

std::string lzf_block(const std::string& raw) {
  std::string out(raw.size() + raw.size() / 16 + 64, '\0');
  const unsigned int n = lzf_compress(raw.data(), static_cast<unsigned int>(raw.size()), out.data(),
                                      static_cast<unsigned int>(out.size()));
  EXPECT_GT(n, 0u);
  out.resize(n);
  return out;
}

std::string pcd_header(std::string_view fields, std::string_view size, std::string_view type,
                       std::string_view count, std::size_t width, std::size_t height,
                       std::string_view data) {
  std::ostringstream s;
  s << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " << fields << "\nSIZE "
    << size << "\nTYPE " << type << "\nCOUNT " << count << "\nWIDTH " << width << "\nHEIGHT "
    << height << "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << width * height << "\nDATA " << data
    << "\n";
  return s.str();
}

// Random points over many magnitudes, both signs, and the float extremes.
PointCloud random_cloud(std::size_t n) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<float> mantissa(-1.0f, 1.0f);
  std::uniform_int_distribution<int> exponent(-40, 40);
  std::uniform_real_distribution<float> metres(-1e4f, 1e4f);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const auto value = [&]() {
      return i % 2 == 0 ? metres(rng) : std::ldexp(mantissa(rng), exponent(rng));
    };
    const float x = value();
    const float y = value();
    const float z = value();
    cloud.points.emplace_back(x, y, z);
  }
  constexpr float kMax = std::numeric_limits<float>::max();
  constexpr float kMin = std::numeric_limits<float>::min();
  constexpr float kDenorm = std::numeric_limits<float>::denorm_min();
  cloud.points.emplace_back(kMax, -kMax, 0.0f);
  cloud.points.emplace_back(kMin, -kMin, -0.0f);
  cloud.points.emplace_back(kDenorm, -kDenorm, 123456789.0f);
  cloud.points.emplace_back(1e30f, -3.4e38f, 1e-30f);
  return cloud;
}

// ---------------------------------------------------------------------------------------------
// Format names

TEST(IoFormat, FromExtension) {
  EXPECT_EQ(format_from_extension("a/b.pcd"), FileFormat::pcd);
  EXPECT_EQ(format_from_extension("b.PLY"), FileFormat::ply);
  EXPECT_EQ(format_from_extension("000000.bin"), FileFormat::kitti_bin);
  EXPECT_EQ(format_from_extension("c.xyz"), FileFormat::xyz);
  EXPECT_EQ(format_from_extension("c.txt"), FileFormat::xyz);
  EXPECT_EQ(format_from_extension("c.csv"), FileFormat::xyz);
  EXPECT_EQ(format_from_extension("cloud.00000.vtk"), FileFormat::vtk);
  EXPECT_EQ(format_from_extension("frame.xyz.f32"), FileFormat::f32);
  EXPECT_THROW((void)format_from_extension("cloud.las"), FormatError);
  EXPECT_THROW((void)format_from_extension("cloud"), FormatError);
  EXPECT_EQ(to_string(FileFormat::pcd), "pcd");
  EXPECT_EQ(to_string(FileFormat::kitti_bin), "kitti_bin");
  EXPECT_EQ(to_string(FileFormat::f32), "f32");
}

// One name table for formats and encodings (io.hpp), read by to_string, the Python bindings and
// their messages.
TEST(IoFormat, NameTables) {
  EXPECT_EQ(to_string(FileFormat::automatic), "auto");
  EXPECT_EQ(parse_enum<FileFormat>("automatic"), FileFormat::automatic);
  EXPECT_EQ(parse_enum<FileFormat>("kitti-bin"), FileFormat::kitti_bin);
  EXPECT_EQ(name_list<FileFormat>(), "auto, pcd, ply, kitti_bin, xyz, vtk or f32");
  for (const std::string_view name : canonical_names<FileFormat>()) {
    EXPECT_EQ(to_string(parse_enum<FileFormat>(name)), name);
  }
  EXPECT_THROW((void)parse_enum<FileFormat>("las"), InvalidSettingsError);
  EXPECT_EQ(parse_enum<Encoding>("ascii"), Encoding::ascii);
  EXPECT_EQ(name_list<Encoding>(), "binary or ascii");
}

// ---------------------------------------------------------------------------------------------
// Round trips

struct RoundTripCase {
  std::string extension;
  Encoding encoding;
  std::string label;
};

// Named printing: gtest would otherwise dump the raw bytes, padding included.
void PrintTo(const RoundTripCase& c, std::ostream* os) {
  *os << c.label;
}

class RoundTrip : public IoTest, public ::testing::WithParamInterface<RoundTripCase> {};

TEST_P(RoundTrip, ReadBackIsBitwiseIdentical) {
  const auto& param = GetParam();
  const PointCloud cloud = random_cloud(2000);
  const fs::path path = dir_ / ("cloud" + param.extension);
  write_point_cloud(path, cloud, FileFormat::automatic, param.encoding);
  const ReadResult r = read_point_cloud(path);
  EXPECT_EQ(r.format, format_from_extension(path));
  EXPECT_EQ(r.points_in_file, cloud.size());
  EXPECT_EQ(r.non_finite_dropped, 0u);
  ASSERT_EQ(r.cloud.size(), cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(absolute(r.cloud, i, k), absolute(cloud, i, k))
          << "point " << i << " coordinate " << k << ": wrote " << cloud.points[i][k] << ", read "
          << r.cloud.points[i][k] << " from " << r.cloud.origin_m[k];
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Io, RoundTrip,
                         ::testing::Values(RoundTripCase{".ply", Encoding::binary, "ply_binary"},
                                           RoundTripCase{".ply", Encoding::ascii, "ply_ascii"},
                                           RoundTripCase{".pcd", Encoding::binary, "pcd_binary"},
                                           RoundTripCase{".pcd", Encoding::ascii, "pcd_ascii"},
                                           RoundTripCase{".xyz", Encoding::ascii, "xyz"}),
                         [](const auto& info) { return info.param.label; });

TEST_F(IoTest, WritesEmptyCloudAndExplicitFormat) {
  const fs::path path = dir_ / "empty.out";
  write_point_cloud(path, PointCloud{}, FileFormat::pcd, Encoding::binary);
  const ReadResult r = read_point_cloud(path, FileFormat::pcd);
  EXPECT_TRUE(r.cloud.empty());
  EXPECT_EQ(r.points_in_file, 0u);
}

TEST_F(IoTest, WriteErrors) {
  PointCloud cloud;
  cloud.points.emplace_back(1.0f, 2.0f, 3.0f);
  EXPECT_THROW(write_point_cloud(dir_ / "no_such_dir" / "a.ply", cloud), IoError);
  EXPECT_THROW(write_point_cloud(dir_ / "a.vtk", cloud), FormatError);
  EXPECT_THROW(write_point_cloud(dir_ / "a.unknown", cloud), FormatError);
  try {
    write_point_cloud(dir_, cloud, FileFormat::ply);  // a directory
    ADD_FAILURE() << "writing onto a directory did not throw";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(dir_.string()), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// PCD variants

TEST_F(IoTest, PcdAsciiWithExtraFields) {
  // x is not first, a 3-byte "_" padding field and a COUNT 4 field sit between the coordinates.
  const std::string text = pcd_header("normal_x x _ y z rgb hist", "4 4 1 4 4 4 4", "F F U F F F F",
                                      "1 1 3 1 1 1 4", 2, 1, "ascii") +
                           "0.5 1.5 0 0 0 -2.25 3e2 4.2e6 1 2 3 4\n"
                           "0.1 -7 1 2 3 8 9 0 0 0 0 0\n";
  const ReadResult r = read_point_cloud(write("extra.pcd", text));
  EXPECT_EQ(r.format, FileFormat::pcd);
  EXPECT_EQ(r.points_in_file, 2u);
  expect_points(r, {{1.5f, -2.25f, 300.0f}, {-7.0f, 8.0f, 9.0f}});
}

TEST_F(IoTest, PcdVersion5WithoutViewpoint) {
  const std::string text =
      "# .PCD v.5 - Point Cloud Data file format\nVERSION .5\nFIELDS x y z\nSIZE 4 4 4\n"
      "TYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3\r\n4 5 6\r\n";
  expect_points(read_point_cloud(write("v5.pcd", text)), {{1, 2, 3}, {4, 5, 6}});
}

TEST_F(IoTest, PcdAsciiDoubleCoordinates) {
  const std::string text =
      pcd_header("x y z intensity", "8 8 8 2", "F F F U", "1 1 1 1", 1, 1, "ascii") +
      "0.125 -1e3 12345.5 7\n";
  expect_points(read_point_cloud(write("f8.pcd", text)), {{0.125f, -1000.0f, 12345.5f}});
}

TEST_F(IoTest, PcdBinaryFloatWithExtraFields) {
  Bytes b;
  b.text(pcd_header("x y z intensity", "4 4 4 4", "F F F F", "1 1 1 1", 3, 1, "binary"));
  b.le(1.0f).le(2.0f).le(3.0f).le(0.5f);
  b.le(-4.0f).le(5.5f).le(-6.0f).le(0.25f);
  b.le(1e6f).le(-1e-6f).le(0.0f).le(1.0f);
  const ReadResult r = read_point_cloud(write("binary.pcd", b.str()));
  EXPECT_EQ(r.points_in_file, 3u);
  expect_points(r, {{1, 2, 3}, {-4, 5.5f, -6}, {1e6f, -1e-6f, 0}});
}

TEST_F(IoTest, PcdBinaryDoubleCoordinatesAndPadding) {
  // rgb (U4) first, then z y x as F8 in reverse order, then a 2-value padding field.
  Bytes b;
  b.text(pcd_header("rgb z y x _", "4 8 8 8 1", "U F F F U", "1 1 1 1 2", 2, 1, "binary"));
  b.le(std::uint32_t{0xffffff}).le(3.0).le(2.0).le(1.0).le(std::uint16_t{0});
  b.le(std::uint32_t{0}).le(-0.5).le(1e10).le(-1e-10).le(std::uint16_t{0});
  expect_points(read_point_cloud(write("f8.pcd", b.str())), {{1, 2, 3}, {-1e-10f, 1e10f, -0.5f}});
}

TEST_F(IoTest, PcdBinaryCompressedOrganisedWithNaN) {
  // 2 x 2 organised cloud, one NaN pixel; structure of arrays: x x x x, y y y y, z..., rgba....
  Bytes raw;
  for (const float x : {1.0f, kNaN, 3.0f, 4.0f}) raw.le(x);
  for (const float y : {10.0f, kNaN, 30.0f, 40.0f}) raw.le(y);
  for (const float z : {100.0f, kNaN, 300.0f, 400.0f}) raw.le(z);
  for (std::uint32_t c = 0; c < 4; ++c) raw.le(c * 0x01010101u);
  const std::string block = lzf_block(raw.str());
  Bytes b;
  b.text(pcd_header("x y z rgba", "4 4 4 4", "F F F U", "1 1 1 1", 2, 2, "binary_compressed"));
  b.le(static_cast<std::uint32_t>(block.size())).le(static_cast<std::uint32_t>(raw.str().size()));
  b.text(block);
  const ReadResult r = read_point_cloud(write("compressed.pcd", b.str()));
  EXPECT_EQ(r.points_in_file, 4u);
  EXPECT_EQ(r.non_finite_dropped, 1u);
  expect_points(r, {{1, 10, 100}, {3, 30, 300}, {4, 40, 400}});
}

TEST_F(IoTest, PcdBinaryCompressedDoubleCoordinates) {
  Bytes raw;
  for (const double v : {0.5, -1.5}) raw.le(v);     // x
  for (const float v : {7.0f, 8.0f}) raw.le(v);     // intensity
  for (const double v : {2.5, 1e20}) raw.le(v);     // y
  for (const double v : {-3.25, 1e300}) raw.le(v);  // z: 1e300 overflows float -> dropped
  const std::string block = lzf_block(raw.str());
  Bytes b;
  b.text(pcd_header("x intensity y z", "8 4 8 8", "F F F F", "1 1 1 1", 2, 1, "binary_compressed"));
  b.le(static_cast<std::uint32_t>(block.size())).le(static_cast<std::uint32_t>(raw.str().size()));
  b.text(block);
  const ReadResult r = read_point_cloud(write("compressed_f8.pcd", b.str()));
  EXPECT_EQ(r.non_finite_dropped, 1u);
  expect_points(r, {{0.5f, 2.5f, -3.25f}});
}

TEST_F(IoTest, PcdZeroPoints) {
  const ReadResult r = read_point_cloud(
      write("zero.pcd", pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 0, 1, "binary")));
  EXPECT_TRUE(r.cloud.empty());
  EXPECT_EQ(r.points_in_file, 0u);
}

// ---------------------------------------------------------------------------------------------
// PLY variants

TEST_F(IoTest, PlyAsciiWithFacesAndExtraProperties) {
  const std::string text =
      "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\n"
      "element face 1\r\nproperty list uchar int vertex_indices\r\n"
      "element vertex 3\r\nproperty double y\r\nproperty uchar red\r\nproperty double x\r\n"
      "property list uint8 float32 weights\r\nproperty float z\r\n"
      "element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\n"
      "end_header\r\n"
      "3 0 1 2\r\n"
      "2.5 255 1.5 0 -3\r\n"
      "-1e2 0 4 2 0.5 0.25 7\r\n"
      "0 12 0 1 9 0\r\n"
      "0 1\r\n";
  const ReadResult r = read_point_cloud(write("faces.ply", text));
  EXPECT_EQ(r.format, FileFormat::ply);
  EXPECT_EQ(r.points_in_file, 3u);
  expect_points(r, {{1.5f, 2.5f, -3.0f}, {4.0f, -100.0f, 7.0f}, {0.0f, 0.0f, 0.0f}});
}

// A binary PLY with double x y z, extra properties and a face element before and after vertex.
std::string binary_ply(bool big_endian) {
  Bytes b;
  b.text(std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
         " 1.0\nelement face 2\nproperty list uchar int vertex_indices\n"
         "element vertex 2\nproperty float64 x\nproperty uchar red\nproperty double y\n"
         "property short id\nproperty double z\n"
         "element face2 1\nproperty list ushort uint idx\nproperty float quality\n"
         "end_header\n");
  const auto put = [&](auto v) { big_endian ? b.be(v) : b.le(v); };
  put(std::uint8_t{3});
  for (const std::int32_t i : {0, 1, 2}) put(i);
  put(std::uint8_t{0});  // an empty list
  put(1.5);
  put(std::uint8_t{200});
  put(-2.25);
  put(std::int16_t{-7});
  put(1e5);
  put(-0.125);
  put(std::uint8_t{0});
  put(3.0);
  put(std::int16_t{8});
  put(4.0);
  put(std::uint16_t{2});
  put(std::uint32_t{0});
  put(std::uint32_t{1});
  put(0.5f);
  return b.str();
}

TEST_F(IoTest, PlyBinaryLittleEndian) {
  const ReadResult r = read_point_cloud(write("le.ply", binary_ply(false)));
  EXPECT_EQ(r.points_in_file, 2u);
  expect_points(r, {{1.5f, -2.25f, 1e5f}, {-0.125f, 3.0f, 4.0f}});
}

TEST_F(IoTest, PlyBinaryBigEndian) {
  const ReadResult r = read_point_cloud(write("be.ply", binary_ply(true)));
  expect_points(r, {{1.5f, -2.25f, 1e5f}, {-0.125f, 3.0f, 4.0f}});
}

TEST_F(IoTest, PlyBinaryIntegerCoordinatesAndVertexList) {
  // Integer coordinates, and a list inside the vertex element (records of varying size).
  Bytes b;
  b.text(
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty int16 x\n"
      "property list uchar uint16 neighbours\nproperty int y\nproperty uint8 z\nend_header\n");
  b.le(std::int16_t{-3}).le(std::uint8_t{2}).le(std::uint16_t{1}).le(std::uint16_t{2});
  b.le(std::int32_t{100000}).le(std::uint8_t{250});
  b.le(std::int16_t{5}).le(std::uint8_t{0}).le(std::int32_t{-1}).le(std::uint8_t{0});
  expect_points(read_point_cloud(write("int.ply", b.str())), {{-3, 100000, 250}, {5, -1, 0}});
}

// ---------------------------------------------------------------------------------------------
// Headerless binary, text and VTK

TEST_F(IoTest, KittiBin) {
  Bytes b;
  b.le(1.0f).le(2.0f).le(3.0f).le(0.5f).le(-4.0f).le(-5.0f).le(-6.0f).le(0.0f);
  const ReadResult r = read_point_cloud(write("000000.bin", b.str()));
  EXPECT_EQ(r.format, FileFormat::kitti_bin);
  EXPECT_EQ(r.points_in_file, 2u);
  expect_points(r, {{1, 2, 3}, {-4, -5, -6}});
}

TEST_F(IoTest, F32) {
  Bytes b;
  b.le(1.0f).le(2.0f).le(3.0f).le(-4.0f).le(-5.0f).le(-6.0f);
  const ReadResult r = read_point_cloud(write("frame.xyz.f32", b.str()));
  EXPECT_EQ(r.format, FileFormat::f32);
  expect_points(r, {{1, 2, 3}, {-4, -5, -6}});
}

TEST_F(IoTest, XyzSeparatorsCommentsAndBlankLines) {
  const std::string text =
      "# a comment\n"
      "\n"
      "1 2 3\n"
      "  4\t5   6  extra columns 7\r\n"
      "7,8,9\n"
      "-3.5376 , 0.639553 , -1.37678 , -0.06,0.17,0.98\n"
      "10;11;12;13\n"
      "   # indented comment\n"
      "+1.5e1 -2E-1 .5";  // no final newline
  const ReadResult r = read_point_cloud(write("mixed.xyz", text));
  EXPECT_EQ(r.format, FileFormat::xyz);
  EXPECT_EQ(r.points_in_file, 6u);
  expect_points(r, {{1, 2, 3},
                    {4, 5, 6},
                    {7, 8, 9},
                    {-3.5376f, 0.639553f, -1.37678f},
                    {10, 11, 12},
                    {15, -0.2f, 0.5f}});
}

TEST_F(IoTest, XyzHeaderLine) {
  const ReadResult r =
      read_point_cloud(write("car.csv", "x,y,z,nx,ny,nz\n1,2,3,0,0,1\n4,5,6,0,1,0\n"));
  expect_points(r, {{1, 2, 3}, {4, 5, 6}});
  EXPECT_EQ(r.points_in_file, 2u);
}

TEST_F(IoTest, XyzHeaderNamesColumnsInAnotherPosition) {
  const ReadResult r =
      read_point_cloud(write("cols.txt", "id; intensity; Z; \"Y\"; X\n7;0.5;3;2;1\n8;0.5;6;5;4\n"));
  expect_points(r, {{1, 2, 3}, {4, 5, 6}});
}

TEST_F(IoTest, XyzHeaderWithoutXyzNamesUsesFirstColumns) {
  const ReadResult r = read_point_cloud(write("h.txt", "a b c d\n1 2 3 4\n"));
  expect_points(r, {{1, 2, 3}});
}

TEST_F(IoTest, VtkPointsInAnyGrouping) {
  const std::string text =
      "# vtk DataFile Version 3.0\n"
      "some title\n"
      "ASCII\n"
      "DATASET POLYDATA\n"
      "POINTS 4 float\n"
      "1 2 3 4 5\n"
      "6\n"
      "7 8\n"
      "9 -1e1 11 12\n"
      "VERTICES 4 8\n1 0\n1 1\n1 2\n1 3\n"
      "POINT_DATA 4\nSCALARS s float\nLOOKUP_TABLE default\n0 0 0 0\n";
  const ReadResult r = read_point_cloud(write("cloud.vtk", text));
  EXPECT_EQ(r.format, FileFormat::vtk);
  EXPECT_EQ(r.points_in_file, 4u);
  expect_points(r, {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}, {-10, 11, 12}});
}

TEST_F(IoTest, VtkDouble) {
  const std::string text =
      "# vtk DataFile Version 2.0\n\nascii\nDATASET POLYDATA\nPOINTS 1 double\n0.1 0.2 0.3\n";
  expect_points(read_point_cloud(write("d.vtk", text)), {{0.1f, 0.2f, 0.3f}});
}

TEST_F(IoTest, ExplicitFormatOverridesExtension) {
  const ReadResult r = read_point_cloud(write("points.dat", "1 2 3\n"), FileFormat::xyz);
  EXPECT_EQ(r.format, FileFormat::xyz);
  expect_points(r, {{1, 2, 3}});
}

// ---------------------------------------------------------------------------------------------
// Non-finite values

TEST_F(IoTest, NonFiniteTextPointsAreDroppedAndCounted) {
  const std::string text = "1 2 3\nnan 0 0\n0 inf 0\n0 0 -inf\n-nan 1 1\n1e39 0 0\n4 5 6\n";
  const ReadResult r = read_point_cloud(write("nan.xyz", text));
  EXPECT_EQ(r.points_in_file, 7u);
  EXPECT_EQ(r.non_finite_dropped, 5u);
  expect_points(r, {{1, 2, 3}, {4, 5, 6}});
}

TEST_F(IoTest, NonFiniteBinaryPointsAreDroppedAndCounted) {
  Bytes b;
  b.le(1.0f).le(2.0f).le(3.0f).le(0.0f);
  b.le(kNaN).le(2.0f).le(3.0f).le(0.0f);
  b.le(1.0f).le(-kInf).le(3.0f).le(0.0f);
  b.le(1.0f).le(2.0f).le(kInf).le(0.0f);
  b.le(7.0f).le(8.0f).le(9.0f).le(kNaN);  // a NaN intensity does not matter
  const ReadResult r = read_point_cloud(write("nan.bin", b.str()));
  EXPECT_EQ(r.points_in_file, 5u);
  EXPECT_EQ(r.non_finite_dropped, 3u);
  expect_points(r, {{1, 2, 3}, {7, 8, 9}});
}

TEST_F(IoTest, NonFinitePcdAsciiAndPly) {
  const std::string pcd = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 2, 2, "ascii") +
                          "nan nan nan\n1 2 3\n"
                          "nan nan nan\n4 5 6\n";
  const ReadResult a = read_point_cloud(write("nan.pcd", pcd));
  EXPECT_EQ(a.non_finite_dropped, 2u);
  EXPECT_EQ(a.points_in_file, 4u);
  expect_points(a, {{1, 2, 3}, {4, 5, 6}});

  Bytes b;
  b.text(
      "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double x\n"
      "property double y\nproperty double z\nend_header\n");
  b.be(1.0).be(2.0).be(std::numeric_limits<double>::quiet_NaN()).be(4.0).be(5.0).be(6.0);
  const ReadResult p = read_point_cloud(write("nan.ply", b.str()));
  EXPECT_EQ(p.non_finite_dropped, 1u);
  expect_points(p, {{4, 5, 6}});
}

// ---------------------------------------------------------------------------------------------
// Rejections

TEST_F(IoTest, RejectsTruncatedBinaryPcd) {
  const std::string header = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 100, 1, "binary");
  const std::string content = header + std::string(1000, '\0');
  expect_error<FormatError>(write("t.pcd", content),
                            {"byte " + std::to_string(header.size()), "need 1200", "have 1000"});
}

TEST_F(IoTest, RejectsTruncatedBinaryPly) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  expect_error<FormatError>(write("t.ply", header + std::string(100, '\0')),
                            {"byte " + std::to_string(header.size()), "need 120", "have 100"});
}

TEST_F(IoTest, RejectsTruncatedPlyListElement) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n";
  Bytes b;
  b.text(header).le(1.0f).le(2.0f).le(3.0f).le(std::uint8_t{3}).le(std::int32_t{0});
  expect_error<FormatError>(write("face.ply", b.str()),
                            {"byte " + std::to_string(header.size() + 13), "face"});
}

TEST_F(IoTest, RejectsTruncatedAsciiPly) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n1 2 3\n4 5 6\n7 8\n";
  expect_error<FormatError>(write("t.ply", text), {"line 10", "record 3 of 3"});
}

TEST_F(IoTest, RejectsTruncatedCompressedPcd) {
  Bytes raw;
  for (int i = 0; i < 300; ++i) raw.le(static_cast<float>(i % 7));
  const std::string block = lzf_block(raw.str());
  const std::string header =
      pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 100, 1, "binary_compressed");
  Bytes b;
  b.text(header);
  b.le(static_cast<std::uint32_t>(block.size())).le(static_cast<std::uint32_t>(raw.str().size()));
  b.text(block.substr(0, block.size() / 2));
  expect_error<FormatError>(write("t.pcd", b.str()),
                            {"byte " + std::to_string(header.size() + 8), "truncated"});
  // Not even the two sizes.
  expect_error<FormatError>(write("t2.pcd", header + "abc"),
                            {"byte " + std::to_string(header.size()), "truncated"});
}

TEST_F(IoTest, RejectsCorruptLzfData) {
  Bytes raw;
  for (int i = 0; i < 300; ++i) raw.le(static_cast<float>(i % 7));
  std::string block = lzf_block(raw.str());
  block[0] = '\x3f';  // a back reference before the start of the output
  const std::string header =
      pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 100, 1, "binary_compressed");
  Bytes b;
  b.text(header);
  b.le(static_cast<std::uint32_t>(block.size())).le(static_cast<std::uint32_t>(raw.str().size()));
  b.text(block);
  expect_error<FormatError>(write("corrupt.pcd", b.str()),
                            {"byte " + std::to_string(header.size() + 8), "LZF"});
}

TEST_F(IoTest, RejectsCompressedSizeMismatch) {
  Bytes raw;
  for (int i = 0; i < 300; ++i) raw.le(static_cast<float>(i));
  const std::string block = lzf_block(raw.str());
  const std::string header =
      pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 100, 1, "binary_compressed");
  Bytes b;
  b.text(header);
  b.le(static_cast<std::uint32_t>(block.size())).le(std::uint32_t{1300});
  b.text(block);
  expect_error<FormatError>(write("size.pcd", b.str()),
                            {"byte " + std::to_string(header.size() + 4), "1300", "1200"});
}

TEST_F(IoTest, RejectsPcdWithoutZ) {
  const std::string text =
      "VERSION 0.7\nFIELDS x y intensity\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\n"
      "HEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n";
  expect_error<FormatError>(write("noz.pcd", text), {"line 2", "'z'"});
}

TEST_F(IoTest, RejectsPcdPointsNotWidthTimesHeight) {
  const std::string text =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 640\nHEIGHT 480\n"
      "POINTS 1000\nDATA ascii\n1 2 3\n";
  expect_error<FormatError>(write("wh.pcd", text), {"line 8", "POINTS 1000", "640", "480"});
}

TEST_F(IoTest, RejectsPcdHeaderErrors) {
  expect_error<FormatError>(write("size.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4\n"),
                            {"line 3", "SIZE"});
  expect_error<FormatError>(write("key.pcd", "VERSION 0.7\nFIELDS x y z\nCOLOR 1\n"),
                            {"line 3", "COLOR"});
  expect_error<FormatError>(
      write("data.pcd", pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 1, 1, "zip")),
      {"line 11", "zip"});
  expect_error<FormatError>(
      write("nodata.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"),
      {"line 4", "DATA"});
  expect_error<FormatError>(
      write("int.pcd", pcd_header("x y z", "4 4 4", "I F F", "1 1 1", 1, 1, "ascii") + "1 2 3\n"),
      {"line 5", "'x'"});
  expect_error<FormatError>(
      write("values.pcd", pcd_header("x y z rgb", "4 4 4 4", "F F F F", "1 1 1 1", 2, 1, "ascii") +
                              "1 2 3 4\n1 2 3\n"),
      {"line 13", "expected 4 values, got 3"});
  expect_error<FormatError>(
      write("more.pcd",
            pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 1, 1, "ascii") + "1 2 3\n4 5 6\n"),
      {"line 13", "more data"});
  expect_error<FormatError>(
      write("nan.pcd", pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 1, 1, "ascii") + "1 two 3\n"),
      {"line 12", "'two'"});
}

TEST_F(IoTest, RejectsHeadersLyingAboutThePointCount) {
  // Each would need gigabytes (within the largest cloud read); each must fail on the bounds
  // check, not on an allocation.
  const std::string pcd =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
      "WIDTH 200000000\nHEIGHT 1\nPOINTS 200000000\nDATA binary\n";
  expect_error<FormatError>(write("lie.pcd", pcd + std::string(1000, '\x01')),
                            {"byte " + std::to_string(pcd.size()), "need 2400000000", "have 1000"});

  const std::string ascii =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
      "WIDTH 200000000\nHEIGHT 1\nPOINTS 200000000\nDATA ascii\n";
  expect_error<FormatError>(write("lie_ascii.pcd", ascii + "1 2 3\n"),
                            {"line 10", "expected 200000000 points"});

  const std::string compressed =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
      "WIDTH 250000000\nHEIGHT 1\nPOINTS 250000000\nDATA binary_compressed\n";
  Bytes c;
  c.text(compressed)
      .le(std::uint32_t{100})
      .le(std::uint32_t{3000000000u})
      .text(std::string(100, 'a'));
  expect_error<FormatError>(write("lie_compressed.pcd", c.str()),
                            {"byte " + std::to_string(compressed.size() + 4), "impossible"});

  const std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 200000000\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n";
  expect_error<FormatError>(write("lie.ply", ply + std::string(1000, '\x01')),
                            {"byte " + std::to_string(ply.size())});

  const std::string faces =
      "ply\nformat binary_little_endian 1.0\nelement face 4000000000\n"
      "property list uint int idx\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  Bytes f;
  f.text(faces).le(std::uint32_t{4000000000u}).le(0).le(0);
  expect_error<FormatError>(write("lie_faces.ply", f.str()),
                            {"byte " + std::to_string(faces.size() + 4), "face"});

  expect_error<FormatError>(write("lie.vtk",
                                  "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n"
                                  "POINTS 200000000 float\n1 2 3\n"),
                            {"line 6", "200000000 points"});
}

// A 4 MB block of garbage whose header claims 88 x its size (the most LZF can expand), as in
// issue 11: rejected by walking the block, before the 350 MB output is allocated.
std::string hostile_compressed_pcd(std::uint64_t points) {
  std::mt19937 rng(7);
  std::string garbage(4'000'000, '\0');
  for (char& c : garbage) c = static_cast<char>(rng());
  garbage[0] = '\x1f';  // a literal run first, so that decompressing would get going
  const std::string header =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " +
      std::to_string(points) + "\nHEIGHT 1\nDATA binary_compressed\n";
  Bytes b;
  b.text(header)
      .le(static_cast<std::uint32_t>(garbage.size()))
      .le(static_cast<std::uint32_t>(points * 12))
      .text(garbage);
  return b.str();
}

TEST_F(IoTest, GarbageCompressedPcdFailsWithoutAllocatingItsClaim) {
  const std::uint64_t points = 4'000'000 * 88 / 12;  // 352 MB claimed
  const std::string pcd = hostile_compressed_pcd(points);
  const auto* data = reinterpret_cast<const std::byte*>(pcd.data());
  reset_largest_allocation();
  EXPECT_THROW((void)read_point_cloud_from_memory({data, pcd.size()}, FileFormat::pcd),
               FormatError);
  EXPECT_LT(largest_allocation(), std::size_t{1} << 20);

  const fs::path path = write("hostile.pcd", pcd);
  reset_largest_allocation();
  expect_error<FormatError>(path, {"corrupt LZF data"});
  EXPECT_LT(largest_allocation(), pcd.size() + (std::size_t{1} << 20));  // the file copy

  // Claims beyond what LZF can produce from 4 MB fail on the header alone.
  reset_largest_allocation();
  expect_error<FormatError>(write("claim.pcd", hostile_compressed_pcd(std::uint64_t{1} << 28)),
                            {"3221225472", "impossible for 4000000 bytes"});
  EXPECT_LT(largest_allocation(), pcd.size() + (std::size_t{1} << 20));
}

TEST_F(IoTest, LzfBlockDecodingToAnotherSizeIsRejectedBeforeDecompressing) {
  Bytes raw;
  std::mt19937 rng(3);
  for (int i = 0; i < 3000; ++i) raw.le(static_cast<float>(rng() % 1000));
  const std::string block = lzf_block(raw.str());
  // The header claims twice the points: still within 88 x, but the block says otherwise.
  const std::string header =
      pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 2000, 1, "binary_compressed");
  Bytes b;
  b.text(header).le(static_cast<std::uint32_t>(block.size())).le(std::uint32_t{24000});
  b.text(block);
  reset_largest_allocation();
  expect_error<FormatError>(write("short.pcd", b.str()), {"decompress to 12000 bytes", "24000"});
  EXPECT_LT(largest_allocation(), 20000u);
}

TEST_F(IoTest, CloudsBeyondTheLargestAreRejectedNamingTheLimit) {
  const std::string limit = std::to_string(kMaxCloudPoints);
  EXPECT_EQ(limit, "268435456");
  const std::string pcd =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
      "WIDTH 4000000000\nHEIGHT 1\nPOINTS 4000000000\nDATA binary\n";
  expect_error<FormatError>(write("big.pcd", pcd + std::string(1000, '\x01')),
                            {"line 8", "4000000000 points exceed", limit});
  const std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 268435457\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n";
  expect_error<FormatError>(write("big.ply", ply + std::string(1000, '\x01')),
                            {"line 3", "268435457 points exceed", limit});
  // The real count, not one wrapped by a multiplication.
  expect_error<FormatError>(write("big.vtk",
                                  "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n"
                                  "POINTS 18446744073709551615 float\n1 2 3\n"),
                            {"line 5", "18446744073709551615 points exceed", limit});
}

TEST_F(IoTest, NonRegularFilesAreRejectedWithAMessage) {
  if (!fs::exists("/dev/zero")) GTEST_SKIP() << "no /dev/zero";
  const fs::path zero = dir_ / "zero.bin";
  fs::create_symlink("/dev/zero", zero);
  expect_error<IoError>(zero, {"a character device", "only regular files"});
  const fs::path fifo = dir_ / "fifo.xyz";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expect_error<IoError>(fifo, {"a FIFO"});  // and does not block waiting for a writer
}

TEST_F(IoTest, FilesBeyondTheLargestAreRejectedBeforeReading) {
  const fs::path path = write("huge.f32", "");
  std::error_code ec;
  fs::resize_file(path, kMaxFileBytes + 12, ec);  // sparse: no disk space used
  if (ec) GTEST_SKIP() << "cannot make a sparse file: " << ec.message();
  reset_largest_allocation();
  expect_error<IoError>(path, {"larger than the largest file read", "17179869184 bytes = 16 GiB"});
  EXPECT_LT(largest_allocation(), std::size_t{1} << 20);
}

TEST_F(IoTest, RejectsPlyWithoutVertexElement) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n3 0 1 2\n";
  expect_error<FormatError>(write("novertex.ply", text), {"line 5", "vertex"});
}

TEST_F(IoTest, RejectsPlyBadFormatLine) {
  expect_error<FormatError>(
      write("format.ply", "ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n"),
      {"line 2", "format"});
  expect_error<FormatError>(
      write("version.ply", "ply\nformat ascii 2.0\nelement vertex 0\nend_header\n"),
      {"line 2", "format"});
}

TEST_F(IoTest, RejectsPlyHeaderErrors) {
  expect_error<FormatError>(write("magic.ply", "PLY file\nformat ascii 1.0\n"), {"line 1"});
  expect_error<FormatError>(
      write("noz.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            "end_header\n1 2\n"),
      {"line 3", "'z'"});
  expect_error<FormatError>(
      write("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\n"),
      {"line 4", "float128"});
  expect_error<FormatError>(
      write("noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"),
      {"line 4", "end_header"});
  expect_error<FormatError>(
      write("extra.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n1 2 3\n4\n"),
      {"line 9", "after the last element"});
  expect_error<FormatError>(
      write("bad.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n1 2 zz\n"),
      {"line 8", "'zz'"});
}

TEST_F(IoTest, RejectsKittiBinOfWrongSize) {
  const std::string message =
      expect_error<FormatError>(write("bad.bin", std::string(1000, '\0')), {"byte 992", "1000"});
  EXPECT_NE(message.find("16"), std::string::npos) << message;
  expect_error<FormatError>(write("bad.f32", std::string(100, '\0')), {"byte 96", "100"});
}

TEST_F(IoTest, RejectsXyzLineWithTwoNumbers) {
  expect_error<FormatError>(write("two.xyz", "1 2 3\n4 5 6\n# c\n7 8\n9 10 11\n"),
                            {"line 4", "expected 3 numbers, got 2"});
}

TEST_F(IoTest, RejectsXyzGarbageInTheMiddle) {
  expect_error<FormatError>(write("garbage.csv", "x,y,z\n1,2,3\nhello world\n4,5,6\n"),
                            {"line 3", "'hello'"});
  expect_error<FormatError>(write("garbage2.txt", "1 2 3\n4 5 6abc\n"), {"line 2", "'6abc'"});
  // A second header-like line is not a header any more.
  expect_error<FormatError>(write("header2.txt", "a b c\nx y z\n1 2 3\n"), {"line 2", "'x'"});
}

TEST_F(IoTest, RejectsVtkWithFewerNumbersThanDeclared) {
  const std::string text =
      "# vtk DataFile Version 3.0\ntitle\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n"
      "1 2 3\n4 5 6\n7 8\n";
  expect_error<FormatError>(write("short.vtk", text), {"line 8", "9 numbers", "after 8"});
  const std::string cut =
      "# vtk DataFile Version 3.0\ntitle\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n"
      "1 2 3\n4 5 6\nVERTICES 3 6\n";
  expect_error<FormatError>(write("cut.vtk", cut), {"line 8", "'VERTICES'"});
}

TEST_F(IoTest, RejectsVtkVariants) {
  expect_error<FormatError>(
      write("binary.vtk", "# vtk DataFile Version 3.0\ntitle\nBINARY\nDATASET POLYDATA\n"),
      {"line 3", "binary VTK not supported"});
  expect_error<FormatError>(
      write("grid.vtk", "# vtk DataFile Version 3.0\ntitle\nASCII\nDATASET STRUCTURED_POINTS\n"),
      {"line 4", "STRUCTURED_POINTS"});
  expect_error<FormatError>(write("magic.vtk", "hello\n"), {"line 1"});
  expect_error<FormatError>(
      write("type.vtk",
            "# vtk DataFile Version 3.0\ntitle\nASCII\nDATASET POLYDATA\nPOINTS 1 int\n1 2 3\n"),
      {"line 5", "'int'"});
}

TEST_F(IoTest, RejectsEmptyFile) {
  for (const char* name :
       {"empty.pcd", "empty.ply", "empty.bin", "empty.xyz", "empty.vtk", "empty.f32"}) {
    expect_error<FormatError>(write(name, ""), {"byte 0", "empty"});
  }
}

TEST_F(IoTest, MissingFileIsIoError) {
  expect_error<IoError>(dir_ / "does_not_exist.pcd", {"No such file or directory"});
}

TEST_F(IoTest, DirectoryIsIoError) {
  const fs::path sub = dir_ / "folder.ply";
  fs::create_directory(sub);
  expect_error<IoError>(sub, {"Is a directory"});
}

TEST_F(IoTest, UnknownExtensionIsFormatError) {
  try {
    (void)read_point_cloud(write("cloud.las", "1 2 3\n"));
    ADD_FAILURE() << "no exception";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(".las"), std::string::npos) << e.what();
  }
}

// Random damage of valid files must end in a FormatError or a result, never in a crash
// (run under a sanitizer or valgrind to catch out-of-bounds reads).
TEST_F(IoTest, TruncatedAndDamagedFilesNeverCrash) {
  PointCloud cloud = random_cloud(50);
  std::vector<fs::path> originals;
  for (const auto& [name, encoding] :
       {std::pair{"a.ply", Encoding::binary}, std::pair{"b.ply", Encoding::ascii},
        std::pair{"c.pcd", Encoding::binary}, std::pair{"d.pcd", Encoding::ascii},
        std::pair{"e.xyz", Encoding::ascii}}) {
    originals.push_back(dir_ / name);
    write_point_cloud(originals.back(), cloud, FileFormat::automatic, encoding);
  }
  originals.push_back(write("f.ply", binary_ply(true)));
  originals.push_back(write("g.vtk",
                            "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n"
                            "POINTS 2 float\n1 2 3 4 5 6\n"));
  {
    Bytes raw;
    for (int i = 0; i < 64; ++i) raw.le(static_cast<float>(i));
    const std::string block = lzf_block(raw.str());
    Bytes b;
    b.text(pcd_header("x y z rgb", "4 4 4 4", "F F F U", "1 1 1 1", 4, 4, "binary_compressed"));
    b.le(static_cast<std::uint32_t>(block.size())).le(std::uint32_t{256}).text(block);
    originals.push_back(write("h.pcd", b.str()));
  }

  std::mt19937 rng(7);
  for (const auto& original : originals) {
    std::ifstream in(original, std::ios::binary);
    const std::string content((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
    ASSERT_NO_THROW((void)read_point_cloud(original)) << original;
    for (int trial = 0; trial < 60; ++trial) {
      std::string damaged = content;
      if (trial % 2 == 0) {
        damaged.resize(std::uniform_int_distribution<std::size_t>(1, content.size() - 1)(rng));
      } else {
        for (int k = 0; k < 4; ++k) {
          const auto at = std::uniform_int_distribution<std::size_t>(0, content.size() - 1)(rng);
          damaged[at] = static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
        }
      }
      const fs::path path = write("damaged" + original.extension().string(), damaged);
      try {
        (void)read_point_cloud(path);
      } catch (const FormatError&) {
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Real data

fs::path shared(const std::string& relative) {
  return kSharedData / relative;
}

#define SKIP_IF_MISSING(path) \
  if (!fs::exists(path)) GTEST_SKIP() << "missing " << (path)

TEST(IoRealData, KinectBinaryCompressedPcdMatchesF32) {
  const fs::path folder = shared("pcl_kinect_frames");
  SKIP_IF_MISSING(folder);
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() != ".pcd") continue;
    fs::path f32 = entry.path();
    f32.replace_extension(".xyz.f32");
    if (!fs::exists(f32)) continue;
    const ReadResult pcd = read_point_cloud(entry.path());
    const ReadResult ref = read_point_cloud(f32);
    EXPECT_EQ(pcd.format, FileFormat::pcd);
    EXPECT_EQ(pcd.points_in_file, 640u * 480u) << entry.path();
    EXPECT_GT(pcd.non_finite_dropped, 0u) << entry.path();
    EXPECT_EQ(pcd.cloud.size() + pcd.non_finite_dropped, pcd.points_in_file);
    EXPECT_EQ(ref.cloud.size(), fs::file_size(f32) / 12);
    EXPECT_EQ(ref.non_finite_dropped, 0u);
    ASSERT_EQ(pcd.cloud.size(), ref.cloud.size()) << entry.path();
    for (std::size_t i = 0; i < ref.cloud.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        ASSERT_TRUE(same_bits(pcd.cloud.points[i][k], ref.cloud.points[i][k]))
            << entry.path() << " point " << i;
      }
    }
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

TEST(IoRealData, BunnyAsciiPcd) {
  SKIP_IF_MISSING(shared("pcl_bunny/bun0.pcd"));
  const ReadResult bun0 = read_point_cloud(shared("pcl_bunny/bun0.pcd"));
  const ReadResult bun4 = read_point_cloud(shared("pcl_bunny/bun4.pcd"));
  const ReadResult bunny = read_point_cloud(shared("pcl_bunny/bunny.pcd"));
  EXPECT_EQ(bun0.cloud.size(), 397u);
  EXPECT_EQ(bun4.cloud.size(), 361u);
  EXPECT_EQ(bunny.cloud.size(), 397u);
  EXPECT_EQ(bun0.non_finite_dropped, 0u);
  EXPECT_FLOAT_EQ(bun4.cloud.points[0].x(), 0.053026f);
  EXPECT_FLOAT_EQ(bun4.cloud.points[0].z(), 0.077131f);
  ASSERT_EQ(bunny.cloud.size(), bun0.cloud.size());
  for (std::size_t i = 0; i < bun0.cloud.size(); ++i) {
    EXPECT_LT((bun0.cloud.points[i] - bunny.cloud.points[i]).norm(), 1e-6f) << i;
  }
}

TEST(IoRealData, LibpointmatcherCsvAndVtk) {
  SKIP_IF_MISSING(shared("libpointmatcher_car/car_cloud400.csv"));
  const ReadResult c400 = read_point_cloud(shared("libpointmatcher_car/car_cloud400.csv"));
  const ReadResult c401 = read_point_cloud(shared("libpointmatcher_car/car_cloud401.csv"));
  EXPECT_EQ(c400.cloud.size(), 24989u);
  EXPECT_EQ(c401.cloud.size(), 25193u);
  EXPECT_EQ(c400.points_in_file, 24989u);
  EXPECT_FLOAT_EQ(c400.cloud.points[0].x(), -3.5376f);
  EXPECT_FLOAT_EQ(c400.cloud.points[0].y(), 0.639553f);
  EXPECT_FLOAT_EQ(c400.cloud.points[0].z(), -1.37678f);
  EXPECT_FLOAT_EQ(c401.cloud.points[0].x(), 2.6247663f);

  const ReadResult v0 = read_point_cloud(shared("libpointmatcher_car/cloud.00000.vtk"));
  const ReadResult v1 = read_point_cloud(shared("libpointmatcher_car/cloud.00001.vtk"));
  const ReadResult v2 = read_point_cloud(shared("libpointmatcher_car/cloud.00002.vtk"));
  EXPECT_EQ(v0.format, FileFormat::vtk);
  EXPECT_EQ(v0.cloud.size(), c400.cloud.size());
  EXPECT_EQ(v1.cloud.size(), 25193u);
  EXPECT_EQ(v2.cloud.size(), 24154u);
  EXPECT_FLOAT_EQ(v0.cloud.points[0].x(), -3.79521f);
}

TEST(IoRealData, KittiBin) {
  const fs::path folder = shared("kitti_odometry_seq00/velodyne");
  SKIP_IF_MISSING(folder);
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() != ".bin") continue;
    const ReadResult r = read_point_cloud(entry.path());
    EXPECT_EQ(r.points_in_file, fs::file_size(entry.path()) / 16) << entry.path();
    EXPECT_EQ(r.cloud.size() + r.non_finite_dropped, r.points_in_file);
    ++checked;
  }
  EXPECT_EQ(checked, 6);
  const ReadResult first = read_point_cloud(folder / "000000.bin");
  EXPECT_EQ(first.cloud.size(), 124668u);
}

TEST(IoRealData, EthKinectMapPly) {
  const fs::path path =
      shared("eth_kinect_highcomplexity_map/high-complexity-environment_map_ascii.ply");
  SKIP_IF_MISSING(path);
  const ReadResult r = read_point_cloud(path);
  EXPECT_EQ(r.format, FileFormat::ply);
  EXPECT_EQ(r.cloud.size(), 38144u);
  EXPECT_EQ(r.points_in_file, 38144u);
  EXPECT_FLOAT_EQ(r.cloud.points[0].x(), 3.31309f);
  EXPECT_FLOAT_EQ(r.cloud.points[0].y(), -1.20276f);
  EXPECT_FLOAT_EQ(r.cloud.points[0].z(), -0.102287f);
}

TEST(IoRealData, GeneratedCopies) {
  const fs::path eth = shared("generated/eth_kinect_map_copies");
  SKIP_IF_MISSING(eth);
  for (const auto& entry : fs::directory_iterator(eth)) {
    if (entry.path().extension() != ".pcd") continue;
    EXPECT_EQ(read_point_cloud(entry.path()).cloud.size(), 38144u) << entry.path();
  }
  const fs::path kitti = shared("generated/kitti_copies");
  for (const auto& entry : fs::directory_iterator(kitti)) {
    if (entry.path().extension() != ".bin") continue;
    EXPECT_EQ(read_point_cloud(entry.path()).points_in_file, fs::file_size(entry.path()) / 16);
  }
}

// Whatever was read can be written and read back unchanged.
TEST_F(IoTest, RealDataSurvivesARoundTrip) {
  const fs::path path = shared("pcl_bunny/bun0.pcd");
  SKIP_IF_MISSING(path);
  const ReadResult r = read_point_cloud(path);
  for (const char* name : {"bun0.ply", "bun0.pcd", "bun0.xyz"}) {
    write_point_cloud(dir_ / name, r.cloud);
    const ReadResult back = read_point_cloud(dir_ / name);
    ASSERT_EQ(back.cloud.size(), r.cloud.size());
    for (std::size_t i = 0; i < r.cloud.size(); ++i) {
      ASSERT_EQ(back.cloud.points[i], r.cloud.points[i]) << name << " point " << i;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// In-memory entry point: the same parser as the file reader

std::vector<std::byte> file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> bytes(text.size());
  std::memcpy(bytes.data(), text.data(), text.size());
  return bytes;
}

// The error of one entry point, with the file's name replaced by "<name>".
std::string error_of(const std::function<ReadResult()>& read, const std::string& name) {
  try {
    (void)read();
  } catch (const FormatError& e) {
    std::string message = e.what();
    if (message.starts_with(name)) message.replace(0, name.size(), "<name>");
    return message;
  }
  return "no error";
}

void expect_memory_reads_like_file(const fs::path& path) {
  const FileFormat format = format_from_extension(path);
  const auto bytes = file_bytes(path);
  const ReadResult from_file = read_point_cloud(path);
  const ReadResult from_memory = read_point_cloud_from_memory(bytes, format, "mem");
  EXPECT_EQ(from_memory.format, from_file.format) << path;
  EXPECT_EQ(from_memory.points_in_file, from_file.points_in_file) << path;
  EXPECT_EQ(from_memory.non_finite_dropped, from_file.non_finite_dropped) << path;
  ASSERT_EQ(from_memory.cloud.size(), from_file.cloud.size()) << path;
  for (std::size_t i = 0; i < from_file.cloud.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_TRUE(same_bits(from_memory.cloud.points[i][k], from_file.cloud.points[i][k]))
          << path << " point " << i;
    }
  }
  // A truncated copy fails the same way through both entry points.
  const std::size_t half = bytes.size() / 2 + 1;
  const std::span<const std::byte> truncated(bytes.data(), half);
  const fs::path cut = path.parent_path() / ("cut_" + path.filename().string());
  {
    std::ofstream out(cut, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(half));
  }
  EXPECT_EQ(error_of([&] { return read_point_cloud_from_memory(truncated, format, "mem"); }, "mem"),
            error_of([&] { return read_point_cloud(cut); }, cut.string()))
      << path;
}

TEST_F(IoTest, MemoryReaderMatchesFileReaderForEveryFormat) {
  PointCloud cloud = random_cloud(50);
  cloud.points.emplace_back(kNaN, 1.0f, 2.0f);  // dropped and counted by both
  write_point_cloud(dir_ / "c.ply", cloud, FileFormat::automatic, Encoding::binary);
  write_point_cloud(dir_ / "a.ply", cloud, FileFormat::automatic, Encoding::ascii);
  write_point_cloud(dir_ / "c.pcd", cloud, FileFormat::automatic, Encoding::binary);
  write_point_cloud(dir_ / "a.pcd", cloud, FileFormat::automatic, Encoding::ascii);
  write_point_cloud(dir_ / "c.xyz", cloud);
  Bytes raw;
  for (const float x : {1.0f, kNaN, 3.0f}) raw.le(x);
  for (const float y : {10.0f, 20.0f, 30.0f}) raw.le(y);
  for (const double z : {100.0, 200.0, 1e300}) raw.le(z);
  const std::string block = lzf_block(raw.str());
  Bytes pcd;
  pcd.text(pcd_header("x y z", "4 4 8", "F F F", "1 1 1", 3, 1, "binary_compressed"));
  pcd.le(static_cast<std::uint32_t>(block.size())).le(static_cast<std::uint32_t>(raw.str().size()));
  pcd.text(block);
  write("z.pcd", pcd.str());
  Bytes be;
  be.text(
      "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double x\n"
      "property double y\nproperty double z\nend_header\n");
  for (const double v : {1.0, 2.0, 3.0, -4.0, 5.5, 1e-300}) be.be(v);
  write("be.ply", be.str());
  Bytes floats;
  for (int i = 0; i < 24; ++i) floats.le(static_cast<float>(i) * 0.25f);
  write("k.bin", floats.str());
  write("k.f32", floats.str());
  write("v.vtk",
        "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 2 double\n"
        "1 2 3\n4.5 -6 7e-3\n");
  write("t.csv", "x,y,z\n1,2,3\n4,5,6\nnan,1,1\n");
  for (const auto& entry : fs::directory_iterator(dir_)) {
    if (!entry.path().filename().string().starts_with("cut_")) {
      expect_memory_reads_like_file(entry.path());
    }
  }
}

TEST(IoMemory, RealDataReadsLikeTheFiles) {
  for (const char* relative :
       {"pcl_kinect_frames", "pcl_bunny", "libpointmatcher_car", "kitti_odometry_seq00/velodyne"}) {
    const fs::path folder = shared(relative);
    if (!fs::exists(folder)) continue;
    for (const auto& entry : fs::directory_iterator(folder)) {
      const std::string name = entry.path().filename().string();
      if (name == "000000.bin" || name.ends_with(".pcd") || name.ends_with(".vtk") ||
          name == "car_cloud400.csv") {
        const auto bytes = file_bytes(entry.path());
        const ReadResult a = read_point_cloud(entry.path());
        const ReadResult b = read_point_cloud_from_memory(bytes, a.format, name);
        ASSERT_EQ(a.cloud.points, b.cloud.points) << entry.path();
        EXPECT_EQ(a.non_finite_dropped, b.non_finite_dropped);
      }
    }
  }
}

TEST(IoMemory, NeedsAnExplicitFormatAndNamesTheSource) {
  const std::string text = "1 2 3\n4 5\n";
  const auto* data = reinterpret_cast<const std::byte*>(text.data());
  const std::span<const std::byte> bytes(data, text.size());
  EXPECT_THROW((void)read_point_cloud_from_memory(bytes, FileFormat::automatic), FormatError);
  EXPECT_EQ(read_point_cloud_from_memory(bytes.first(6), FileFormat::xyz).cloud.size(), 1u);
  try {
    (void)read_point_cloud_from_memory(bytes, FileFormat::xyz, "fuzz input");
    ADD_FAILURE() << "no error";
  } catch (const FormatError& e) {
    EXPECT_TRUE(std::string(e.what()).starts_with("fuzz input: line 2:")) << e.what();
  }
  EXPECT_THROW((void)read_point_cloud_from_memory({}, FileFormat::pcd), FormatError);
}

// ---------------------------------------------------------------------------------------------
// Numbers in text formats

ReadResult read_text(const std::string& text, FileFormat format = FileFormat::xyz) {
  const auto* data = reinterpret_cast<const std::byte*>(text.data());
  return read_point_cloud_from_memory({data, text.size()}, format, "numbers");
}

std::string text_error(const std::string& text, FileFormat format = FileFormat::xyz) {
  try {
    (void)read_text(text, format);
  } catch (const FormatError& e) {
    return e.what();
  }
  return "no error";
}

TEST(IoNumbers, OverflowIsInfiniteAndDroppedUnderflowIsZero) {
  const std::string overflow = "1" + std::string(400, '0') + "e-1";     // 1e399
  const std::string underflow = "0." + std::string(400, '0') + "1e+1";  // 1e-400
  const ReadResult r = read_text("1 2 " + overflow + "\n" + underflow + " -" + underflow +
                                 " -1e-400\n-" + overflow + " 0 0\n");
  EXPECT_EQ(r.points_in_file, 3u);
  EXPECT_EQ(r.non_finite_dropped, 2u);
  ASSERT_EQ(r.cloud.size(), 1u);
  EXPECT_EQ(r.cloud.points[0], Eigen::Vector3f::Zero());
  EXPECT_FALSE(std::signbit(r.cloud.points[0].x()));
  EXPECT_TRUE(std::signbit(r.cloud.points[0].y()));
  EXPECT_TRUE(std::signbit(r.cloud.points[0].z()));
  // Exponents beyond any integer type saturate the same way.
  EXPECT_EQ(read_text("1e99999999999999999999999 0 0\n").non_finite_dropped, 1u);
  EXPECT_EQ(read_text("1e-99999999999999999999999 0 0\n").cloud.size(), 1u);
}

TEST(IoNumbers, EdgesOfTheFloatStorageAndLongMantissas) {
  constexpr float kMax = std::numeric_limits<float>::max();
  constexpr float kDenorm = std::numeric_limits<float>::denorm_min();
  const ReadResult r = read_text("3.4028234663852886e38 1.4e-45 1e-310\n3.5e38 0 0\n");
  EXPECT_EQ(r.non_finite_dropped, 1u);  // beyond the float range: infinite
  ASSERT_EQ(r.cloud.size(), 1u);
  EXPECT_EQ(r.cloud.points[0].x(), kMax);
  EXPECT_EQ(r.cloud.points[0].y(), kDenorm);
  EXPECT_EQ(r.cloud.points[0].z(), 0.0f);  // a double subnormal, below the float ones
  // 500 digits: correctly rounded, not cut off.
  const std::string long_one = "0." + std::string(500, '9');  // 1 - 1e-500
  const std::string long_tenth = "0.1" + std::string(500, '0') + "1";
  const ReadResult l =
      read_text(long_one + " " + long_tenth + " 1" + std::string(300, '0') + "e-300\n");
  ASSERT_EQ(l.cloud.size(), 1u);
  EXPECT_EQ(l.cloud.points[0].x(), 1.0f);
  EXPECT_EQ(l.cloud.points[0].y(), 0.1f);
  EXPECT_EQ(l.cloud.points[0].z(), 1.0f);
}

TEST(IoNumbers, StrictTokensInEveryTextFormat) {
  EXPECT_EQ(read_text("+1 +2.5 -3\n").cloud.points[0], Eigen::Vector3f(1, 2.5f, -3));
  for (const std::string bad :
       {"0.0.5", "+-1", "++1", "1e", "1e+", ".", "-", "0x1p3", "1.5f", "1_000"}) {
    SCOPED_TRACE(bad);
    const std::string xyz = text_error("1 2 3\n0 " + bad + " 0\n");
    EXPECT_NE(xyz.find("numbers: line 2: '" + bad + "' is not a number"), std::string::npos) << xyz;
    const std::string pcd = text_error(
        pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 1, 1, "ascii") + "0 0 " + bad + "\n",
        FileFormat::pcd);
    EXPECT_NE(pcd.find("is not a number"), std::string::npos) << pcd;
    const std::string ply = text_error(
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n" +
            bad + " 0 0\n",
        FileFormat::ply);
    EXPECT_NE(ply.find("is not a number"), std::string::npos) << ply;
    const std::string vtk = text_error(
        "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n0 " + bad + " 0\n",
        FileFormat::vtk);
    EXPECT_NE(vtk.find("is not a number"), std::string::npos) << vtk;
  }
}

TEST(IoNumbers, DecimalPointIgnoresTheLocale) {
  const char* previous = std::setlocale(LC_ALL, nullptr);
  const std::string saved = previous != nullptr ? previous : "C";
  bool comma_locale = false;
  for (const char* name : {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "ru_RU.UTF-8"}) {
    if (std::setlocale(LC_ALL, name) != nullptr) {
      comma_locale = true;
      break;
    }
  }
  if (!comma_locale) GTEST_SKIP() << "no locale with a decimal comma installed";
  const ReadResult r = read_text("1.5 2.25 -3.125\n");
  std::setlocale(LC_ALL, saved.c_str());
  ASSERT_EQ(r.cloud.size(), 1u);
  EXPECT_EQ(r.cloud.points[0], Eigen::Vector3f(1.5f, 2.25f, -3.125f));
}

// ---------------------------------------------------------------------------------------------
// Strictness: every value of its type, nothing after binary data

TEST(IoStrict, PlyAsciiValuesOfEveryPropertyHaveTheirType) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar red\nproperty char dx\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n";
  EXPECT_EQ(read_text(header + "1 2 3 255 -128\n1 0\n", FileFormat::ply).cloud.size(), 1u);
  const std::pair<std::string, std::string> cases[] = {
      {"1 2 3 banana 0\n1 0\n", "line 12: 'banana' is not a uchar value (property 'red')"},
      {"1 2 3 256 0\n1 0\n", "'256' is not a uchar value (property 'red')"},
      {"1 2 3 -1 0\n1 0\n", "'-1' is not a uchar value"},
      {"1 2 3 1.5 0\n1 0\n", "'1.5' is not a uchar value"},
      {"1 2 3 0 -129\n1 0\n", "'-129' is not a char value (property 'dx')"},
      {"1 2 3 0 0\nbanana 0\n", "line 13: 'banana' is not a list length of type uchar"},
      {"1 2 3 0 0\n256 0\n", "'256' is not a list length of type uchar"},
      {"1 2 3 0 0\n1 banana\n", "'banana' is not a int value (property 'vertex_indices')"},
  };
  for (const auto& [body, message] : cases) {
    SCOPED_TRACE(body);
    const std::string error = text_error(header + body, FileFormat::ply);
    EXPECT_NE(error.find(message), std::string::npos) << error;
  }
}

TEST(IoStrict, PcdAsciiValuesOfEveryFieldHaveTheirType) {
  const std::string header = pcd_header("x y z rgb label normal", "4 4 4 4 1 4", "F F F U I F",
                                        "1 1 1 1 1 3", 1, 1, "ascii");
  const ReadResult ok = read_text(header + "1 2 3 4294967295 -128 nan 0 1e-3\n", FileFormat::pcd);
  EXPECT_EQ(ok.cloud.size(), 1u);
  const std::pair<std::string, std::string> cases[] = {
      {"1 2 3 banana 0 0 0 0\n",
       "line 12: 'banana' is not an unsigned integer of 4 byte(s) "
       "(field 'rgb')"},
      {"1 2 3 4294967296 0 0 0 0\n", "'4294967296' is not an unsigned integer"},
      {"1 2 3 -1 0 0 0 0\n", "'-1' is not an unsigned integer"},
      {"1 2 3 0 128 0 0 0\n", "'128' is not a signed integer of 1 byte(s) (field 'label')"},
      {"1 2 3 0 0 0 banana 0\n", "'banana' is not a number (field 'normal')"},
  };
  for (const auto& [body, message] : cases) {
    SCOPED_TRACE(body);
    const std::string error = text_error(header + body, FileFormat::pcd);
    EXPECT_NE(error.find(message), std::string::npos) << error;
  }
}

TEST(IoStrict, BytesAfterBinaryDataAreAnErrorExceptPagePadding) {
  Bytes points;
  for (const float v : {1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f}) points.le(v);
  const std::string pcd = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 2, 1, "binary");
  const std::string data = pcd + points.str();
  // PCL before 1.10 padded its files with zeros to a page after the header (real files in
  // pcl_kinect_frames end with 3901 zero bytes).
  const std::string padding(4096 - pcd.size(), '\0');
  EXPECT_EQ(read_text(data + padding, FileFormat::pcd).cloud.size(), 2u);
  const std::string one =
      text_error(data + padding.substr(1) + std::string(1, '\x01'), FileFormat::pcd);
  EXPECT_NE(one.find("byte " + std::to_string(data.size()) + ": " + std::to_string(padding.size()) +
                     " bytes after the point data"),
            std::string::npos)
      << one;
  const std::string zeros = text_error(data + std::string(70000, '\0'), FileFormat::pcd);
  EXPECT_NE(zeros.find("70000 bytes after the point data"), std::string::npos) << zeros;

  const std::string block = lzf_block(points.str());
  Bytes compressed;
  compressed.text(pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 2, 1, "binary_compressed"))
      .le(static_cast<std::uint32_t>(block.size()))
      .le(static_cast<std::uint32_t>(points.str().size()))
      .text(block);
  EXPECT_EQ(read_text(compressed.str() + padding, FileFormat::pcd).cloud.size(), 2u);
  const std::string after = text_error(compressed.str() + "junk", FileFormat::pcd);
  EXPECT_NE(after.find("4 bytes after the point data"), std::string::npos) << after;

  const std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n" +
      points.str();
  EXPECT_EQ(read_text(ply, FileFormat::ply).cloud.size(), 2u);
  const std::string ply_error = text_error(ply + std::string(1, '\0'), FileFormat::ply);
  EXPECT_NE(
      ply_error.find("byte " + std::to_string(ply.size()) + ": 1 bytes after the last element"),
      std::string::npos)
      << ply_error;
}

}  // namespace
}  // namespace sgdicp
