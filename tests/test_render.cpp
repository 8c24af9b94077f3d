#include "sgdicp/tools/render.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sgdicp/core/error.hpp"
#include "test_support.hpp"

namespace {

using sgdicp::test::TempDir;

namespace fs = std::filesystem;

/// A helix of `n` points around the z axis, a few metres across.
sgdicp::PointCloud helix(const int n) {
  sgdicp::PointCloud cloud;
  for (int i = 0; i < n; ++i) {
    const float t = 0.05F * static_cast<float>(i);
    cloud.points.emplace_back(3.0F * std::cos(t), 2.0F * std::sin(t), 0.02F * t);
  }
  return cloud;
}

Eigen::Matrix4d small_motion() {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  const double angle = 0.2;
  T(0, 0) = std::cos(angle);
  T(0, 1) = -std::sin(angle);
  T(1, 0) = std::sin(angle);
  T(1, 1) = std::cos(angle);
  T(0, 3) = 0.5;
  T(2, 3) = -0.1;
  return T;
}

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::uint32_t big_endian_u32(const std::vector<std::uint8_t>& bytes, const std::size_t offset) {
  return (std::uint32_t{bytes[offset]} << 24U) | (std::uint32_t{bytes[offset + 1]} << 16U) |
         (std::uint32_t{bytes[offset + 2]} << 8U) | std::uint32_t{bytes[offset + 3]};
}

/// Checks the PNG signature and the IHDR chunk (which must come first) for the expected size.
void expect_png(const std::vector<std::uint8_t>& bytes, const int width, const int height) {
  constexpr std::array<std::uint8_t, 8> signature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  ASSERT_GE(bytes.size(), 33U);  // signature + IHDR chunk
  for (std::size_t i = 0; i < signature.size(); ++i) {
    EXPECT_EQ(bytes[i], signature[i]) << "signature byte " << i;
  }
  EXPECT_EQ(std::string(bytes.begin() + 12, bytes.begin() + 16), "IHDR");
  EXPECT_EQ(big_endian_u32(bytes, 16), static_cast<std::uint32_t>(width));
  EXPECT_EQ(big_endian_u32(bytes, 20), static_cast<std::uint32_t>(height));
}

TEST(Render, WritesPngOfRequestedSize) {
  const TempDir dir;
  const fs::path file = dir.path() / "pair.png";
  const sgdicp::RenderSettings settings{640, 320, 200000};
  sgdicp::render_alignment_png(file, helix(2000), helix(1500), small_motion(), settings);

  ASSERT_TRUE(fs::exists(file));
  const auto bytes = read_bytes(file);
  expect_png(bytes, 640, 320);
  // Two clouds, text, frames and a scale bar do not compress to a near-empty picture.
  EXPECT_GT(bytes.size(), 3000U);
}

TEST(Render, IsDeterministicAndDependsOnTheTransform) {
  const TempDir dir;
  const auto reference = helix(1000);
  const auto source = helix(1000);
  sgdicp::render_alignment_png(dir.path() / "a.png", reference, source, small_motion());
  sgdicp::render_alignment_png(dir.path() / "b.png", reference, source, small_motion());
  sgdicp::render_alignment_png(dir.path() / "c.png", reference, source,
                               Eigen::Matrix4d::Identity());
  const auto a = read_bytes(dir.path() / "a.png");
  expect_png(a, sgdicp::RenderSettings{}.width, sgdicp::RenderSettings{}.height);
  EXPECT_EQ(a, read_bytes(dir.path() / "b.png"));
  EXPECT_NE(a, read_bytes(dir.path() / "c.png"));
}

TEST(Render, HandlesStridingSmallPicturesAndDegenerateClouds) {
  const TempDir dir;
  // More points than max_points: drawn strided.
  sgdicp::render_alignment_png(dir.path() / "strided.png", helix(5000), helix(5000), small_motion(),
                               {300, 200, 100});
  expect_png(read_bytes(dir.path() / "strided.png"), 300, 200);

  // The smallest allowed picture.
  sgdicp::render_alignment_png(dir.path() / "tiny.png", helix(100), helix(100), small_motion(),
                               {64, 64, 1000});
  expect_png(read_bytes(dir.path() / "tiny.png"), 64, 64);

  // A single point (zero extent) and a cloud with a non-finite point.
  sgdicp::PointCloud one;
  one.points.emplace_back(1.0F, 2.0F, 3.0F);
  sgdicp::PointCloud with_nan = helix(50);
  with_nan.points.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0F, 0.0F);
  sgdicp::render_alignment_png(dir.path() / "one.png", one, one, Eigen::Matrix4d::Identity());
  sgdicp::render_alignment_png(dir.path() / "nan.png", with_nan, one, small_motion());
  expect_png(read_bytes(dir.path() / "one.png"), 1200, 600);
  expect_png(read_bytes(dir.path() / "nan.png"), 1200, 600);
}

TEST(Render, RejectsEmptyOrNonFiniteInput) {
  const TempDir dir;
  const fs::path file = dir.path() / "x.png";
  const sgdicp::PointCloud empty;
  const auto cloud = helix(100);
  EXPECT_THROW(sgdicp::render_alignment_png(file, empty, cloud, Eigen::Matrix4d::Identity()),
               sgdicp::InvalidInputError);
  EXPECT_THROW(sgdicp::render_alignment_png(file, cloud, empty, Eigen::Matrix4d::Identity()),
               sgdicp::InvalidInputError);

  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T(1, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sgdicp::render_alignment_png(file, cloud, cloud, T), sgdicp::InvalidInputError);
  T(1, 3) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(sgdicp::render_alignment_png(file, cloud, cloud, T), sgdicp::InvalidInputError);

  sgdicp::PointCloud all_nan;
  all_nan.points.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0F, 0.0F);
  EXPECT_THROW(sgdicp::render_alignment_png(file, all_nan, all_nan, Eigen::Matrix4d::Identity()),
               sgdicp::InvalidInputError);

  EXPECT_FALSE(fs::exists(file));
}

TEST(Render, RejectsBadSettings) {
  const TempDir dir;
  const fs::path file = dir.path() / "x.png";
  const auto cloud = helix(100);
  const Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  for (const auto& settings :
       {sgdicp::RenderSettings{63, 600, 1000}, sgdicp::RenderSettings{1200, 63, 1000},
        sgdicp::RenderSettings{8193, 600, 1000}, sgdicp::RenderSettings{1200, 8193, 1000},
        sgdicp::RenderSettings{0, 600, 1000}, sgdicp::RenderSettings{-5, 600, 1000},
        sgdicp::RenderSettings{1200, 600, 0}}) {
    EXPECT_THROW(sgdicp::render_alignment_png(file, cloud, cloud, T, settings),
                 sgdicp::InvalidSettingsError)
        << settings.width << "x" << settings.height << ", max_points " << settings.max_points;
  }
  EXPECT_FALSE(fs::exists(file));
}

TEST(Render, UnwritablePathThrowsIoErrorNamingThePath) {
  const fs::path file = "/nonexistent_dir/x.png";
  const auto cloud = helix(100);
  try {
    sgdicp::render_alignment_png(file, cloud, cloud, Eigen::Matrix4d::Identity());
    FAIL() << "expected IoError";
  } catch (const sgdicp::IoError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
}

/// A circle of `n` poses (radius 2 m, rising slowly), the camera turning with it.
std::vector<Eigen::Matrix4d> circle_path(const int n) {
  std::vector<Eigen::Matrix4d> poses;
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * 3.141592653589793 * i / n;
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(t, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.topRightCorner<3, 1>() << 2.0 * std::cos(t), 2.0 * std::sin(t), 0.01 * i;
    poses.push_back(T);
  }
  return poses;
}

TEST(RenderTrajectories, WritesPngWithAndWithoutGroundTruth) {
  const TempDir dir;
  const auto truth = circle_path(200);
  auto estimate = truth;
  for (auto& T : estimate) T(0, 3) += 0.05;  // 5 cm off: a second line beside the first
  sgdicp::render_trajectories_png(dir.path() / "both.png", estimate, truth,
                                  Eigen::Matrix4d::Identity(), {800, 400, 200000});
  sgdicp::render_trajectories_png(dir.path() / "again.png", estimate, truth,
                                  Eigen::Matrix4d::Identity(), {800, 400, 200000});
  sgdicp::render_trajectories_png(dir.path() / "alone.png", estimate, {},
                                  Eigen::Matrix4d::Identity(), {800, 400, 200000});
  Eigen::Matrix4d shift = Eigen::Matrix4d::Identity();
  shift(1, 3) = 0.5;  // the alignment moves the estimate
  sgdicp::render_trajectories_png(dir.path() / "shifted.png", estimate, truth, shift,
                                  {800, 400, 200000});
  const auto both = read_bytes(dir.path() / "both.png");
  expect_png(both, 800, 400);
  EXPECT_EQ(both, read_bytes(dir.path() / "again.png"));
  EXPECT_NE(both, read_bytes(dir.path() / "alone.png"));
  EXPECT_NE(both, read_bytes(dir.path() / "shifted.png"));
  expect_png(read_bytes(dir.path() / "alone.png"), 800, 400);
  // One pose (no path) still draws.
  sgdicp::render_trajectories_png(dir.path() / "one.png", {Eigen::Matrix4d::Identity()}, {},
                                  Eigen::Matrix4d::Identity());
  expect_png(read_bytes(dir.path() / "one.png"), 1200, 600);
}

TEST(RenderTrajectories, RejectsEmptyOrNonFinitePoses) {
  const TempDir dir;
  const fs::path file = dir.path() / "x.png";
  const auto path = circle_path(10);
  const Eigen::Matrix4d I = Eigen::Matrix4d::Identity();
  EXPECT_THROW(sgdicp::render_trajectories_png(file, {}, path, I), sgdicp::InvalidInputError);
  auto bad = path;
  bad[3](0, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sgdicp::render_trajectories_png(file, bad, path, I), sgdicp::InvalidInputError);
  EXPECT_THROW(sgdicp::render_trajectories_png(file, path, bad, I), sgdicp::InvalidInputError);
  Eigen::Matrix4d inf = I;
  inf(2, 3) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(sgdicp::render_trajectories_png(file, path, path, inf), sgdicp::InvalidInputError);
  EXPECT_THROW(sgdicp::render_trajectories_png(file, path, {}, I, {63, 600, 1000}),
               sgdicp::InvalidSettingsError);
  EXPECT_FALSE(fs::exists(file));
}

}  // namespace
