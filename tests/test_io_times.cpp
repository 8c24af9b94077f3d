// Tests of the per-point times the PCD and PLY readers fill (docs/io.md, "Per-point times"):
// each driver's field name and type, in seconds from the earliest kept point, aligned with the
// points after non-finite ones are dropped; the priority of the names; hostile time fields; and
// the round trip through the writers.
#include <cstdint>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include "io_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

namespace sgdicp::io_test {
namespace {

// The times read, one per point, each within `tolerance_s` of the expected seconds.
void expect_times(const ReadResult& r, std::initializer_list<double> expected,
                  double tolerance_s = 0.0) {
  ASSERT_TRUE(r.cloud.has_times());
  ASSERT_EQ(r.cloud.times_s.size(), expected.size());
  std::size_t i = 0;
  for (const double e : expected) {
    if (tolerance_s == 0.0) {
      EXPECT_FLOAT_EQ(r.cloud.times_s[i], static_cast<float>(e)) << "point " << i;
    } else {
      EXPECT_NEAR(r.cloud.times_s[i], e, tolerance_s) << "point " << i;
    }
    ++i;
  }
}

std::string pcd_with_one_point(std::string_view time_name, std::string_view size,
                               std::string_view type, std::string_view count) {
  return pcd_header("x y z " + std::string(time_name), "4 4 4 " + std::string(size),
                    "F F F " + std::string(type), "1 1 1 " + std::string(count), 1, 1, "binary");
}

// ---------------------------------------------------------------------------------------------
// PCD

TEST_F(IoTest, PcdAsciiOusterIntegerNanoseconds) {
  // Ouster: uint32 t, nanoseconds from the sweep's start. The dropped NaN point holds the
  // earliest time: the times count from the earliest point kept.
  const std::string text =
      pcd_header("x y z intensity t", "4 4 4 4 4", "F F F F U", "1 1 1 1 1", 4, 1, "ascii") +
      "1 2 3 7 50000000\n"
      "nan 0 0 7 0\n"
      "4 5 6 7 10000000\n"
      "7 8 9 7 99999999\n";
  const ReadResult r = read_point_cloud(write("ouster.pcd", text));
  EXPECT_EQ(r.non_finite_dropped, 1u);
  expect_points(r, {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}});
  expect_times(r, {0.04, 0.0, 0.089999999});
}

TEST_F(IoTest, PcdBinaryVelodyneFloatSecondsBeforeTheSweepEnd) {
  // Velodyne: float time in seconds, relative to the sweep (negative: before its end).
  Bytes b;
  b.text(pcd_header("x y z intensity ring time", "4 4 4 4 2 4", "F F F F U F", "1 1 1 1 1 1", 4, 1,
                    "binary"));
  b.le(1.0f).le(2.0f).le(3.0f).le(0.5f).le(std::uint16_t{3}).le(-0.1f);
  b.le(4.0f).le(kInf).le(6.0f).le(0.5f).le(std::uint16_t{4}).le(-0.2f);  // dropped
  b.le(7.0f).le(8.0f).le(9.0f).le(0.5f).le(std::uint16_t{5}).le(-0.05f);
  b.le(1.0f).le(1.0f).le(1.0f).le(0.5f).le(std::uint16_t{6}).le(0.0f);
  const ReadResult r = read_point_cloud(write("velodyne.pcd", b.str()));
  EXPECT_EQ(r.non_finite_dropped, 1u);
  expect_points(r, {{1, 2, 3}, {7, 8, 9}, {1, 1, 1}});
  expect_times(r, {0.0, 0.05, 0.1}, 1e-7);
}

TEST_F(IoTest, PcdBinaryHesaiAbsoluteSecondsKeepMicroseconds) {
  // Hesai: double timestamp, absolute UNIX time; float alone would snap it to 128 s.
  Bytes b;
  b.text(pcd_header("x y z timestamp ring", "4 4 4 8 2", "F F F F U", "1 1 1 1 1", 3, 1, "binary"));
  b.le(1.0f).le(0.0f).le(0.0f).le(1700000000.000123).le(std::uint16_t{0});
  b.le(2.0f).le(0.0f).le(0.0f).le(1700000000.0).le(std::uint16_t{1});
  b.le(3.0f).le(0.0f).le(0.0f).le(1700000000.099999).le(std::uint16_t{2});
  const ReadResult r = read_point_cloud(write("hesai.pcd", b.str()));
  expect_times(r, {0.000123, 0.0, 0.099999}, 0.5e-6);
  EXPECT_GT(r.cloud.times_s[0], 0.0f);  // the 123 microseconds are there
}

TEST_F(IoTest, PcdBinaryCompressedLivoxOffsetTimeWithNaN) {
  // Livox: integer offset_time in nanoseconds (here uint64); structure of arrays.
  Bytes raw;
  for (const float x : {1.0f, kNaN, 3.0f}) raw.le(x);
  for (const float y : {10.0f, 20.0f, 30.0f}) raw.le(y);
  for (const float z : {100.0f, 200.0f, 300.0f}) raw.le(z);
  for (const std::uint64_t t : {2000000u, 1000000u, 5000000u}) raw.le(t);
  const std::string block = lzf_block(raw.str());
  Bytes b;
  b.text(
      pcd_header("x y z offset_time", "4 4 4 8", "F F F U", "1 1 1 1", 3, 1, "binary_compressed"));
  b.le(static_cast<std::uint32_t>(block.size())).le(static_cast<std::uint32_t>(raw.str().size()));
  b.text(block);
  const ReadResult r = read_point_cloud(write("livox.pcd", b.str()));
  EXPECT_EQ(r.non_finite_dropped, 1u);
  expect_points(r, {{1, 10, 100}, {3, 30, 300}});
  expect_times(r, {0.0, 0.003});
}

TEST_F(IoTest, PcdTypeDecidesTheUnitForEveryName) {
  // An integer field counts nanoseconds, a floating one seconds, whatever its name.
  const std::string float_t =
      pcd_header("x y z t", "4 4 4 8", "F F F F", "1 1 1 1", 2, 1, "ascii") +
      "0 0 0 0.25\n1 1 1 0.5\n";
  expect_times(read_text(float_t, FileFormat::pcd), {0.0, 0.25});
  const std::string integer_time =
      pcd_header("x y z time", "4 4 4 4", "F F F I", "1 1 1 1", 2, 1, "ascii") +
      "0 0 0 -250000000\n1 1 1 0\n";
  expect_times(read_text(integer_time, FileFormat::pcd), {0.0, 0.25});
}

TEST_F(IoTest, PcdPicksTheTimeFieldByPriority) {
  // t before offset_time before time before timestamp, wherever they stand.
  const std::string text = pcd_header("timestamp time x y z t offset_time", "8 4 4 4 4 4 4",
                                      "F F F F F U U", "1 1 1 1 1 1 1", 2, 1, "ascii") +
                           "1e9 5 0 0 0 1000 7\n2e9 9 1 1 1 3000 8\n";
  expect_times(read_text(text, FileFormat::pcd), {0.0, 2e-6});
  const std::string without_t = pcd_header("timestamp time x y z offset_time", "8 4 4 4 4 4",
                                           "F F F F F U", "1 1 1 1 1 1", 2, 1, "ascii") +
                                "1e9 5 0 0 0 7\n2e9 9 1 1 1 8\n";
  expect_times(read_text(without_t, FileFormat::pcd), {0.0, 1e-9});
  const std::string time_and_timestamp =
      pcd_header("x y z timestamp time", "4 4 4 8 4", "F F F F F", "1 1 1 1 1", 2, 1, "ascii") +
      "0 0 0 1e9 5\n1 1 1 2e9 9\n";
  expect_times(read_text(time_and_timestamp, FileFormat::pcd), {0.0, 4.0});
}

TEST_F(IoTest, PcdDropsPointsWithoutAFiniteTime) {
  // A NaN, infinite or beyond-float time drops its point, counted like a non-finite coordinate.
  const std::string text =
      pcd_header("x y z time", "4 4 4 8", "F F F F", "1 1 1 1", 5, 1, "ascii") +
      "1 1 1 nan\n2 2 2 0.5\n3 3 3 inf\n4 4 4 1e300\n5 5 5 0.75\n";
  const ReadResult r = read_text(text, FileFormat::pcd);
  EXPECT_EQ(r.points_in_file, 5u);
  EXPECT_EQ(r.non_finite_dropped, 3u);
  expect_points(r, {{2, 2, 2}, {5, 5, 5}});
  expect_times(r, {0.0, 0.25});
}

TEST_F(IoTest, PcdWithoutTimeFieldHasNoTimes) {
  const std::string text =
      pcd_header("x y z intensity times", "4 4 4 4 4", "F F F F F", "1 1 1 1 1", 1, 1, "ascii") +
      "1 2 3 4 5\n";
  const ReadResult r = read_text(text, FileFormat::pcd);
  EXPECT_EQ(r.cloud.size(), 1u);
  EXPECT_TRUE(r.cloud.times_s.empty());
  EXPECT_FALSE(r.cloud.has_times());
}

TEST_F(IoTest, RejectsHostilePcdTimeFields) {
  // COUNT 2: which of the two would be the time?
  expect_error<FormatError>(write("count.pcd", pcd_with_one_point("t", "4", "U", "2")),
                            {"line 6", "'t' (the per-point time) must be a single value"});
  expect_error<FormatError>(write("twice.pcd", pcd_header("x y z t t", "4 4 4 4 4", "F F F U U",
                                                          "1 1 1 1 1", 1, 1, "ascii") +
                                                   "1 2 3 4 5\n"),
                            {"line 3", "field 't' appears twice"});
  expect_error<FormatError>(write("half.pcd", pcd_with_one_point("time", "2", "F", "1")),
                            {"line 5", "float field 'time' has SIZE 2"});
  expect_error<FormatError>(write("three.pcd", pcd_with_one_point("t", "3", "U", "1")),
                            {"line 4", "SIZE of field 't' must be 1, 2, 4 or 8"});
  // SIZE 8 declared, 4 bytes stored: the data is too short for the header.
  Bytes b;
  const std::string header = pcd_with_one_point("t", "8", "U", "1");
  b.text(header).le(1.0f).le(2.0f).le(3.0f).le(std::uint32_t{5});
  expect_error<FormatError>(write("size.pcd", b.str()),
                            {"byte " + std::to_string(header.size()), "need 20", "have 16"});
  // An integer time holding a fraction.
  expect_error<FormatError>(
      write("fraction.pcd",
            pcd_header("x y z t", "4 4 4 4", "F F F U", "1 1 1 1", 1, 1, "ascii") + "1 2 3 0.5\n"),
      {"line 12", "'0.5' is not an unsigned integer of 4 byte(s) (field 't')"});
}

// ---------------------------------------------------------------------------------------------
// PLY

TEST_F(IoTest, PlyAsciiVelodyneFloatSecondsWithNaN) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nproperty float intensity\nproperty float time\n"
      "property ushort ring\nend_header\n"
      "1 2 3 9 -0.08 1\n"
      "nan 5 6 9 -0.1 2\n"
      "7 8 9 9 -0.02 3\n"
      "0 0 0 9 -0.09 4\n";
  const ReadResult r = read_point_cloud(write("velodyne.ply", text));
  EXPECT_EQ(r.non_finite_dropped, 1u);
  expect_points(r, {{1, 2, 3}, {7, 8, 9}, {0, 0, 0}});
  expect_times(r, {0.01, 0.07, 0.0}, 1e-7);
}

// Livox ROS Driver 2 writes `timestamp` as a double counting nanoseconds (absolute): against the
// unit rule, but no recording spans 1e6 s, so a span beyond is read as nanoseconds.
TEST_F(IoTest, PlyDoubleNanosecondTimestampsSpanningYearsAreNanoseconds) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty double timestamp\nend_header\n"
      "1 2 3 1700000000000000000\n"
      "4 5 6 1700000000050000000\n"
      "7 8 9 1700000000100000000\n";
  expect_times(read_point_cloud(write("livox_ros2.ply", text)), {0.0, 0.05, 0.1}, 1e-6);
  // An hour of absolute seconds stays seconds.
  const std::string hour =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nproperty double timestamp\nend_header\n"
      "1 2 3 1700000000.0\n"
      "4 5 6 1700003600.0\n";
  expect_times(read_point_cloud(write("hour.ply", hour)), {0.0, 3600.0});
}

// Three vertices with Ouster's uint32 t (nanoseconds), the second NaN, a face element after.
std::string ouster_ply(bool big_endian) {
  Bytes b;
  b.text(std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
         " 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
         "property uint t\nproperty ushort reflectivity\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n");
  const auto put = [&](auto v) { big_endian ? b.be(v) : b.le(v); };
  const auto vertex = [&](float x, std::uint32_t t) {
    put(x);
    put(2.0f);
    put(3.0f);
    put(t);
    put(std::uint16_t{77});
  };
  vertex(1.0f, 30000000u);
  vertex(kNaN, 0u);
  vertex(5.0f, 20000000u);
  put(std::uint8_t{3});
  for (const std::int32_t i : {0, 1, 2}) put(i);
  return b.str();
}

TEST_F(IoTest, PlyBinaryLittleEndianOusterIntegerNanoseconds) {
  const ReadResult r = read_point_cloud(write("ouster_le.ply", ouster_ply(false)));
  EXPECT_EQ(r.non_finite_dropped, 1u);
  expect_points(r, {{1, 2, 3}, {5, 2, 3}});
  expect_times(r, {0.01, 0.0});
}

TEST_F(IoTest, PlyBinaryBigEndianOusterIntegerNanoseconds) {
  const ReadResult r = read_point_cloud(write("ouster_be.ply", ouster_ply(true)));
  expect_points(r, {{1, 2, 3}, {5, 2, 3}});
  expect_times(r, {0.01, 0.0});
}

TEST_F(IoTest, PlyBinaryBigEndianHesaiAbsoluteSeconds) {
  Bytes b;
  b.text(
      "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double timestamp\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n");
  b.be(1700000000.250001).be(1.0f).be(2.0f).be(3.0f);
  b.be(1700000000.25).be(4.0f).be(5.0f).be(6.0f);
  const ReadResult r = read_point_cloud(write("hesai.ply", b.str()));
  expect_times(r, {1e-6, 0.0}, 0.3e-6);
  EXPECT_GT(r.cloud.times_s[0], 0.5e-6f);
}

TEST_F(IoTest, PlyBinaryLivoxOffsetTimeInVerticesWithLists) {
  // A list in the vertex element: records of varying size, walked one property at a time.
  Bytes b;
  b.text(
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
      "property list uchar float extra\nproperty float y\nproperty uint offset_time\n"
      "property float z\nend_header\n");
  b.le(1.0f).le(std::uint8_t{2}).le(0.0f).le(0.0f).le(2.0f).le(std::uint32_t{4000}).le(3.0f);
  b.le(4.0f).le(std::uint8_t{0}).le(5.0f).le(std::uint32_t{1000}).le(6.0f);
  const ReadResult r = read_point_cloud(write("livox.ply", b.str()));
  expect_points(r, {{1, 2, 3}, {4, 5, 6}});
  expect_times(r, {3e-6, 0.0});
}

TEST_F(IoTest, PlyWithoutTimeFieldHasNoTimes) {
  for (const bool big_endian : {false, true}) {
    const ReadResult r = read_point_cloud(write("plain.ply", binary_ply(big_endian)));
    EXPECT_EQ(r.cloud.size(), 2u);
    EXPECT_TRUE(r.cloud.times_s.empty());
  }
}

TEST_F(IoTest, RejectsHostilePlyTimeFields) {
  const std::string start =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\n";
  expect_error<FormatError>(
      write("list.ply", start + "property list uchar float time\nend_header\n"),
      {"line 3", "'time' (the per-point time) is a list"});
  expect_error<FormatError>(
      write("twice.ply", start + "property uint t\nproperty float t\nend_header\n"),
      {"line 3", "'t' appears twice"});
  // double declared, a float stored.
  const std::string header = start + "property double timestamp\nend_header\n";
  Bytes b;
  b.text(header).le(1.0f).le(2.0f).le(3.0f).le(4.0f);
  expect_error<FormatError>(write("size.ply", b.str()),
                            {"byte " + std::to_string(header.size()), "need 20", "have 16"});
}

// ---------------------------------------------------------------------------------------------
// Writers

PointCloud timed_cloud() {
  PointCloud cloud;
  cloud.points = {{1.0f, 2.0f, 3.0f}, {-4.0f, 5.5f, 6.25f}, {0.125f, -7.0f, 8.0f}};
  cloud.times_s = {0.0375f, 0.0f, 0.099999994f};
  return cloud;
}

TEST_F(IoTest, WrittenTimesReadBackBitIdentical) {
  PointCloud georeferenced = timed_cloud();
  georeferenced.origin_m = {500000.0, 4000000.0, 0.0};  // written as double x y z, float time
  for (const PointCloud& cloud : {timed_cloud(), georeferenced}) {
    for (const char* file : {"times.ply", "times.pcd"}) {
      for (const Encoding encoding : {Encoding::binary, Encoding::ascii}) {
        SCOPED_TRACE(std::string(file) + " " + std::string(enum_name(encoding)));
        const fs::path path = dir_ / file;
        write_point_cloud(path, cloud, FileFormat::automatic, encoding);
        const ReadResult r = read_point_cloud(path);
        ASSERT_EQ(r.cloud.times_s.size(), cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i) {
          EXPECT_TRUE(same_bits(r.cloud.times_s[i], cloud.times_s[i])) << i;
        }
      }
    }
  }
}

TEST_F(IoTest, CloudWithoutTimesIsWrittenWithoutATimeField) {
  PointCloud cloud = timed_cloud();
  cloud.times_s.clear();
  for (const char* file : {"plain.ply", "plain.pcd"}) {
    const fs::path path = dir_ / file;
    write_point_cloud(path, cloud, FileFormat::automatic, Encoding::ascii);
    std::ifstream in(path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(text.find("time"), std::string::npos) << text;
    EXPECT_TRUE(read_point_cloud(path).cloud.times_s.empty());
  }
}

}  // namespace
}  // namespace sgdicp::io_test
