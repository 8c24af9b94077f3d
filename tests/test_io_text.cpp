// Tests of the text readers: XYZ / CSV / TXT (separators, comments, header lines) and ascii
// VTK, their rejections, and the numbers of every text format (overflow, float edges, strict
// tokens, the locale).
#include <clocale>
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "io_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

namespace sgdicp::io_test {
namespace {

// ---------------------------------------------------------------------------------------------
// XYZ / CSV / TXT and VTK

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

// ---------------------------------------------------------------------------------------------
// Rejections

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

// ---------------------------------------------------------------------------------------------
// Numbers in text formats

TEST(IoNumbers, OverflowIsInfiniteAndDroppedUnderflowIsZero) {
  const std::string zeros(400, '0');
  const std::string overflow = "1" + zeros + "e-1";     // 1e399
  const std::string underflow = "0." + zeros + "1e+1";  // 1e-400
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

}  // namespace
}  // namespace sgdicp::io_test
