#pragma once
// What the point-cloud readers and writers (src/io/*.cpp, behind sgdicp/io/io.hpp) share: the
// error messages, byte and text helpers, the text cursor, the one PointSink every reader hands
// its points to, and the entry point of each format. Internal: not installed.
#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "io/files.hpp"
#include "io/parse_number.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/io/io.hpp"

namespace sgdicp::io_detail {

namespace fs = std::filesystem;

constexpr std::size_t kNoLimit = std::numeric_limits<std::size_t>::max();

// ---------------------------------------------------------------------------------------------
// Errors (common.cpp)

[[noreturn]] void fail_line(const std::string& name, std::size_t line, const std::string& what);
[[noreturn]] void fail_byte(const std::string& name, std::size_t byte, const std::string& what);
// A token from the file, quoted and shortened so a binary blob cannot flood the message.
std::string shown(std::string_view token);
std::string system_message(int error_number);

// ---------------------------------------------------------------------------------------------
// Arithmetic and byte helpers

std::optional<std::uint64_t> checked_mul(std::uint64_t a, std::uint64_t b);
std::optional<std::uint64_t> checked_add(std::uint64_t a, std::uint64_t b);
std::string byte_count_text(std::optional<std::uint64_t> bytes);

// Reads a T stored in the given byte order; memcpy because file data has no alignment.
template <typename T>
T load(const char* p, bool big_endian) {
  std::array<char, sizeof(T)> raw{};
  std::memcpy(raw.data(), p, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(raw.begin(), raw.end());
  return std::bit_cast<T>(raw);
}

template <typename T>
void append_little_endian(std::string& out, T value) {
  auto raw = std::bit_cast<std::array<char, sizeof(T)>>(value);
  if constexpr (std::endian::native == std::endian::big) std::reverse(raw.begin(), raw.end());
  out.append(raw.data(), raw.size());
}

// ---------------------------------------------------------------------------------------------
// Text helpers

inline bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

inline std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool iequals(std::string_view a, std::string_view b);
std::string lowercase(std::string_view s);
std::vector<std::string_view> split_whitespace(std::string_view line);
bool parse_uint(std::string_view token, std::uint64_t& out);
// Whether a token is an integer (one optional sign) that fits `bytes` bytes, signed or not:
// the text of an integer field, where "banana", "1.5" or "300" for a uchar are errors.
bool is_integer_token(std::string_view token, std::size_t bytes, bool is_signed);

// Walks text by lines or by whitespace-separated tokens and keeps the line number for messages.
class TextCursor {
 public:
  TextCursor(std::string_view data, std::size_t offset, std::size_t line)
      : data_(data), pos_(offset), line_(line), next_line_(line) {}

  // The next line without its terminator ("\n" or "\r\n"); false at the end of the data.
  bool next_line(std::string_view& out) {
    if (pos_ >= data_.size()) return false;
    const std::size_t newline = data_.find('\n', pos_);
    const std::size_t stop = newline == std::string_view::npos ? data_.size() : newline;
    out = data_.substr(pos_, stop - pos_);
    if (!out.empty() && out.back() == '\r') out.remove_suffix(1);
    pos_ = newline == std::string_view::npos ? data_.size() : newline + 1;
    line_ = next_line_++;
    return true;
  }

  // The next token, crossing line ends; false at the end of the data.
  bool next_token(std::string_view& out) {
    while (pos_ < data_.size() && is_space(data_[pos_])) {
      if (data_[pos_] == '\n') ++next_line_;
      ++pos_;
    }
    if (pos_ >= data_.size()) return false;
    const std::size_t start = pos_;
    while (pos_ < data_.size() && !is_space(data_[pos_])) ++pos_;
    out = data_.substr(start, pos_ - start);
    line_ = next_line_;
    return true;
  }

  /// Line number of the last line or token returned.
  [[nodiscard]] std::size_t line() const { return line_; }
  /// Byte offset of the first unread character.
  [[nodiscard]] std::size_t offset() const { return pos_; }
  [[nodiscard]] std::size_t remaining() const { return data_.size() - pos_; }

 private:
  std::string_view data_;
  std::size_t pos_;
  std::size_t line_;       // line of the last returned line or token
  std::size_t next_line_;  // line that pos_ is on
};

// ---------------------------------------------------------------------------------------------
// Files (files.cpp; read_whole_file and limit_text in files.hpp)

void write_whole_file(const fs::path& path, const std::string& name, std::string_view data);

// ---------------------------------------------------------------------------------------------
// Output of the readers

// Every reader hands each parsed point here, in double: the one place where coordinates are
// converted to the float storage and non-finite points are dropped and counted. A reader of a
// file with per-point times calls record_times() first, then add() with each point's time.
class PointSink {
 public:
  PointSink(const std::string& name, ReadResult& result) : name_(name), result_(result) {}

  void record_times() { timed_ = true; }

  void add(double x, double y, double z) { add_point(x, y, z, true); }

  // A point without a usable time is dropped like one without usable coordinates: deskewing
  // could not place it. Times beyond float's range count as non-finite, as coordinates do.
  void add(double x, double y, double z, double time_s) {
    const bool usable = std::abs(time_s) <= std::numeric_limits<float>::max();
    if (add_point(x, y, z, usable)) times_s_.push_back(time_s);
  }

  // Reserves for a declared count, but never more than the data could hold: a header can lie.
  void reserve(std::uint64_t declared, std::size_t upper_bound) {
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(declared, upper_bound));
    result_.cloud.points.reserve(n);
    if (timed_) times_s_.reserve(n);
  }

  // Stores the times relative to the earliest, subtracted in double so that absolute clocks
  // (UNIX time, 1.7e9 s) keep their microseconds in float.
  void finish();

  [[nodiscard]] ReadResult& result() { return result_; }

 private:
  // Whether the point was kept.
  bool add_point(double x, double y, double z, bool time_usable) {
    if (++seen_ > kMaxCloudPoints) {
      throw FormatError(name_ + ": more than the largest cloud read (" +
                        std::to_string(kMaxCloudPoints) + " points)");
    }
    // The first finite point sets the origin the points are stored from (0 unless the cloud is
    // georeferenced: point_cloud.hpp); beyond the float range counts as non-finite too.
    if (!has_origin_ && std::isfinite(x) && std::isfinite(y) && std::isfinite(z)) {
      result_.cloud.origin_m = georeferencing_origin({x, y, z});
      has_origin_ = true;
    }
    const Eigen::Vector3d& origin = result_.cloud.origin_m;
    const float xf = to_float_saturating(x - origin.x());
    const float yf = to_float_saturating(y - origin.y());
    const float zf = to_float_saturating(z - origin.z());
    if (time_usable && std::isfinite(xf) && std::isfinite(yf) && std::isfinite(zf)) {
      result_.cloud.points.emplace_back(xf, yf, zf);
      return true;
    }
    ++result_.non_finite_dropped;
    return false;
  }

  const std::string& name_;
  ReadResult& result_;
  std::uint64_t seen_ = 0;
  bool has_origin_ = false;
  bool timed_ = false;
  std::vector<double> times_s_;  // of the kept points, as in the file (seconds)
};

// ---------------------------------------------------------------------------------------------
// Per-point times (common.cpp; docs/io.md, "Per-point times")

// Rank of a field name among the per-point time fields drivers write, 0 the highest priority
// (Ouster t, Livox offset_time, Velodyne time, Hesai timestamp); nullopt for any other name.
std::optional<std::size_t> time_field_rank(std::string_view field_name);

// Seconds per unit of a time field: an integer field counts nanoseconds, a floating one seconds.
inline double time_field_unit_s(bool is_integer) {
  return is_integer ? 1e-9 : 1.0;
}

// Index of the time field among the named fields: the recognised name of highest priority, or
// nullopt. `name_of(i)` gives the name of field i.
template <typename NameOf>
std::optional<std::size_t> find_time_field(std::size_t fields, const NameOf& name_of) {
  std::optional<std::size_t> best;
  std::optional<std::size_t> best_rank;
  for (std::size_t i = 0; i < fields; ++i) {
    const auto rank = time_field_rank(name_of(i));
    if (rank && (!best_rank || *rank < *best_rank)) {
      best = i;
      best_rank = rank;
    }
  }
  return best;
}

// A declared point count beyond the largest cloud: the message names the count and the limit.
bool beyond_cloud_limit(std::uint64_t points);
std::string cloud_limit_text(std::uint64_t points);

// Smallest text for one point: "0 0 0\n".
constexpr std::size_t kMinTextPointBytes = 6;

// ---------------------------------------------------------------------------------------------
// The formats: one reader per file (pcd.cpp, ply.cpp, float_records.cpp, text.cpp, vtk.cpp)

void read_pcd(const std::string& name, std::string_view data, PointSink& sink);
void read_ply(const std::string& name, std::string_view data, PointSink& sink);
// Headerless float32 records (KITTI .bin: 4 floats, .f32: 3 floats).
void read_float_records(const std::string& name, std::string_view data, std::size_t floats,
                        const std::string& layout, PointSink& sink);
void read_xyz(const std::string& name, std::string_view data, PointSink& sink);
void read_vtk(const std::string& name, std::string_view data, PointSink& sink);

// ---------------------------------------------------------------------------------------------
// Writers (common.cpp; the headers in pcd.cpp and ply.cpp)

// A georeferenced cloud (origin_m not zero) is written as origin + point in double, which float
// cannot hold; any other cloud as the floats it stores.
bool written_in_double(const PointCloud& cloud);
// With `with_times`, each point's time follows its x y z as a float (seconds).
void append_points_text(std::string& out, const PointCloud& cloud, bool with_times = false);
void append_points_binary(std::string& out, const PointCloud& cloud, bool with_times = false);
std::string ply_text(const PointCloud& cloud, Encoding encoding);
std::string pcd_text(const PointCloud& cloud, Encoding encoding);

}  // namespace sgdicp::io_detail
