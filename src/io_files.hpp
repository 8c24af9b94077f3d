#pragma once
// File access shared by the readers (internal): one bounded way to read a whole file.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace sgdicp {

/// The bytes of a regular file, at most kMaxFileBytes (io.hpp); IoError naming `name` otherwise.
[[nodiscard]] std::vector<char> read_whole_file(const std::filesystem::path& path,
                                                const std::string& name);

/// "N bytes = G GiB", for the messages about a size limit.
[[nodiscard]] std::string limit_text(std::uint64_t bytes);

}  // namespace sgdicp
