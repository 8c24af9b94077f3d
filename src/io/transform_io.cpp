#include "sgdicp/io/transform_io.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "io/parse_number.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/core/pose.hpp"

namespace sgdicp {
namespace {

// A transform is a few hundred bytes: a larger file, or one that is not a regular file (a
// directory, /dev/zero, a FIFO), is not a transform and is not read.
constexpr std::uintmax_t kMaxTransformFileBytes = std::uintmax_t{1} << 20;

std::string read_text_file(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!ec && status.type() == std::filesystem::file_type::directory) {
    throw IoError(path.string() + ": a directory, not a transform file");
  }
  if (!ec && status.type() != std::filesystem::file_type::regular) {
    throw IoError(path.string() + ": not a regular file (only regular files are read)");
  }
  if (!ec && std::filesystem::file_size(path, ec) > kMaxTransformFileBytes && !ec) {
    throw IoError(path.string() + ": larger than " + std::to_string(kMaxTransformFileBytes) +
                  " bytes, not a transform file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open: " + std::strerror(errno));
  std::string text(kMaxTransformFileBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw IoError(path.string() + ": read error");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxTransformFileBytes) {
    throw IoError(path.string() + ": larger than " + std::to_string(kMaxTransformFileBytes) +
                  " bytes, not a transform file");
  }
  return text;
}

bool is_transform_separator(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == ',' || c == ';' || c == '[' ||
         c == ']' || c == '#';
}

}  // namespace

Eigen::Matrix4d parse_transform(std::string_view text, std::string_view what) {
  const auto fail = [&](std::size_t line, const std::string& message) {
    throw FormatError(std::string(what) + ": line " + std::to_string(line) + ": " + message);
  };
  std::vector<double> values;
  std::size_t line = 1;
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '#') {  // a comment to the end of the line
      while (i < text.size() && text[i] != '\n') ++i;
      continue;
    }
    if (is_transform_separator(c)) {
      line += c == '\n' ? 1 : 0;
      ++i;
      continue;
    }
    // A whole token must be one number: "0.0.5" is an error, not 0.0 and .5.
    const std::size_t start = i;
    while (i < text.size() && !is_transform_separator(text[i])) ++i;
    const std::string_view token = text.substr(start, i - start);
    double v = 0.0;
    if (!parse_number(token, v)) {
      fail(line, "expected a number, got '" + std::string(token.substr(0, 40)) + "'" +
                     (token.size() > 40 ? "..." : ""));
    }
    if (!std::isfinite(v)) {
      fail(line, "non-finite value '" + std::string(token.substr(0, 40)) + "' in transform");
    }
    values.push_back(v);
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
