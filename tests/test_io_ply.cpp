// Tests of the PLY reader: ascii and binary in both byte orders, lists and other elements,
// rejections of broken files (type and position in the message), the type of every ascii value.
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
// Rejections

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

// ---------------------------------------------------------------------------------------------
// Strictness: every value of its type

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

}  // namespace
}  // namespace sgdicp::io_test
