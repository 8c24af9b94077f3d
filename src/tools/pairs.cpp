#include "sgdicp/tools/pairs.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "sgdicp/core/error.hpp"
#include "sgdicp/io/transform_io.hpp"

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

// One non-blank, non-comment line: SOURCE REFERENCE and the 12 numbers of the ground truth.
RegistrationPair parse_pair_line(const std::string& line, const std::filesystem::path& folder,
                                 const std::string& where) {
  std::istringstream fields(line);
  std::string source;
  std::string reference;
  fields >> source >> reference;
  if (reference.empty()) throw FormatError(where + ": expected SOURCE REFERENCE and 12 numbers");
  std::string rest;
  std::getline(fields, rest);
  RegistrationPair pair;
  pair.source = folder / source;
  pair.reference = folder / reference;
  pair.T_reference_source_gt = parse_transform(rest, where);
  return pair;
}

}  // namespace

std::vector<RegistrationPair> parse_pairs(std::string_view text,
                                          const std::filesystem::path& folder,
                                          std::string_view name) {
  std::vector<RegistrationPair> pairs;
  std::size_t number = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    const std::size_t newline = std::min(text.find('\n', pos), text.size());
    const std::string line(text.substr(pos, newline - pos));
    pos = newline + 1;
    ++number;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    RegistrationPair pair =
        parse_pair_line(line, folder, std::string(name) + ": line " + std::to_string(number));
    pair.line = number;
    pairs.push_back(std::move(pair));
  }
  if (pairs.empty()) throw FormatError(std::string(name) + ": no pairs in file");
  return pairs;
}

std::vector<RegistrationPair> read_pairs_file(const std::filesystem::path& path) {
  return parse_pairs(read_text_file(path), path.parent_path(), path.string());
}

}  // namespace sgdicp
