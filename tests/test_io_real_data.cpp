// Tests of the readers on the real data of ../shared/data (skipped when absent), and of the
// in-memory entry point against the file reader.
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "io_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"
#include "test_support.hpp"

namespace sgdicp::io_test {
namespace {

// ---------------------------------------------------------------------------------------------
// Real data

const fs::path kSharedData = SGDICP_SHARED_DATA;

fs::path shared(const std::string& relative) {
  return kSharedData / relative;
}

TEST(IoRealData, KinectBinaryCompressedPcdMatchesF32) {
  const fs::path folder = shared("pcl_kinect_frames");
  SKIP_WITHOUT(folder);
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
  SKIP_WITHOUT(shared("pcl_bunny/bun0.pcd"));
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
  SKIP_WITHOUT(shared("libpointmatcher_car/car_cloud400.csv"));
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
  SKIP_WITHOUT(folder);
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
  SKIP_WITHOUT(path);
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
  SKIP_WITHOUT(eth);
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
  SKIP_WITHOUT(path);
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

}  // namespace
}  // namespace sgdicp::io_test
