#pragma once
// Rigid transforms as text: 12 numbers (3x4 [R | t]) or 16 numbers (4x4), row-major,
// separated by white space or commas. Lines starting with '#' are comments.
#include <filesystem>
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace sgdicp {

/// Parses 12 or 16 numbers into a 4x4 transform; `what` names the source in error messages.
/// Throws FormatError for another count, a non-number, or a matrix that is not rigid within
/// 1e-3 (the result is projected onto the nearest rotation, so 6-digit files are fine).
[[nodiscard]] Eigen::Matrix4d parse_transform(std::string_view text, std::string_view what);

/// Reads a transform file (see parse_transform). Throws IoError or FormatError.
[[nodiscard]] Eigen::Matrix4d read_transform(const std::filesystem::path& path);

/// Writes a 4x4 row-major transform with 17 significant digits (exact round trip).
void write_transform(const std::filesystem::path& path, const Eigen::Matrix4d& T);

/// The 4x4 transform as text: 4 lines of 4 numbers with 17 significant digits.
[[nodiscard]] std::string format_transform(const Eigen::Matrix4d& T);

}  // namespace sgdicp
