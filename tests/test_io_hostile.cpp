// Tests of the readers against hostile input: headers lying about the point count, compressed
// blocks that would expand beyond their claim, clouds and files beyond the largest read,
// non-regular files, and damaged files that must fail cleanly (run under a sanitizer to catch
// out-of-bounds reads).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "allocation_tracker.hpp"
#include "io_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

namespace sgdicp::io_test {
namespace {

// ---------------------------------------------------------------------------------------------
// Headers that lie, hostile compressed blocks, limits

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

// ---------------------------------------------------------------------------------------------
// Damaged files

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

}  // namespace
}  // namespace sgdicp::io_test
