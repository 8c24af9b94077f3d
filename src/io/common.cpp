// Helpers every reader and writer shares (io_internal.hpp).
#include "io/io_internal.hpp"

namespace sgdicp::io_detail {

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

// ---------------------------------------------------------------------------------------------
// Text helpers

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

// A declared point count beyond the largest cloud: the message names the count and the limit.
bool beyond_cloud_limit(std::uint64_t points) {
  return points > kMaxCloudPoints;
}

std::string cloud_limit_text(std::uint64_t points) {
  return std::to_string(points) + " points exceed the largest cloud read (" +
         std::to_string(kMaxCloudPoints) + " points)";
}

// ---------------------------------------------------------------------------------------------
// Per-point times

std::optional<std::size_t> time_field_rank(std::string_view field_name) {
  // Integer nanoseconds from the sweep's start first (exact), then float seconds within the
  // sweep, then absolute seconds (docs/io.md, "Per-point times").
  constexpr std::array<std::string_view, 4> kByPriority = {"t", "offset_time", "time", "timestamp"};
  const auto found = std::find(kByPriority.begin(), kByPriority.end(), field_name);
  if (found == kByPriority.end()) return std::nullopt;
  return static_cast<std::size_t>(found - kByPriority.begin());
}

// A floating field that counts nanoseconds against the rule (Livox ROS Driver 2's double
// `timestamp`) spans about 1e8 "seconds" a sweep. No recording kept in one file lasts 11 days
// (1e6 s), so times spanning more are read as nanoseconds.
void PointSink::finish() {
  if (times_s_.empty()) return;
  const auto [earliest, latest] = std::minmax_element(times_s_.begin(), times_s_.end());
  constexpr double kLongestRecording_s = 1e6;
  const double scale = *latest - *earliest > kLongestRecording_s ? 1e-9 : 1.0;
  // A span beyond float's range (only a hostile file) saturates, so every stored time is finite.
  constexpr double kLongest_s = std::numeric_limits<float>::max();
  std::vector<float>& out = result_.cloud.times_s;
  out.reserve(times_s_.size());
  for (const double t : times_s_) {
    out.push_back(static_cast<float>(std::min((t - *earliest) * scale, kLongest_s)));
  }
  times_s_ = {};
}

// ---------------------------------------------------------------------------------------------
// Writers

// A georeferenced cloud (origin_m not zero) is written as origin + point in double, which float
// cannot hold; any other cloud as the floats it stores.
bool written_in_double(const PointCloud& cloud) {
  return !cloud.origin_m.isZero();
}

namespace {

template <typename T>
void append_number_text(std::string& out, T value) {
  // Shortest text that reads back as the same number.
  std::array<char, 32> buffer{};
  const auto r = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  out.append(buffer.data(), r.ptr);
}

// Each point as the numbers written: `emit(out, value, last)` for x, y and z, in float or double,
// then its time as a float when `with_times`; `last` marks the point's last value.
template <typename Emit>
void append_points(std::string& out, const PointCloud& cloud, bool with_times, const Emit& emit) {
  const bool wide = written_in_double(cloud);
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    for (Eigen::Index axis = 0; axis < 3; ++axis) {
      const bool last = axis == 2 && !with_times;
      if (wide) {
        emit(out, static_cast<double>(p[axis]) + cloud.origin_m[axis], last);
      } else {
        emit(out, p[axis], last);
      }
    }
    if (with_times) emit(out, cloud.times_s[i], true);
  }
}

}  // namespace

void append_points_text(std::string& out, const PointCloud& cloud, bool with_times) {
  const std::size_t per_point = (written_in_double(cloud) ? 60 : 36) + (with_times ? 12 : 0);
  out.reserve(out.size() + cloud.size() * per_point);
  append_points(out, cloud, with_times, [](std::string& text, auto value, bool last) {
    append_number_text(text, value);
    text += last ? '\n' : ' ';
  });
}

void append_points_binary(std::string& out, const PointCloud& cloud, bool with_times) {
  const std::size_t per_point = (written_in_double(cloud) ? 24 : 12) + (with_times ? 4 : 0);
  out.reserve(out.size() + cloud.size() * per_point);
  append_points(out, cloud, with_times,
                [](std::string& bytes, auto value, bool) { append_little_endian(bytes, value); });
}

}  // namespace sgdicp::io_detail
