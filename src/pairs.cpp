#include "sgdicp/pairs.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "sgdicp/error.hpp"
#include "sgdicp/transform_io.hpp"

namespace sgdicp {

std::vector<RegistrationPair> read_pairs_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path.string() + ": cannot open: " + std::strerror(errno));
  const std::filesystem::path folder = path.parent_path();
  std::vector<RegistrationPair> pairs;
  std::string line;
  std::size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    std::string source;
    std::string reference;
    fields >> source >> reference;
    const std::string where = path.string() + ": line " + std::to_string(number);
    if (reference.empty()) {
      throw FormatError(where + ": expected SOURCE REFERENCE and 12 numbers");
    }
    std::string rest;
    std::getline(fields, rest);
    RegistrationPair pair;
    pair.source = folder / source;
    pair.reference = folder / reference;
    pair.T_reference_source_gt = parse_transform(rest, where);
    pair.line = number;
    pairs.push_back(std::move(pair));
  }
  if (in.bad()) throw IoError(path.string() + ": read error");
  if (pairs.empty()) throw FormatError(path.string() + ": no pairs in file");
  return pairs;
}

}  // namespace sgdicp
