// Text x y z (.xyz, .txt, .csv): one point per line, a header line allowed.
#include "io/io_internal.hpp"

namespace sgdicp::io_detail {
namespace {

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

}  // namespace

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

}  // namespace sgdicp::io_detail
