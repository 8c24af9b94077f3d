#include "cli_common.hpp"

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string_view>
#include <type_traits>

#include "sgdicp/error.hpp"
#include "sgdicp/transform_io.hpp"

namespace sgdicp::cli {

PointCloud load_cloud(const std::string& path, const std::string& role, bool verbose) {
  ReadResult read = read_point_cloud(path);
  if (read.non_finite_dropped > 0 && verbose) {
    std::cerr << "note: " << path << ": dropped " << read.non_finite_dropped
              << " points with non-finite coordinates\n";
  }
  if (read.cloud.empty()) {
    throw InvalidInputError(path + ": the " + role + " cloud has no finite points");
  }
  return std::move(read.cloud);
}

namespace {

// Whether text is a list of numbers (nan and inf included) separated by blanks, commas,
// semicolons or brackets: an inline matrix rather than a file name.
bool is_number_list(const std::string& text) {
  std::size_t numbers = 0;
  std::size_t i = 0;
  while (i < text.size()) {
    if (std::string_view(" \t\r\n,;[]").find(text[i]) != std::string_view::npos) {
      ++i;
      continue;
    }
    const char* begin = text.c_str() + i;
    char* end = nullptr;
    (void)std::strtod(begin, &end);
    if (end == begin) return false;
    const char next = *end;
    if (next != '\0' && std::string_view(" \t\r\n,;[]").find(next) == std::string_view::npos) {
      return false;
    }
    i += static_cast<std::size_t>(end - begin);
    ++numbers;
  }
  return numbers > 0;
}

}  // namespace

Eigen::Matrix4d parse_transform_option(const std::string& text, const std::string& option) {
  std::error_code ec;
  const std::filesystem::path path(text);
  if (std::filesystem::is_directory(path, ec)) {
    throw IoError(option + " " + text + ": a directory, not a transform file");
  }
  if (std::filesystem::exists(path, ec)) {
    try {
      return read_transform(path);
    } catch (const FormatError& e) {
      throw FormatError(option + ": " + e.what());
    } catch (const IoError& e) {
      throw IoError(option + ": " + e.what());
    }
  }
  if (!is_number_list(text)) {
    throw IoError(option + " " + text +
                  ": no such transform file (and not 12 or 16 numbers either)");
  }
  return parse_transform(text, option);
}

nlohmann::json matrix_to_json(const Eigen::Matrix4d& T) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) {
    rows.push_back({T(r, 0), T(r, 1), T(r, 2), T(r, 3)});
  }
  return rows;
}

nlohmann::json result_to_json(const RegistrationResult& r) {
  nlohmann::json j{{"transform", matrix_to_json(r.T_reference_source)}};
  for_each_result_field([&](const char* name, auto member, const char*) {
    if constexpr (std::is_same_v<std::remove_cvref_t<decltype(r.*member)>, StopReason>) {
      j[name] = std::string(to_string(r.*member));
    } else {
      j[name] = r.*member;
    }
  });
  return j;
}

}  // namespace sgdicp::cli
