// Tests of the PCD reader: ascii, binary and binary_compressed variants, rejections of broken
// files (type and position in the message), the type of every ascii value and the bytes after
// the point data.
#include <cstdint>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "io_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

namespace sgdicp::io_test {
namespace {

// ---------------------------------------------------------------------------------------------
// Variants

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
// Rejections

TEST_F(IoTest, RejectsTruncatedBinaryPcd) {
  const std::string header = pcd_header("x y z", "4 4 4", "F F F", "1 1 1", 100, 1, "binary");
  const std::string content = header + std::string(1000, '\0');
  expect_error<FormatError>(write("t.pcd", content),
                            {"byte " + std::to_string(header.size()), "need 1200", "have 1000"});
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

// ---------------------------------------------------------------------------------------------
// Strictness: every value of its type, nothing after binary data

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
}  // namespace sgdicp::io_test
