#pragma once
// Pairs files (shared/data/PAIRS.md): one registration problem per line,
// `SOURCE REFERENCE t00 t01 t02 t03 t10 ... t23` with the ground truth T_reference_source as a
// row-major 3x4 matrix; paths relative to the folder of the pairs file; '#' starts a comment line.
#include <filesystem>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace sgdicp {

struct RegistrationPair {
  std::filesystem::path source;     ///< resolved against the pairs file's folder
  std::filesystem::path reference;  ///< resolved against the pairs file's folder
  Eigen::Matrix4d T_reference_source_gt = Eigen::Matrix4d::Identity();
  std::size_t line = 0;  ///< line in the pairs file
};

/// Parses the text of a pairs file; paths are resolved against `folder`, `name` names the source
/// in error messages. Throws FormatError (naming `name` and the line).
[[nodiscard]] std::vector<RegistrationPair> parse_pairs(std::string_view text,
                                                        const std::filesystem::path& folder,
                                                        std::string_view name);

/// Reads a pairs file (see parse_pairs). Throws IoError (cannot read) or FormatError (naming file
/// and line).
[[nodiscard]] std::vector<RegistrationPair> read_pairs_file(const std::filesystem::path& path);

}  // namespace sgdicp
