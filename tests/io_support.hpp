#pragma once
// What the tests of the point-cloud readers and writers (test_io*.cpp) share: binary content in
// either byte order, a fresh directory per test, PCD headers and LZF blocks, checks of the points
// read and of the errors thrown.
#include <lzf.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <ios>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>

#include <gtest/gtest.h>

#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

namespace sgdicp::io_test {

namespace fs = std::filesystem;

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline constexpr float kInf = std::numeric_limits<float>::infinity();

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

inline bool same_bits(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

// A coordinate of a read point in the file's frame: the readers store points from an origin
// (0 unless the first point lies beyond 16 km: georeferencing_origin in point_cloud.hpp).
inline double absolute(const PointCloud& cloud, std::size_t i, int k) {
  return static_cast<double>(cloud.points[i][k]) + cloud.origin_m[k];
}

inline void expect_points(const ReadResult& r,
                          std::initializer_list<std::array<float, 3>> expected) {
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
inline std::string expect_error(const fs::path& path, std::initializer_list<std::string_view> parts,
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

inline std::string lzf_block(const std::string& raw) {
  std::string out(raw.size() + raw.size() / 16 + 64, '\0');
  const unsigned int n = lzf_compress(raw.data(), static_cast<unsigned int>(raw.size()), out.data(),
                                      static_cast<unsigned int>(out.size()));
  EXPECT_GT(n, 0u);
  out.resize(n);
  return out;
}

inline std::string pcd_header(std::string_view fields, std::string_view size, std::string_view type,
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
inline PointCloud random_cloud(std::size_t n) {
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

// A binary PLY with double x y z, extra properties and a face element before and after vertex.
inline std::string binary_ply(bool big_endian) {
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

// Reads text (or any bytes) given in memory, named "numbers" in the messages.
inline ReadResult read_text(const std::string& text, FileFormat format = FileFormat::xyz) {
  const auto* data = reinterpret_cast<const std::byte*>(text.data());
  return read_point_cloud_from_memory({data, text.size()}, format, "numbers");
}

inline std::string text_error(const std::string& text, FileFormat format = FileFormat::xyz) {
  try {
    (void)read_text(text, format);
  } catch (const FormatError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace sgdicp::io_test
