// Tests of the point-cloud readers and writers: format names, round trips, headerless binary,
// non-finite values and files that cannot be read. The formats have their own files
// (test_io_pcd.cpp, test_io_ply.cpp, test_io_text.cpp), as have hostile input
// (test_io_hostile.cpp) and the real data and the in-memory reader (test_io_real_data.cpp);
// io_support.hpp holds what they share.
#include <array>
#include <cstdint>
#include <filesystem>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>

#include <gtest/gtest.h>

#include "io_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

namespace sgdicp::io_test {
namespace {

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
// Headerless binary (KITTI .bin, .f32) and the format from the extension

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

TEST_F(IoTest, RejectsKittiBinOfWrongSize) {
  const std::string message =
      expect_error<FormatError>(write("bad.bin", std::string(1000, '\0')), {"byte 992", "1000"});
  EXPECT_NE(message.find("16"), std::string::npos) << message;
  expect_error<FormatError>(write("bad.f32", std::string(100, '\0')), {"byte 96", "100"});
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
// Files that cannot be read

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

}  // namespace
}  // namespace sgdicp::io_test
