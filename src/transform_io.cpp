#include "sgdicp/transform_io.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "sgdicp/error.hpp"
#include "sgdicp/pose.hpp"

namespace sgdicp {
namespace {

std::string read_text_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open: " + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw IoError(path.string() + ": read error");
  return buffer.str();
}

}  // namespace

Eigen::Matrix4d parse_transform(std::string_view text, std::string_view what) {
  std::vector<double> values;
  std::size_t line = 1;
  bool in_comment = false;
  const char* p = text.data();
  const char* const end = text.data() + text.size();
  while (p < end) {
    const char c = *p;
    if (c == '\n') {
      ++line;
      in_comment = false;
      ++p;
      continue;
    }
    if (in_comment || c == ' ' || c == '\t' || c == '\r' || c == ',' || c == ';' || c == '[' ||
        c == ']') {
      ++p;
      continue;
    }
    if (c == '#') {
      in_comment = true;
      ++p;
      continue;
    }
    double v = 0.0;
    const char* start = p + (c == '+' ? 1 : 0);
    const auto [next, ec] = std::from_chars(start, end, v);
    if (ec != std::errc() || next == start) {
      throw FormatError(
          std::string(what) + ": line " + std::to_string(line) + ": expected a number, got '" +
          std::string(p, std::min<std::size_t>(12, static_cast<std::size_t>(end - p))) + "'");
    }
    if (!std::isfinite(v)) {
      throw FormatError(std::string(what) + ": line " + std::to_string(line) +
                        ": non-finite value in transform");
    }
    values.push_back(v);
    p = next;
  }
  if (values.size() != 12 && values.size() != 16) {
    throw FormatError(std::string(what) + ": expected 12 (3x4) or 16 (4x4) numbers, got " +
                      std::to_string(values.size()));
  }
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  for (std::size_t i = 0; i < values.size(); ++i) {
    T(static_cast<Eigen::Index>(i / 4), static_cast<Eigen::Index>(i % 4)) = values[i];
  }
  if (!is_rigid_transform(T, 1e-3)) {
    throw FormatError(std::string(what) +
                      ": not a rigid transform (rotation block not orthonormal with determinant "
                      "+1 within 1e-3, or last row not 0 0 0 1)");
  }
  // Already a rotation to machine precision: keep the bits (exact write/read round trip).
  return is_rigid_transform(T, 1e-12) ? T : orthonormalized(T);
}

Eigen::Matrix4d read_transform(const std::filesystem::path& path) {
  return parse_transform(read_text_file(path), path.string());
}

std::string format_transform(const Eigen::Matrix4d& T) {
  std::string out;
  char buf[64];
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      const auto [ptr, ec] =
          std::to_chars(buf, buf + sizeof(buf), T(r, c), std::chars_format::general, 17);
      (void)ec;
      out.append(buf, ptr);
      out += c < 3 ? ' ' : '\n';
    }
  }
  return out;
}

void write_transform(const std::filesystem::path& path, const Eigen::Matrix4d& T) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw IoError(path.string() + ": cannot open for writing: " + std::strerror(errno));
  out << format_transform(T);
  out.flush();
  if (!out) throw IoError(path.string() + ": write error");
}

}  // namespace sgdicp
