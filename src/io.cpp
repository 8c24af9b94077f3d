// Point-cloud file I/O. Every reader works on one in-memory copy of the whole file and checks
// each access against its size, so a truncated or lying file ends in a FormatError, never in
// an out-of-bounds read or an allocation the file cannot back.
#include "sgdicp/io.hpp"

#include <lzf.h>

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
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "io_files.hpp"
#include "parse_number.hpp"
#include "sgdicp/error.hpp"

namespace sgdicp {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kNoLimit = std::numeric_limits<std::size_t>::max();

// ---------------------------------------------------------------------------------------------
// Errors

[[noreturn]] void fail_line(const std::string& name, std::size_t line, const std::string& what) {
  throw FormatError(name + ": line " + std::to_string(line) + ": " + what);
}

[[noreturn]] void fail_byte(const std::string& name, std::size_t byte, const std::string& what) {
  throw FormatError(name + ": byte " + std::to_string(byte) + ": " + what);
}

// A token from the file, quoted and shortened so a binary blob cannot flood the message.
std::string shown(std::string_view token) {
  constexpr std::size_t kMaxShown = 40;
  std::string out = "'";
  for (const char c : token.substr(0, kMaxShown)) {
    out += std::isprint(static_cast<unsigned char>(c)) != 0 ? c : '?';
  }
  if (token.size() > kMaxShown) out += "...";
  return out + "'";
}

std::string system_message(int error_number) {
  return std::generic_category().message(error_number != 0 ? error_number : EIO);
}

// ---------------------------------------------------------------------------------------------
// Arithmetic and byte helpers

std::optional<std::uint64_t> checked_mul(std::uint64_t a, std::uint64_t b) {
  if (a != 0 && b > std::numeric_limits<std::uint64_t>::max() / a) return std::nullopt;
  return a * b;
}

std::optional<std::uint64_t> checked_add(std::uint64_t a, std::uint64_t b) {
  if (b > std::numeric_limits<std::uint64_t>::max() - a) return std::nullopt;
  return a + b;
}

std::string byte_count_text(std::optional<std::uint64_t> bytes) {
  return bytes ? std::to_string(*bytes)
               : "more than " + std::to_string(std::numeric_limits<std::uint64_t>::max());
}

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

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

std::string lowercase(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::vector<std::string_view> split_whitespace(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

bool parse_uint(std::string_view token, std::uint64_t& out) {
  const char* const last = token.data() + token.size();
  const auto [end, error] = std::from_chars(token.data(), last, out);
  return !token.empty() && error == std::errc() && end == last;
}

// Whether a token is an integer (one optional sign) that fits `bytes` bytes, signed or not:
// the text of an integer field, where "banana", "1.5" or "300" for a uchar are errors.
bool is_integer_token(std::string_view token, std::size_t bytes, bool is_signed) {
  if (token.starts_with('+')) token.remove_prefix(1);
  if (token.empty() || token.front() == '+') return false;
  const char* const last = token.data() + token.size();
  const unsigned bits = static_cast<unsigned>(bytes * 8);
  if (is_signed) {
    std::int64_t v = 0;
    const auto [end, error] = std::from_chars(token.data(), last, v);
    if (error != std::errc() || end != last) return false;
    const std::int64_t max =
        bits >= 64 ? std::numeric_limits<std::int64_t>::max() : (std::int64_t{1} << (bits - 1)) - 1;
    return v <= max && v >= -max - 1;
  }
  std::uint64_t v = 0;
  const auto [end, error] = std::from_chars(token.data(), last, v);
  if (error != std::errc() || end != last) return false;
  return bits >= 64 || v <= (std::uint64_t{1} << bits) - 1;
}

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
// Files

struct FileCloser {
  void operator()(std::FILE* file) const noexcept { std::fclose(file); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

}  // namespace

std::string limit_text(std::uint64_t bytes) {
  return std::to_string(bytes) + " bytes = " + std::to_string(bytes >> 30) + " GiB";
}

namespace {

// Only regular files: a device or FIFO has no size to check, and /dev/zero never ends.
void check_regular_file(const fs::path& path, const std::string& name) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || status.type() == fs::file_type::regular) return;  // missing: fopen says why
  if (status.type() == fs::file_type::directory) {
    throw IoError(name + ": cannot read: " + system_message(EISDIR));
  }
  const char* kind = status.type() == fs::file_type::character ? "a character device"
                     : status.type() == fs::file_type::block   ? "a block device"
                     : status.type() == fs::file_type::fifo    ? "a FIFO"
                     : status.type() == fs::file_type::socket  ? "a socket"
                                                               : "not a regular file";
  throw IoError(name + ": " + kind +
                " (only regular files are read, so that their size bounds what is read)");
}

}  // namespace

std::vector<char> read_whole_file(const fs::path& path, const std::string& name) {
  check_regular_file(path, name);
  errno = 0;
  const FilePtr file(std::fopen(path.string().c_str(), "rb"));
  if (!file) throw IoError(name + ": cannot open: " + system_message(errno));
  std::error_code size_error;
  const auto expected = fs::file_size(path, size_error);
  if (size_error) throw IoError(name + ": cannot read the size: " + size_error.message());
  const auto too_large = [&]() {
    return IoError(name + ": larger than the largest file read (" + limit_text(kMaxFileBytes) +
                   ")");
  };
  if (expected > kMaxFileBytes) throw too_large();
  // One byte more than expected so that the end of file is seen by the first read; a file that
  // grows while it is read is still bounded by kMaxFileBytes.
  std::vector<char> bytes(static_cast<std::size_t>(expected) + 1);
  std::size_t used = 0;
  for (;;) {
    if (used == bytes.size()) {
      if (used > kMaxFileBytes) throw too_large();
      bytes.resize(std::min<std::size_t>(bytes.size() * 2, kMaxFileBytes + 1));
    }
    errno = 0;
    const std::size_t got = std::fread(bytes.data() + used, 1, bytes.size() - used, file.get());
    used += got;
    if (std::ferror(file.get()) != 0) {
      throw IoError(name + ": cannot read: " + system_message(errno));
    }
    if (got == 0) break;
  }
  bytes.resize(used);
  return bytes;
}

namespace {

void write_whole_file(const fs::path& path, const std::string& name, std::string_view data) {
  errno = 0;
  FilePtr file(std::fopen(path.string().c_str(), "wb"));
  if (!file) throw IoError(name + ": cannot open for writing: " + system_message(errno));
  errno = 0;
  if (std::fwrite(data.data(), 1, data.size(), file.get()) != data.size()) {
    throw IoError(name + ": cannot write: " + system_message(errno));
  }
  // fclose flushes, so its failure (e.g. a full disk) is a write failure too.
  errno = 0;
  if (std::fclose(file.release()) != 0) {
    throw IoError(name + ": cannot write: " + system_message(errno));
  }
}

// ---------------------------------------------------------------------------------------------
// Output of the readers

// Every reader hands each parsed point here, in double: the one place where coordinates are
// converted to the float storage and non-finite points are dropped and counted.
class PointSink {
 public:
  PointSink(const std::string& name, ReadResult& result) : name_(name), result_(result) {}

  void add(double x, double y, double z) {
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
    if (std::isfinite(xf) && std::isfinite(yf) && std::isfinite(zf)) {
      result_.cloud.points.emplace_back(xf, yf, zf);
    } else {
      ++result_.non_finite_dropped;
    }
  }

  // Reserves for a declared count, but never more than the data could hold: a header can lie.
  void reserve(std::uint64_t declared, std::size_t upper_bound) {
    result_.cloud.points.reserve(
        static_cast<std::size_t>(std::min<std::uint64_t>(declared, upper_bound)));
  }

  [[nodiscard]] ReadResult& result() { return result_; }

 private:
  const std::string& name_;
  ReadResult& result_;
  std::uint64_t seen_ = 0;
  bool has_origin_ = false;
};

// A declared point count beyond the largest cloud: the message names the count and the limit.
bool beyond_cloud_limit(std::uint64_t points) {
  return points > kMaxCloudPoints;
}

std::string cloud_limit_text(std::uint64_t points) {
  return std::to_string(points) + " points exceed the largest cloud read (" +
         std::to_string(kMaxCloudPoints) + " points)";
}

// Smallest text for one point: "0 0 0\n".
constexpr std::size_t kMinTextPointBytes = 6;

// ---------------------------------------------------------------------------------------------
// PCD

enum class PcdData { ascii, binary, binary_compressed };

struct PcdField {
  std::string name;
  std::size_t size = 0;  // bytes per value
  char type = 0;         // 'I', 'U' or 'F'
  std::uint64_t count = 1;
};

struct PcdHeader {
  std::vector<PcdField> fields;
  std::uint64_t width = 0;
  std::uint64_t height = 1;
  std::uint64_t points = 0;
  PcdData data = PcdData::ascii;
  std::size_t data_offset = 0;
  std::size_t data_line = 0;  // line of the DATA key
  std::size_t fields_line = 0;
  std::size_t type_line = 0;
  std::size_t points_line = 0;
  std::array<std::size_t, 3> xyz{};  // field index of x, y, z
};

PcdHeader parse_pcd_header(const std::string& name, TextCursor& cursor) {
  PcdHeader header;
  bool have_fields = false;
  bool have_size = false;
  bool have_type = false;
  bool have_width = false;
  bool have_points = false;
  bool have_data = false;
  std::string_view line;
  while (!have_data && cursor.next_line(line)) {
    const std::size_t at = cursor.line();
    const auto tokens = split_whitespace(line);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    const std::string_view key = tokens[0];
    const std::span<const std::string_view> values(tokens.begin() + 1, tokens.end());
    const auto expect_values = [&](std::size_t n) {
      if (values.size() != n) {
        fail_line(name, at,
                  std::string(key) + " needs " + std::to_string(n) + " value(s), got " +
                      std::to_string(values.size()));
      }
    };
    const auto per_field = [&]() {
      if (!have_fields) fail_line(name, at, std::string(key) + " before FIELDS");
      expect_values(header.fields.size());
    };
    const auto uint_value = [&](std::string_view token) {
      std::uint64_t v = 0;
      if (!parse_uint(token, v)) {
        fail_line(name, at, std::string(key) + " value " + shown(token) + " is not a count");
      }
      return v;
    };

    if (key == "VERSION") {
      expect_values(1);
      constexpr std::array<std::string_view, 6> kKnown = {".5", "0.5", ".6", "0.6", ".7", "0.7"};
      if (std::find(kKnown.begin(), kKnown.end(), values[0]) == kKnown.end()) {
        fail_line(name, at, "unsupported PCD version " + shown(values[0]));
      }
    } else if (key == "FIELDS" || key == "COLUMNS") {  // COLUMNS: the v0.5 spelling
      if (have_fields) fail_line(name, at, "second FIELDS line");
      if (values.empty()) fail_line(name, at, "FIELDS lists no field");
      for (const auto v : values) header.fields.push_back(PcdField{std::string(v)});
      have_fields = true;
      header.fields_line = at;
    } else if (key == "SIZE") {
      per_field();
      for (std::size_t i = 0; i < values.size(); ++i) {
        const auto size = uint_value(values[i]);
        if (size != 1 && size != 2 && size != 4 && size != 8) {
          fail_line(name, at, "SIZE of field '" + header.fields[i].name + "' must be 1, 2, 4 or 8");
        }
        header.fields[i].size = static_cast<std::size_t>(size);
      }
      have_size = true;
    } else if (key == "TYPE") {
      per_field();
      for (std::size_t i = 0; i < values.size(); ++i) {
        if (values[i] != "I" && values[i] != "U" && values[i] != "F") {
          fail_line(name, at,
                    "TYPE " + shown(values[i]) + " of field '" + header.fields[i].name +
                        "' is not I, U or F");
        }
        header.fields[i].type = values[i][0];
      }
      have_type = true;
      header.type_line = at;
    } else if (key == "COUNT") {
      per_field();
      for (std::size_t i = 0; i < values.size(); ++i) {
        header.fields[i].count = uint_value(values[i]);
        if (header.fields[i].count == 0) {
          fail_line(name, at, "COUNT of field '" + header.fields[i].name + "' is 0");
        }
      }
    } else if (key == "WIDTH") {
      expect_values(1);
      header.width = uint_value(values[0]);
      have_width = true;
    } else if (key == "HEIGHT") {
      expect_values(1);
      header.height = uint_value(values[0]);
    } else if (key == "VIEWPOINT") {
      expect_values(7);
      for (const auto v : values) {
        if (double f = 0.0; !parse_number(v, f)) {
          fail_line(name, at, "VIEWPOINT value " + shown(v) + " is not a number");
        }
      }
    } else if (key == "POINTS") {
      expect_values(1);
      header.points = uint_value(values[0]);
      have_points = true;
      header.points_line = at;
    } else if (key == "DATA") {
      expect_values(1);
      if (values[0] == "ascii") {
        header.data = PcdData::ascii;
      } else if (values[0] == "binary") {
        header.data = PcdData::binary;
      } else if (values[0] == "binary_compressed") {
        header.data = PcdData::binary_compressed;
      } else {
        fail_line(name, at,
                  "unknown DATA " + shown(values[0]) + " (ascii, binary or binary_compressed)");
      }
      have_data = true;
      header.data_line = at;
      header.data_offset = cursor.offset();
    } else {
      fail_line(name, at, "unknown PCD header key " + shown(key));
    }
  }

  const std::size_t end_line = cursor.line();
  if (!have_data) fail_line(name, end_line, "PCD header has no DATA line");
  if (!have_fields) fail_line(name, end_line, "PCD header has no FIELDS line");
  if (!have_size) fail_line(name, end_line, "PCD header has no SIZE line");
  if (!have_type) fail_line(name, end_line, "PCD header has no TYPE line");
  if (!have_width) fail_line(name, end_line, "PCD header has no WIDTH line");

  for (const auto& field : header.fields) {
    if (field.type == 'F' && field.size != 4 && field.size != 8) {
      fail_line(name, header.type_line,
                "float field '" + field.name + "' has SIZE " + std::to_string(field.size) +
                    " (only 4 or 8)");
    }
  }
  constexpr std::array<std::string_view, 3> kAxes = {"x", "y", "z"};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const auto found = std::find_if(header.fields.begin(), header.fields.end(),
                                    [&](const PcdField& f) { return f.name == kAxes[axis]; });
    if (found == header.fields.end()) {
      fail_line(name, header.fields_line, "PCD has no '" + std::string(kAxes[axis]) + "' field");
    }
    if (std::find_if(found + 1, header.fields.end(), [&](const PcdField& f) {
          return f.name == kAxes[axis];
        }) != header.fields.end()) {
      fail_line(name, header.fields_line, "field '" + found->name + "' appears twice");
    }
    if (found->type != 'F' || found->count != 1) {
      fail_line(
          name, header.type_line,
          "field '" + found->name + "' must be a single float (TYPE F, SIZE 4 or 8, COUNT 1)");
    }
    header.xyz[axis] = static_cast<std::size_t>(found - header.fields.begin());
  }

  const auto cells = checked_mul(header.width, header.height);
  if (!have_points) {
    if (!cells) fail_line(name, header.data_line, "WIDTH x HEIGHT overflows");
    header.points = *cells;
  } else if (!cells || *cells != header.points) {
    fail_line(name, header.points_line,
              "POINTS " + std::to_string(header.points) + " does not match WIDTH x HEIGHT = " +
                  std::to_string(header.width) + " x " + std::to_string(header.height));
  }
  if (beyond_cloud_limit(header.points)) {
    fail_line(name, have_points ? header.points_line : header.data_line,
              cloud_limit_text(header.points));
  }
  return header;
}

// Every value of a data line is of its field's type: a number for F, an integer that fits SIZE
// bytes for I and U. The line has as many values as the fields' COUNTs add up to.
void check_pcd_values(const std::string& name, std::size_t line_number, const PcdHeader& header,
                      std::string_view line) {
  std::size_t field = 0;
  std::uint64_t left = header.fields.empty() ? 0 : header.fields[0].count;
  for (const std::string_view token : split_whitespace(line)) {
    while (left == 0) left = header.fields[++field].count;
    const PcdField& f = header.fields[field];
    double ignored = 0.0;
    const bool ok = f.type == 'F' ? parse_number(token, ignored)
                                  : is_integer_token(token, f.size, f.type == 'I');
    if (!ok) {
      fail_line(name, line_number,
                shown(token) + " is not " +
                    (f.type == 'F'
                         ? std::string("a number")
                         : (f.type == 'I' ? "a signed" : "an unsigned") +
                               std::string(" integer of ") + std::to_string(f.size) + " byte(s)") +
                    " (field '" + f.name + "')");
    }
    --left;
  }
}

void read_pcd_ascii(const std::string& name, const PcdHeader& header, TextCursor& cursor,
                    PointSink& sink) {
  // Column of x, y and z on a line, where fields with COUNT > 1 take several columns.
  std::array<std::uint64_t, 3> column{};
  std::uint64_t columns = 0;
  for (std::size_t f = 0; f < header.fields.size(); ++f) {
    for (std::size_t axis = 0; axis < 3; ++axis) {
      if (header.xyz[axis] == f) column[axis] = columns;
    }
    const auto next = checked_add(columns, header.fields[f].count);
    if (!next) fail_line(name, header.data_line, "COUNT values overflow");
    columns = *next;
  }

  sink.reserve(header.points, cursor.remaining() / kMinTextPointBytes);
  std::uint64_t read = 0;
  std::string_view line;
  while (read < header.points) {
    if (!cursor.next_line(line)) {
      fail_line(name, cursor.line(),
                "expected " + std::to_string(header.points) + " points, file ends after " +
                    std::to_string(read));
    }
    std::array<std::string_view, 3> xyz;
    std::uint64_t count = 0;
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && is_space(line[i])) ++i;
      const std::size_t start = i;
      while (i < line.size() && !is_space(line[i])) ++i;
      if (i == start) break;
      for (std::size_t axis = 0; axis < 3; ++axis) {
        if (column[axis] == count) xyz[axis] = line.substr(start, i - start);
      }
      ++count;
    }
    if (count == 0) continue;  // blank line
    if (count != columns) {
      fail_line(name, cursor.line(),
                "expected " + std::to_string(columns) + " values, got " + std::to_string(count));
    }
    check_pcd_values(name, cursor.line(), header, line);
    std::array<double, 3> p{};
    for (std::size_t axis = 0; axis < 3; ++axis) {
      if (!parse_number(xyz[axis], p[axis])) {
        fail_line(name, cursor.line(), shown(xyz[axis]) + " is not a number");
      }
    }
    sink.add(p[0], p[1], p[2]);
    ++read;
  }
  while (cursor.next_line(line)) {
    if (!trim(line).empty()) {
      fail_line(name, cursor.line(),
                "more data than POINTS " + std::to_string(header.points) + " declares");
    }
  }
}

double load_pcd_coordinate(const char* p, std::size_t size) {
  return size == 4 ? load<float>(p, false) : load<double>(p, false);
}

// Byte layout of one point: offset of each field and the total size.
struct PcdLayout {
  std::vector<std::uint64_t> field_offset;
  std::uint64_t point_size = 0;
};

PcdLayout pcd_layout(const std::string& name, const PcdHeader& header) {
  PcdLayout layout;
  for (const auto& field : header.fields) {
    layout.field_offset.push_back(layout.point_size);
    const auto bytes = checked_mul(field.size, field.count);
    const auto next = bytes ? checked_add(layout.point_size, *bytes) : std::nullopt;
    if (!next) fail_line(name, header.data_line, "point size overflows");
    layout.point_size = *next;
  }
  return layout;
}

// The bytes after binary point data must be none, or zeros that fill a page: PCL before 1.10
// stretched its files to a page (4096 bytes, up to 64 KiB on some systems) plus the data.
void check_pcd_end(const std::string& name, std::string_view data, std::size_t end) {
  constexpr std::size_t kLargestPage = std::size_t{1} << 16;
  const std::string_view rest = data.substr(end);
  const bool page_padding =
      rest.size() < kLargestPage && rest.find_first_not_of('\0') == std::string_view::npos;
  if (!page_padding) {
    fail_byte(name, end,
              std::to_string(rest.size()) +
                  " bytes after the point data (only zeros that fill a page may follow)");
  }
}

void read_pcd_binary(const std::string& name, const PcdHeader& header, std::string_view data,
                     PointSink& sink) {
  const PcdLayout layout = pcd_layout(name, header);
  const std::size_t available = data.size() - header.data_offset;
  const auto need = checked_mul(header.points, layout.point_size);
  if (!need || *need > available) {
    fail_byte(name, header.data_offset,
              "truncated binary data (need " + byte_count_text(need) +
                  " bytes of point data, have " + std::to_string(available) + ")");
  }
  check_pcd_end(name, data, header.data_offset + static_cast<std::size_t>(*need));
  const char* const base = data.data() + header.data_offset;
  const std::size_t step = static_cast<std::size_t>(layout.point_size);
  std::array<std::size_t, 3> offset{};
  std::array<std::size_t, 3> size{};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    offset[axis] = static_cast<std::size_t>(layout.field_offset[header.xyz[axis]]);
    size[axis] = header.fields[header.xyz[axis]].size;
  }
  const auto n = static_cast<std::size_t>(header.points);
  sink.reserve(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    const char* const point = base + i * step;
    sink.add(load_pcd_coordinate(point + offset[0], size[0]),
             load_pcd_coordinate(point + offset[1], size[1]),
             load_pcd_coordinate(point + offset[2], size[2]));
  }
}

// Size of the output of an LZF block, found by walking its control bytes without writing
// anything, so that a lying or corrupt block is rejected before its output is allocated.
// nullopt when the block is corrupt: a run or reference cut off by the end, or a back reference
// to before the start of the output. Format: a control byte c < 32 starts a run of c + 1 literal
// bytes; otherwise it is a back reference of length (c >> 5) + 2 (a second byte extends length
// 7), its offset ((c & 31) << 8) + the next byte + 1.
std::optional<std::uint64_t> lzf_output_size(std::string_view block) {
  std::uint64_t out = 0;
  std::size_t in = 0;
  while (in < block.size()) {
    const auto control = static_cast<unsigned char>(block[in++]);
    if (control < 32) {
      const std::size_t run = control + 1u;
      if (run > block.size() - in) return std::nullopt;
      in += run;
      out += run;
      continue;
    }
    std::uint64_t length = control >> 5;
    if (length == 7) {
      if (in >= block.size()) return std::nullopt;
      length += static_cast<unsigned char>(block[in++]);
    }
    if (in >= block.size()) return std::nullopt;
    const std::uint64_t offset =
        ((std::uint64_t{control} & 31u) << 8) + static_cast<unsigned char>(block[in++]) + 1;
    if (offset > out) return std::nullopt;
    out += length + 2;
  }
  return out;
}

void read_pcd_compressed(const std::string& name, const PcdHeader& header, std::string_view data,
                         PointSink& sink) {
  // The most LZF can expand: a 3-byte back reference emits at most 264 bytes.
  constexpr std::uint64_t kMaxLzfRatio = 264 / 3;
  const PcdLayout layout = pcd_layout(name, header);
  const std::size_t start = header.data_offset;
  const std::size_t available = data.size() - start;
  if (available < 8) {
    fail_byte(name, start,
              "truncated compressed header (need 8 bytes, have " + std::to_string(available) + ")");
  }
  const auto compressed = load<std::uint32_t>(data.data() + start, false);
  const auto uncompressed = load<std::uint32_t>(data.data() + start + 4, false);
  const auto need = checked_mul(header.points, layout.point_size);
  if (!need || *need != uncompressed) {
    fail_byte(name, start + 4,
              "uncompressed size " + std::to_string(uncompressed) +
                  " does not match POINTS x point size = " + byte_count_text(need));
  }
  if (compressed > available - 8) {
    fail_byte(name, start + 8,
              "truncated compressed data (need " + std::to_string(compressed) + " bytes, have " +
                  std::to_string(available - 8) + ")");
  }
  check_pcd_end(name, data, start + 8 + compressed);
  if (uncompressed == 0) return;
  if (uncompressed > std::uint64_t{compressed} * kMaxLzfRatio) {
    fail_byte(name, start + 4,
              "uncompressed size " + std::to_string(uncompressed) + " is impossible for " +
                  std::to_string(compressed) + " bytes of LZF data");
  }
  const std::string_view block = data.substr(start + 8, compressed);
  if (const auto decoded = lzf_output_size(block); decoded != uncompressed) {
    fail_byte(name, start + 8,
              !decoded ? "corrupt LZF data"
                       : "LZF data decompress to " + std::to_string(*decoded) +
                             " bytes, expected " + std::to_string(uncompressed));
  }
  std::vector<char> raw(uncompressed);
  const unsigned int got =
      lzf_decompress(data.data() + start + 8, compressed, raw.data(), uncompressed);
  if (got != uncompressed) {
    fail_byte(name, start + 8,
              got == 0 ? "corrupt LZF data"
                       : "LZF data decompress to " + std::to_string(got) + " bytes, expected " +
                             std::to_string(uncompressed));
  }
  // Structure of arrays: all values of the first field, then all of the second, ...
  const auto n = static_cast<std::size_t>(header.points);
  std::array<const char*, 3> column{};
  std::array<std::size_t, 3> size{};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const std::size_t field = header.xyz[axis];
    column[axis] = raw.data() + n * static_cast<std::size_t>(layout.field_offset[field]);
    size[axis] = header.fields[field].size;
  }
  sink.reserve(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    sink.add(load_pcd_coordinate(column[0] + i * size[0], size[0]),
             load_pcd_coordinate(column[1] + i * size[1], size[1]),
             load_pcd_coordinate(column[2] + i * size[2], size[2]));
  }
}

void read_pcd(const std::string& name, std::string_view data, PointSink& sink) {
  TextCursor cursor(data, 0, 1);
  const PcdHeader header = parse_pcd_header(name, cursor);
  sink.result().points_in_file = static_cast<std::size_t>(header.points);
  switch (header.data) {
    case PcdData::ascii:
      read_pcd_ascii(name, header, cursor, sink);
      break;
    case PcdData::binary:
      read_pcd_binary(name, header, data, sink);
      break;
    case PcdData::binary_compressed:
      read_pcd_compressed(name, header, data, sink);
      break;
  }
}

// ---------------------------------------------------------------------------------------------
// PLY

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };
enum class PlyEncoding { ascii, binary_little_endian, binary_big_endian };

std::optional<PlyType> ply_type(std::string_view name) {
  static constexpr std::array<std::pair<std::string_view, PlyType>, 16> kNames = {{
      {"char", PlyType::i8},
      {"int8", PlyType::i8},
      {"uchar", PlyType::u8},
      {"uint8", PlyType::u8},
      {"short", PlyType::i16},
      {"int16", PlyType::i16},
      {"ushort", PlyType::u16},
      {"uint16", PlyType::u16},
      {"int", PlyType::i32},
      {"int32", PlyType::i32},
      {"uint", PlyType::u32},
      {"uint32", PlyType::u32},
      {"float", PlyType::f32},
      {"float32", PlyType::f32},
      {"double", PlyType::f64},
      {"float64", PlyType::f64},
  }};
  for (const auto& [text, type] : kNames) {
    if (text == name) return type;
  }
  return std::nullopt;
}

// The PLY name of a type, from the table above (its first spelling).
std::string ply_type_name(PlyType type) {
  for (const std::string_view name :
       {"char", "uchar", "short", "ushort", "int", "uint", "float", "double"}) {
    if (ply_type(name) == type) return std::string(name);
  }
  return "value";
}

std::size_t ply_size(PlyType type) {
  switch (type) {
    case PlyType::i8:
    case PlyType::u8:
      return 1;
    case PlyType::i16:
    case PlyType::u16:
      return 2;
    case PlyType::i32:
    case PlyType::u32:
    case PlyType::f32:
      return 4;
    case PlyType::f64:
      return 8;
  }
  return 0;
}

double ply_value(PlyType type, const char* p, bool big_endian) {
  switch (type) {
    case PlyType::i8:
      return load<std::int8_t>(p, big_endian);
    case PlyType::u8:
      return load<std::uint8_t>(p, big_endian);
    case PlyType::i16:
      return load<std::int16_t>(p, big_endian);
    case PlyType::u16:
      return load<std::uint16_t>(p, big_endian);
    case PlyType::i32:
      return load<std::int32_t>(p, big_endian);
    case PlyType::u32:
      return load<std::uint32_t>(p, big_endian);
    case PlyType::f32:
      return load<float>(p, big_endian);
    case PlyType::f64:
      return load<double>(p, big_endian);
  }
  return 0.0;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::f32;  // the item type for a list
  bool is_list = false;
  PlyType count_type = PlyType::u8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  std::size_t line = 0;
};

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::ascii;
  std::vector<PlyElement> elements;
  std::size_t vertex = 0;            // index of the vertex element
  std::array<std::size_t, 3> xyz{};  // property index of x, y, z in it
  std::size_t data_offset = 0;
  std::size_t end_line = 0;  // line of end_header
};

PlyHeader parse_ply_header(const std::string& name, TextCursor& cursor) {
  PlyHeader header;
  std::string_view line;
  if (!cursor.next_line(line) || trim(line) != "ply") {
    fail_line(name, 1, "not a PLY file (the first line must be 'ply')");
  }
  bool have_format = false;
  bool have_end = false;
  while (!have_end && cursor.next_line(line)) {
    const std::size_t at = cursor.line();
    const auto tokens = split_whitespace(line);
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    if (keyword == "format") {
      if (have_format) fail_line(name, at, "second format line");
      const bool known_version = tokens.size() == 3 && (tokens[2] == "1.0" || tokens[2] == "1");
      if (known_version && tokens[1] == "ascii") {
        header.encoding = PlyEncoding::ascii;
      } else if (known_version && tokens[1] == "binary_little_endian") {
        header.encoding = PlyEncoding::binary_little_endian;
      } else if (known_version && tokens[1] == "binary_big_endian") {
        header.encoding = PlyEncoding::binary_big_endian;
      } else {
        fail_line(name, at,
                  "bad format line " + shown(trim(line)) +
                      " (expected 'format ascii|binary_little_endian|binary_big_endian 1.0')");
      }
      have_format = true;
    } else if (keyword == "comment" || keyword == "obj_info") {
      continue;
    } else if (keyword == "element") {
      std::uint64_t count = 0;
      if (tokens.size() != 3 || !parse_uint(tokens[2], count)) {
        fail_line(name, at,
                  "bad element line " + shown(trim(line)) + " (expected 'element <name> <count>')");
      }
      header.elements.push_back(PlyElement{std::string(tokens[1]), count, {}, at});
    } else if (keyword == "property") {
      if (header.elements.empty()) fail_line(name, at, "property before any element");
      PlyProperty property;
      if (tokens.size() == 5 && tokens[1] == "list") {
        const auto count_type = ply_type(tokens[2]);
        const auto item_type = ply_type(tokens[3]);
        if (!count_type || !item_type) {
          fail_line(name, at, "unknown type in " + shown(trim(line)));
        }
        if (*count_type == PlyType::f32 || *count_type == PlyType::f64) {
          fail_line(name, at, "list length type must be an integer type");
        }
        property = PlyProperty{std::string(tokens[4]), *item_type, true, *count_type};
      } else if (tokens.size() == 3) {
        const auto type = ply_type(tokens[1]);
        if (!type) fail_line(name, at, "unknown property type " + shown(tokens[1]));
        property = PlyProperty{std::string(tokens[2]), *type};
      } else {
        fail_line(name, at, "bad property line " + shown(trim(line)));
      }
      header.elements.back().properties.push_back(std::move(property));
    } else if (keyword == "end_header") {
      have_end = true;
      header.end_line = at;
      header.data_offset = cursor.offset();
    } else {
      fail_line(name, at, "unknown PLY header keyword " + shown(keyword));
    }
  }
  if (!have_end) fail_line(name, cursor.line(), "PLY header has no end_header line");
  if (!have_format) fail_line(name, header.end_line, "PLY header has no format line");

  const auto is_vertex = [](const PlyElement& e) { return e.name == "vertex"; };
  const auto vertex = std::find_if(header.elements.begin(), header.elements.end(), is_vertex);
  if (vertex == header.elements.end())
    fail_line(name, header.end_line, "PLY has no vertex element");
  if (std::find_if(vertex + 1, header.elements.end(), is_vertex) != header.elements.end()) {
    fail_line(name, header.end_line, "PLY has two vertex elements");
  }
  header.vertex = static_cast<std::size_t>(vertex - header.elements.begin());
  constexpr std::array<std::string_view, 3> kAxes = {"x", "y", "z"};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const auto& props = vertex->properties;
    const auto found = std::find_if(props.begin(), props.end(),
                                    [&](const PlyProperty& p) { return p.name == kAxes[axis]; });
    if (found == props.end()) {
      fail_line(name, vertex->line,
                "vertex element has no '" + std::string(kAxes[axis]) + "' property");
    }
    if (found->is_list)
      fail_line(name, vertex->line, "vertex property '" + found->name + "' is a list");
    header.xyz[axis] = static_cast<std::size_t>(found - props.begin());
  }
  if (beyond_cloud_limit(vertex->count)) {
    fail_line(name, vertex->line, "element vertex: " + cloud_limit_text(vertex->count));
  }
  return header;
}

// Whether a token is a value of a PLY type: a number for float and double, an integer that
// fits the type for the others.
bool is_ply_value(PlyType type, std::string_view token) {
  double ignored = 0.0;
  if (type == PlyType::f32 || type == PlyType::f64) return parse_number(token, ignored);
  const bool is_signed = type == PlyType::i8 || type == PlyType::i16 || type == PlyType::i32;
  return is_integer_token(token, ply_size(type), is_signed);
}

void read_ply_ascii(const std::string& name, const PlyHeader& header, TextCursor& cursor,
                    PointSink& sink) {
  std::string_view token;
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    const bool is_vertex = e == header.vertex;
    if (element.properties.empty()) continue;  // records without properties take no text
    if (is_vertex) sink.reserve(element.count, cursor.remaining() / kMinTextPointBytes);
    for (std::uint64_t r = 0; r < element.count; ++r) {
      const auto next = [&]() {
        if (!cursor.next_token(token)) {
          fail_line(name, cursor.line(),
                    "unexpected end of file in element '" + element.name + "' (record " +
                        std::to_string(r + 1) + " of " + std::to_string(element.count) + ")");
        }
        return token;
      };
      std::array<double, 3> p{};
      for (std::size_t k = 0; k < element.properties.size(); ++k) {
        const PlyProperty& property = element.properties[k];
        const std::string_view value = next();
        const auto check = [&](PlyType type, std::string_view text) {
          if (!is_ply_value(type, text)) {
            fail_line(name, cursor.line(),
                      shown(text) + " is not " +
                          (type == PlyType::f32 || type == PlyType::f64
                               ? std::string("a number")
                               : "a " + ply_type_name(type) + " value") +
                          " (property '" + property.name + "')");
          }
        };
        if (property.is_list) {
          std::uint64_t length = 0;
          if (!parse_uint(value, length) || !is_ply_value(property.count_type, value)) {
            fail_line(name, cursor.line(),
                      shown(value) + " is not a list length of type " +
                          ply_type_name(property.count_type) + " (property '" + property.name +
                          "')");
          }
          for (std::uint64_t i = 0; i < length; ++i) check(property.type, next());
          continue;
        }
        check(property.type, value);
        if (is_vertex) {
          for (std::size_t axis = 0; axis < 3; ++axis) {
            if (header.xyz[axis] == k && !parse_number(value, p[axis])) {
              fail_line(name, cursor.line(),
                        shown(value) + " is not a number (property '" + property.name + "')");
            }
          }
        }
      }
      if (is_vertex) sink.add(p[0], p[1], p[2]);
    }
  }
  if (cursor.next_token(token)) {
    fail_line(name, cursor.line(), "unexpected data after the last element: " + shown(token));
  }
}

// Fixed record size of an element without list properties.
std::optional<std::size_t> ply_fixed_stride(const PlyElement& element) {
  std::size_t stride = 0;
  for (const auto& property : element.properties) {
    if (property.is_list) return std::nullopt;
    stride += ply_size(property.type);
  }
  return stride;
}

void read_ply_binary(const std::string& name, const PlyHeader& header, std::string_view data,
                     PointSink& sink) {
  const bool big_endian = header.encoding == PlyEncoding::binary_big_endian;
  std::size_t pos = header.data_offset;
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    const bool is_vertex = e == header.vertex;
    std::array<std::size_t, 3> xyz_offset{};  // offset of x, y, z in a vertex record
    std::array<PlyType, 3> xyz_type{};
    for (std::size_t axis = 0; axis < 3 && is_vertex; ++axis) {
      xyz_type[axis] = element.properties[header.xyz[axis]].type;
    }

    if (const auto stride = ply_fixed_stride(element)) {
      // Fixed-size records: one bounds check for the whole element.
      const std::size_t available = data.size() - pos;
      const auto need = checked_mul(element.count, *stride);
      if (!need || *need > available) {
        fail_byte(name, pos,
                  "truncated binary data (need " + byte_count_text(need) + " bytes of " +
                      element.name + " data, have " + std::to_string(available) + ")");
      }
      if (is_vertex) {
        for (std::size_t axis = 0; axis < 3; ++axis) {
          for (std::size_t k = 0; k < header.xyz[axis]; ++k) {
            xyz_offset[axis] += ply_size(element.properties[k].type);
          }
        }
        const auto n = static_cast<std::size_t>(element.count);
        sink.reserve(n, n);
        for (std::size_t i = 0; i < n; ++i) {
          const char* const record = data.data() + pos + i * *stride;
          sink.add(ply_value(xyz_type[0], record + xyz_offset[0], big_endian),
                   ply_value(xyz_type[1], record + xyz_offset[1], big_endian),
                   ply_value(xyz_type[2], record + xyz_offset[2], big_endian));
        }
      }
      pos += static_cast<std::size_t>(*need);
      continue;
    }

    // Records with lists: walk them one property at a time.
    if (is_vertex) sink.reserve(element.count, (data.size() - pos) / 3);
    for (std::uint64_t r = 0; r < element.count; ++r) {
      const auto take = [&](std::uint64_t bytes) {
        const std::size_t start = pos;
        if (bytes > data.size() - pos) {
          fail_byte(name, pos,
                    "truncated binary data in element '" + element.name + "' (record " +
                        std::to_string(r + 1) + " of " + std::to_string(element.count) + ")");
        }
        pos += static_cast<std::size_t>(bytes);
        return start;
      };
      for (std::size_t k = 0; k < element.properties.size(); ++k) {
        const PlyProperty& property = element.properties[k];
        if (!property.is_list) {
          const std::size_t at = take(ply_size(property.type));
          for (std::size_t axis = 0; axis < 3 && is_vertex; ++axis) {
            if (header.xyz[axis] == k) xyz_offset[axis] = at;
          }
          continue;
        }
        const std::size_t at = take(ply_size(property.count_type));
        const double length = ply_value(property.count_type, data.data() + at, big_endian);
        if (length < 0) {
          fail_byte(name, at, "negative list length in element '" + element.name + "'");
        }
        const auto bytes = checked_mul(static_cast<std::uint64_t>(length), ply_size(property.type));
        take(bytes ? *bytes : std::numeric_limits<std::uint64_t>::max());
      }
      if (is_vertex) {
        sink.add(ply_value(xyz_type[0], data.data() + xyz_offset[0], big_endian),
                 ply_value(xyz_type[1], data.data() + xyz_offset[1], big_endian),
                 ply_value(xyz_type[2], data.data() + xyz_offset[2], big_endian));
      }
    }
  }
  if (pos != data.size()) {
    fail_byte(name, pos,
              std::to_string(data.size() - pos) +
                  " bytes after the last element (binary PLY ends with its data)");
  }
}

void read_ply(const std::string& name, std::string_view data, PointSink& sink) {
  TextCursor cursor(data, 0, 1);
  const PlyHeader header = parse_ply_header(name, cursor);
  sink.result().points_in_file = static_cast<std::size_t>(header.elements[header.vertex].count);
  if (header.encoding == PlyEncoding::ascii) {
    read_ply_ascii(name, header, cursor, sink);
  } else {
    read_ply_binary(name, header, data, sink);
  }
}

// ---------------------------------------------------------------------------------------------
// Headerless float32 records (KITTI .bin, .f32)

void read_float_records(const std::string& name, std::string_view data, std::size_t floats,
                        const std::string& layout, PointSink& sink) {
  const std::size_t record = floats * sizeof(float);
  if (data.size() % record != 0) {
    fail_byte(name, data.size() - data.size() % record,
              "truncated record: file size " + std::to_string(data.size()) +
                  " bytes is not a multiple of " + std::to_string(record) + " (" + layout + ")");
  }
  const std::size_t n = data.size() / record;
  if (beyond_cloud_limit(n)) fail_byte(name, 0, cloud_limit_text(n));
  sink.result().points_in_file = n;
  sink.reserve(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    const char* const p = data.data() + i * record;
    sink.add(load<float>(p, false), load<float>(p + 4, false), load<float>(p + 8, false));
  }
}

// ---------------------------------------------------------------------------------------------
// Text x y z

bool is_xyz_separator(char c) {
  return is_space(c) || c == ',' || c == ';';
}

// Calls visit(index, token) for the separated fields of a line until it returns false.
template <typename Visit>
void for_each_xyz_field(std::string_view line, Visit&& visit) {
  std::size_t i = 0;
  std::size_t index = 0;
  while (i < line.size()) {
    while (i < line.size() && is_xyz_separator(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_xyz_separator(line[i])) ++i;
    if (i == start) break;
    if (!visit(index++, line.substr(start, i - start))) return;
  }
}

// Column name of a header field: lowercase, without quotes or a leading "//".
std::string column_name(std::string_view field) {
  while (!field.empty() &&
         (field.front() == '/' || field.front() == '"' || field.front() == '\'')) {
    field.remove_prefix(1);
  }
  while (!field.empty() && (field.back() == '"' || field.back() == '\'')) field.remove_suffix(1);
  return lowercase(field);
}

void read_xyz(const std::string& name, std::string_view data, PointSink& sink) {
  std::size_t start = 0;
  if (data.starts_with("\xEF\xBB\xBF")) start = 3;  // UTF-8 byte order mark
  TextCursor cursor(data, start, 1);
  sink.reserve(kNoLimit, data.size() / 32);  // a typical line is longer than 32 bytes

  std::array<std::size_t, 3> column = {0, 1, 2};
  bool header_allowed = true;
  std::string_view line;
  while (cursor.next_line(line)) {
    const std::string_view content = trim(line);
    if (content.empty() || content.front() == '#') continue;

    const std::size_t needed = std::max({column[0], column[1], column[2]}) + 1;
    std::array<std::string_view, 3> xyz;
    std::size_t found = 0;
    for_each_xyz_field(content, [&](std::size_t index, std::string_view field) {
      for (std::size_t axis = 0; axis < 3; ++axis) {
        if (column[axis] == index) xyz[axis] = field;
      }
      found = index + 1;
      return found < needed;
    });

    std::array<double, 3> p{};
    if (header_allowed) {
      header_allowed = false;
      std::string_view first;
      for_each_xyz_field(content, [&](std::size_t, std::string_view field) {
        first = field;
        return false;
      });
      if (double ignored = 0.0; !parse_number(first, ignored)) {
        // A header line: use its x, y, z columns when it names all three.
        std::vector<std::string> names;
        for_each_xyz_field(content, [&](std::size_t, std::string_view field) {
          names.push_back(column_name(field));
          return true;
        });
        std::array<std::size_t, 3> named{};
        bool all_named = true;
        constexpr std::array<std::string_view, 3> kAxes = {"x", "y", "z"};
        for (std::size_t axis = 0; axis < 3; ++axis) {
          const auto it = std::find(names.begin(), names.end(), kAxes[axis]);
          all_named = all_named && it != names.end();
          named[axis] = static_cast<std::size_t>(it - names.begin());
        }
        if (all_named) column = named;
        continue;
      }
    }
    // A word where a number belongs says more than the field count, so it is reported first.
    for (std::size_t axis = 0; axis < 3; ++axis) {
      if (column[axis] < found && !parse_number(xyz[axis], p[axis])) {
        fail_line(name, cursor.line(),
                  shown(xyz[axis]) + " is not a number (column " +
                      std::to_string(column[axis] + 1) + ")");
      }
    }
    if (found < needed) {
      fail_line(name, cursor.line(),
                needed == 3 ? "expected 3 numbers, got " + std::to_string(found)
                            : "expected at least " + std::to_string(needed) + " columns, got " +
                                  std::to_string(found));
    }
    sink.add(p[0], p[1], p[2]);
    ++sink.result().points_in_file;
  }
}

// ---------------------------------------------------------------------------------------------
// Legacy ASCII VTK

void read_vtk(const std::string& name, std::string_view data, PointSink& sink) {
  TextCursor cursor(data, 0, 1);
  std::string_view line;
  constexpr std::string_view kMagic = "# vtk DataFile Version";
  if (!cursor.next_line(line) || line.size() < kMagic.size() ||
      !iequals(line.substr(0, kMagic.size()), kMagic)) {
    fail_line(name, 1, "not a legacy VTK file (expected '# vtk DataFile Version x.y')");
  }
  if (!cursor.next_line(line)) fail_line(name, 1, "VTK header ends after the first line");

  std::string_view token;
  const auto next = [&](const char* what) {
    if (!cursor.next_token(token)) {
      fail_line(name, cursor.line(), std::string("unexpected end of file, expected ") + what);
    }
    return token;
  };
  if (const auto encoding = next("ASCII or BINARY"); iequals(encoding, "BINARY")) {
    fail_line(name, cursor.line(), "binary VTK not supported");
  } else if (!iequals(encoding, "ASCII")) {
    fail_line(name, cursor.line(), "expected ASCII or BINARY, got " + shown(encoding));
  }
  if (const auto keyword = next("DATASET"); !iequals(keyword, "DATASET")) {
    fail_line(name, cursor.line(), "expected DATASET, got " + shown(keyword));
  }
  if (const auto dataset = next("POLYDATA"); !iequals(dataset, "POLYDATA")) {
    fail_line(name, cursor.line(), "unsupported dataset " + shown(dataset) + " (only POLYDATA)");
  }
  if (const auto keyword = next("POINTS"); !iequals(keyword, "POINTS")) {
    fail_line(name, cursor.line(), "expected POINTS, got " + shown(keyword));
  }
  std::uint64_t count = 0;
  if (const auto text = next("the point count"); !parse_uint(text, count)) {
    fail_line(name, cursor.line(), "point count " + shown(text) + " is not a count");
  }
  if (const auto type = next("the point type");
      !iequals(type, "float") && !iequals(type, "double")) {
    fail_line(name, cursor.line(), "unsupported POINTS type " + shown(type) + " (float or double)");
  }

  if (beyond_cloud_limit(count)) fail_line(name, cursor.line(), cloud_limit_text(count));
  sink.result().points_in_file = static_cast<std::size_t>(count);
  sink.reserve(count, cursor.remaining() / kMinTextPointBytes);
  for (std::uint64_t i = 0; i < count; ++i) {
    std::array<double, 3> p{};
    for (std::size_t axis = 0; axis < 3; ++axis) {
      if (!cursor.next_token(token)) {
        fail_line(name, cursor.line(),
                  "POINTS declares " + std::to_string(count) + " points (" +
                      std::to_string(count * 3) + " numbers), file ends after " +
                      std::to_string(i * 3 + axis) + " numbers");
      }
      if (!parse_number(token, p[axis])) {
        fail_line(name, cursor.line(), shown(token) + " is not a number");
      }
    }
    sink.add(p[0], p[1], p[2]);
  }
}

// ---------------------------------------------------------------------------------------------
// Writers

// A georeferenced cloud (origin_m not zero) is written as origin + point in double, which float
// cannot hold; any other cloud as the floats it stores.
bool written_in_double(const PointCloud& cloud) {
  return !cloud.origin_m.isZero();
}

template <typename T>
void append_number_text(std::string& out, T value) {
  // Shortest text that reads back as the same number.
  std::array<char, 32> buffer{};
  const auto r = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  out.append(buffer.data(), r.ptr);
}

// Each point as the numbers written: `emit(out, value)` for x, y and z, in float or double.
template <typename Emit>
void append_points(std::string& out, const PointCloud& cloud, const Emit& emit) {
  const bool wide = written_in_double(cloud);
  for (const auto& p : cloud.points) {
    for (Eigen::Index axis = 0; axis < 3; ++axis) {
      if (wide) {
        emit(out, static_cast<double>(p[axis]) + cloud.origin_m[axis], axis);
      } else {
        emit(out, p[axis], axis);
      }
    }
  }
}

void append_points_text(std::string& out, const PointCloud& cloud) {
  out.reserve(out.size() + cloud.size() * (written_in_double(cloud) ? 60 : 36));
  append_points(out, cloud, [](std::string& text, auto value, Eigen::Index axis) {
    append_number_text(text, value);
    text += axis < 2 ? ' ' : '\n';
  });
}

void append_points_binary(std::string& out, const PointCloud& cloud) {
  out.reserve(out.size() + cloud.size() * (written_in_double(cloud) ? 24 : 12));
  append_points(out, cloud, [](std::string& bytes, auto value, Eigen::Index) {
    append_little_endian(bytes, value);
  });
}

std::string ply_text(const PointCloud& cloud, Encoding encoding) {
  const std::string type = written_in_double(cloud) ? "double" : "float";
  std::string out = "ply\nformat ";
  out += encoding == Encoding::ascii ? "ascii" : "binary_little_endian";
  out += " 1.0\ncomment written by sgdicp\nelement vertex " + std::to_string(cloud.size()) +
         "\nproperty " + type + " x\nproperty " + type + " y\nproperty " + type +
         " z\nend_header\n";
  if (encoding == Encoding::ascii) {
    append_points_text(out, cloud);
  } else {
    append_points_binary(out, cloud);
  }
  return out;
}

std::string pcd_text(const PointCloud& cloud, Encoding encoding) {
  const std::string n = std::to_string(cloud.size());
  const std::string sizes = written_in_double(cloud) ? "SIZE 8 8 8\n" : "SIZE 4 4 4\n";
  std::string out = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\n" +
                    sizes + "TYPE F F F\nCOUNT 1 1 1\nWIDTH " + n +
                    "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + n + "\nDATA " +
                    (encoding == Encoding::ascii ? "ascii" : "binary") + "\n";
  if (encoding == Encoding::ascii) {
    append_points_text(out, cloud);
  } else {
    append_points_binary(out, cloud);
  }
  return out;
}

// The one parser behind both entry points: the bytes of a whole file in a known format.
ReadResult parse_point_cloud(const std::string& name, std::string_view data, FileFormat format) {
  if (data.empty()) fail_byte(name, 0, "empty file");
  ReadResult result;
  result.format = format;
  PointSink sink(name, result);
  switch (format) {
    case FileFormat::pcd:
      read_pcd(name, data, sink);
      break;
    case FileFormat::ply:
      read_ply(name, data, sink);
      break;
    case FileFormat::kitti_bin:
      read_float_records(name, data, 4, "float32 x y z intensity", sink);
      break;
    case FileFormat::xyz:
      read_xyz(name, data, sink);
      break;
    case FileFormat::vtk:
      read_vtk(name, data, sink);
      break;
    case FileFormat::f32:
      read_float_records(name, data, 3, "float32 x y z", sink);
      break;
    case FileFormat::automatic:
      break;  // resolved by the callers
  }
  return result;
}

}  // namespace

std::string to_string(FileFormat format) {
  switch (format) {
    case FileFormat::automatic:
      return "automatic";
    case FileFormat::pcd:
      return "pcd";
    case FileFormat::ply:
      return "ply";
    case FileFormat::kitti_bin:
      return "kitti_bin";
    case FileFormat::xyz:
      return "xyz";
    case FileFormat::vtk:
      return "vtk";
    case FileFormat::f32:
      return "f32";
  }
  return "unknown";
}

FileFormat format_from_extension(const std::filesystem::path& path) {
  const std::string extension = lowercase(path.extension().string());
  if (extension == ".pcd") return FileFormat::pcd;
  if (extension == ".ply") return FileFormat::ply;
  if (extension == ".bin") return FileFormat::kitti_bin;
  if (extension == ".xyz" || extension == ".txt" || extension == ".csv") return FileFormat::xyz;
  if (extension == ".vtk") return FileFormat::vtk;
  if (extension == ".f32") return FileFormat::f32;
  throw FormatError(path.string() + ": " +
                    (extension.empty() ? std::string("no file extension")
                                       : "unknown file extension " + shown(extension)) +
                    " (known: .pcd .ply .bin .xyz .txt .csv .vtk .f32)");
}

ReadResult read_point_cloud(const std::filesystem::path& path, FileFormat format) {
  const FileFormat resolved =
      format == FileFormat::automatic ? format_from_extension(path) : format;
  const std::string name = path.string();
  const std::vector<char> bytes = read_whole_file(path, name);
  return parse_point_cloud(name, std::string_view(bytes.data(), bytes.size()), resolved);
}

ReadResult read_point_cloud_from_memory(std::span<const std::byte> bytes, FileFormat format,
                                        std::string_view name) {
  if (bytes.size() > kMaxFileBytes) {
    throw FormatError(std::string(name) + ": larger than the largest file read (" +
                      limit_text(kMaxFileBytes) + ")");
  }
  if (format == FileFormat::automatic) {
    throw FormatError(std::string(name) +
                      ": reading from memory needs an explicit format (no extension to go by)");
  }
  return parse_point_cloud(
      std::string(name),
      std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), format);
}

void write_point_cloud(const std::filesystem::path& path, const PointCloud& cloud,
                       FileFormat format, Encoding encoding) {
  const FileFormat resolved =
      format == FileFormat::automatic ? format_from_extension(path) : format;
  const std::string name = path.string();
  std::string out;
  switch (resolved) {
    case FileFormat::ply:
      out = ply_text(cloud, encoding);
      break;
    case FileFormat::pcd:
      out = pcd_text(cloud, encoding);
      break;
    case FileFormat::xyz:
      append_points_text(out, cloud);
      break;
    default:
      throw FormatError(name + ": cannot write " + to_string(resolved) +
                        " files (PLY, PCD and XYZ can be written)");
  }
  write_whole_file(path, name, out);
}

}  // namespace sgdicp
