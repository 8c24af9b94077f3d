// PCD: reading v0.5-v0.7 ascii, binary and binary_compressed (LZF); writing binary or ascii.
#include "io/io_internal.hpp"

#include <lzf.h>

namespace sgdicp::io_detail {
namespace {

enum class PcdData { ascii, binary, binary_compressed };

struct PcdField {
  std::string name;
  std::size_t size = 0;  // bytes per value
  char type = 0;         // 'I', 'U' or 'F'
  std::uint64_t count = 1;
};

struct PcdHeader {
  std::vector<PcdField> fields;
  std::uint64_t width = 0;
  std::uint64_t height = 1;
  std::uint64_t points = 0;
  PcdData data = PcdData::ascii;
  std::size_t data_offset = 0;
  std::size_t data_line = 0;  // line of the DATA key
  std::size_t fields_line = 0;
  std::size_t type_line = 0;
  std::size_t count_line = 0;
  std::size_t points_line = 0;
  std::array<std::size_t, 3> xyz{};  // field index of x, y, z
  std::optional<std::size_t> time;   // field index of the per-point time, if any
};

// One header line: its key, the values after it and its number, for the messages.
struct PcdKeyLine {
  const std::string& name;
  std::size_t at;
  std::string_view key;
  std::span<const std::string_view> values;

  [[noreturn]] void fail(const std::string& what) const { fail_line(name, at, what); }

  void expect_values(std::size_t n) const {
    if (values.size() != n) {
      fail(std::string(key) + " needs " + std::to_string(n) + " value(s), got " +
           std::to_string(values.size()));
    }
  }

  [[nodiscard]] std::uint64_t uint_value(std::string_view token) const {
    std::uint64_t v = 0;
    if (!parse_uint(token, v)) {
      fail(std::string(key) + " value " + shown(token) + " is not a count");
    }
    return v;
  }
};

// The header keys seen so far: FIELDS, SIZE, TYPE and WIDTH must be there, DATA ends the header.
struct PcdKeysSeen {
  bool fields = false;
  bool size = false;
  bool type = false;
  bool width = false;
  bool points = false;
  bool data = false;
};

void check_pcd_version(const PcdKeyLine& line) {
  line.expect_values(1);
  constexpr std::array<std::string_view, 6> kKnown = {".5", "0.5", ".6", "0.6", ".7", "0.7"};
  if (std::find(kKnown.begin(), kKnown.end(), line.values[0]) == kKnown.end()) {
    line.fail("unsupported PCD version " + shown(line.values[0]));
  }
}

void parse_pcd_fields(const PcdKeyLine& line, PcdHeader& header, PcdKeysSeen& seen) {
  if (seen.fields) line.fail("second FIELDS line");
  if (line.values.empty()) line.fail("FIELDS lists no field");
  for (const auto v : line.values) header.fields.push_back(PcdField{std::string(v)});
  seen.fields = true;
  header.fields_line = line.at;
}

// SIZE, TYPE and COUNT give one value per field, so they need FIELDS before them.
void expect_per_field(const PcdKeyLine& line, const PcdHeader& header, const PcdKeysSeen& seen) {
  if (!seen.fields) line.fail(std::string(line.key) + " before FIELDS");
  line.expect_values(header.fields.size());
}

void parse_pcd_sizes(const PcdKeyLine& line, PcdHeader& header, PcdKeysSeen& seen) {
  expect_per_field(line, header, seen);
  for (std::size_t i = 0; i < line.values.size(); ++i) {
    const auto size = line.uint_value(line.values[i]);
    if (size != 1 && size != 2 && size != 4 && size != 8) {
      line.fail("SIZE of field '" + header.fields[i].name + "' must be 1, 2, 4 or 8");
    }
    header.fields[i].size = static_cast<std::size_t>(size);
  }
  seen.size = true;
}

void parse_pcd_types(const PcdKeyLine& line, PcdHeader& header, PcdKeysSeen& seen) {
  expect_per_field(line, header, seen);
  for (std::size_t i = 0; i < line.values.size(); ++i) {
    const std::string_view type = line.values[i];
    if (type != "I" && type != "U" && type != "F") {
      line.fail("TYPE " + shown(type) + " of field '" + header.fields[i].name +
                "' is not I, U or F");
    }
    header.fields[i].type = type[0];
  }
  seen.type = true;
  header.type_line = line.at;
}

void parse_pcd_counts(const PcdKeyLine& line, PcdHeader& header, const PcdKeysSeen& seen) {
  expect_per_field(line, header, seen);
  header.count_line = line.at;
  for (std::size_t i = 0; i < line.values.size(); ++i) {
    header.fields[i].count = line.uint_value(line.values[i]);
    if (header.fields[i].count == 0) {
      line.fail("COUNT of field '" + header.fields[i].name + "' is 0");
    }
  }
}

void check_pcd_viewpoint(const PcdKeyLine& line) {
  line.expect_values(7);
  for (const auto v : line.values) {
    if (double f = 0.0; !parse_number(v, f)) {
      line.fail("VIEWPOINT value " + shown(v) + " is not a number");
    }
  }
}

PcdData parse_pcd_data(const PcdKeyLine& line) {
  line.expect_values(1);
  if (line.values[0] == "ascii") return PcdData::ascii;
  if (line.values[0] == "binary") return PcdData::binary;
  if (line.values[0] == "binary_compressed") return PcdData::binary_compressed;
  line.fail("unknown DATA " + shown(line.values[0]) + " (ascii, binary or binary_compressed)");
}

// Applies one header line to the header.
void parse_pcd_key(const PcdKeyLine& line, PcdHeader& header, PcdKeysSeen& seen) {
  const std::string_view key = line.key;
  if (key == "VERSION") {
    check_pcd_version(line);
  } else if (key == "FIELDS" || key == "COLUMNS") {  // COLUMNS: the v0.5 spelling
    parse_pcd_fields(line, header, seen);
  } else if (key == "SIZE") {
    parse_pcd_sizes(line, header, seen);
  } else if (key == "TYPE") {
    parse_pcd_types(line, header, seen);
  } else if (key == "COUNT") {
    parse_pcd_counts(line, header, seen);
  } else if (key == "WIDTH") {
    line.expect_values(1);
    header.width = line.uint_value(line.values[0]);
    seen.width = true;
  } else if (key == "HEIGHT") {
    line.expect_values(1);
    header.height = line.uint_value(line.values[0]);
  } else if (key == "VIEWPOINT") {
    check_pcd_viewpoint(line);
  } else if (key == "POINTS") {
    line.expect_values(1);
    header.points = line.uint_value(line.values[0]);
    seen.points = true;
    header.points_line = line.at;
  } else if (key == "DATA") {
    header.data = parse_pcd_data(line);
    seen.data = true;
    header.data_line = line.at;
  } else {
    line.fail("unknown PCD header key " + shown(key));
  }
}

void check_pcd_keys_seen(const std::string& name, std::size_t end_line, const PcdKeysSeen& seen) {
  if (!seen.data) fail_line(name, end_line, "PCD header has no DATA line");
  if (!seen.fields) fail_line(name, end_line, "PCD header has no FIELDS line");
  if (!seen.size) fail_line(name, end_line, "PCD header has no SIZE line");
  if (!seen.type) fail_line(name, end_line, "PCD header has no TYPE line");
  if (!seen.width) fail_line(name, end_line, "PCD header has no WIDTH line");
}

void check_pcd_float_sizes(const std::string& name, const PcdHeader& header) {
  for (const auto& field : header.fields) {
    if (field.type == 'F' && field.size != 4 && field.size != 8) {
      fail_line(name, header.type_line,
                "float field '" + field.name + "' has SIZE " + std::to_string(field.size) +
                    " (only 4 or 8)");
    }
  }
}

// Field index of x, y and z: each must appear once, as a single float.
std::array<std::size_t, 3> find_pcd_xyz(const std::string& name, const PcdHeader& header) {
  std::array<std::size_t, 3> xyz{};
  constexpr std::array<std::string_view, 3> kAxes = {"x", "y", "z"};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const auto found = std::find_if(header.fields.begin(), header.fields.end(),
                                    [&](const PcdField& f) { return f.name == kAxes[axis]; });
    if (found == header.fields.end()) {
      fail_line(name, header.fields_line, "PCD has no '" + std::string(kAxes[axis]) + "' field");
    }
    if (std::find_if(found + 1, header.fields.end(), [&](const PcdField& f) {
          return f.name == kAxes[axis];
        }) != header.fields.end()) {
      fail_line(name, header.fields_line, "field '" + found->name + "' appears twice");
    }
    if (found->type != 'F' || found->count != 1) {
      fail_line(
          name, header.type_line,
          "field '" + found->name + "' must be a single float (TYPE F, SIZE 4 or 8, COUNT 1)");
    }
    xyz[axis] = static_cast<std::size_t>(found - header.fields.begin());
  }
  return xyz;
}

// Field index of the per-point time (docs/io.md, "Per-point times"): a single value, named once.
std::optional<std::size_t> find_pcd_time(const std::string& name, const PcdHeader& header) {
  const auto& fields = header.fields;
  const auto time = find_time_field(
      fields.size(), [&](std::size_t i) -> std::string_view { return fields[i].name; });
  if (!time) return std::nullopt;
  const PcdField& field = fields[*time];
  if (std::count_if(fields.begin(), fields.end(),
                    [&](const PcdField& f) { return f.name == field.name; }) > 1) {
    fail_line(name, header.fields_line, "field '" + field.name + "' appears twice");
  }
  if (field.count != 1) {
    fail_line(name, header.count_line,
              "field '" + field.name + "' (the per-point time) must be a single value (COUNT 1)");
  }
  return time;
}

// POINTS, when given, must be WIDTH x HEIGHT; without it, WIDTH x HEIGHT is the point count.
void set_pcd_points(const std::string& name, PcdHeader& header, bool have_points) {
  const auto cells = checked_mul(header.width, header.height);
  if (!have_points) {
    if (!cells) fail_line(name, header.data_line, "WIDTH x HEIGHT overflows");
    header.points = *cells;
  } else if (!cells || *cells != header.points) {
    fail_line(name, header.points_line,
              "POINTS " + std::to_string(header.points) + " does not match WIDTH x HEIGHT = " +
                  std::to_string(header.width) + " x " + std::to_string(header.height));
  }
  if (beyond_cloud_limit(header.points)) {
    fail_line(name, have_points ? header.points_line : header.data_line,
              cloud_limit_text(header.points));
  }
}

PcdHeader parse_pcd_header(const std::string& name, TextCursor& cursor) {
  PcdHeader header;
  PcdKeysSeen seen;
  std::string_view line;
  while (!seen.data && cursor.next_line(line)) {
    const auto tokens = split_whitespace(line);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    const PcdKeyLine key_line{name, cursor.line(), tokens[0], {tokens.begin() + 1, tokens.end()}};
    parse_pcd_key(key_line, header, seen);
    if (seen.data) header.data_offset = cursor.offset();  // the data starts after the DATA line
  }
  check_pcd_keys_seen(name, cursor.line(), seen);
  check_pcd_float_sizes(name, header);
  header.xyz = find_pcd_xyz(name, header);
  header.time = find_pcd_time(name, header);
  set_pcd_points(name, header, seen.points);
  return header;
}

// Every value of a data line is of its field's type: a number for F, an integer that fits SIZE
// bytes for I and U. The line has as many values as the fields' COUNTs add up to.
void check_pcd_values(const std::string& name, std::size_t line_number, const PcdHeader& header,
                      std::string_view line) {
  std::size_t field = 0;
  std::uint64_t left = header.fields.empty() ? 0 : header.fields[0].count;
  for (const std::string_view token : split_whitespace(line)) {
    while (left == 0) left = header.fields[++field].count;
    const PcdField& f = header.fields[field];
    double ignored = 0.0;
    const bool ok = f.type == 'F' ? parse_number(token, ignored)
                                  : is_integer_token(token, f.size, f.type == 'I');
    if (!ok) {
      fail_line(name, line_number,
                shown(token) + " is not " +
                    (f.type == 'F'
                         ? std::string("a number")
                         : (f.type == 'I' ? "a signed" : "an unsigned") +
                               std::string(" integer of ") + std::to_string(f.size) + " byte(s)") +
                    " (field '" + f.name + "')");
    }
    --left;
  }
}

// Seconds per unit of the time field (an integer field counts nanoseconds).
double pcd_time_unit_s(const PcdField& field) {
  return time_field_unit_s(field.type != 'F');
}

void read_pcd_ascii(const std::string& name, const PcdHeader& header, TextCursor& cursor,
                    PointSink& sink) {
  // Column of x, y, z and the time on a line, where fields with COUNT > 1 take several columns;
  // no column has the time's index when there is none.
  std::array<std::uint64_t, 4> column{0, 0, 0, kNoLimit};
  std::uint64_t columns = 0;
  for (std::size_t f = 0; f < header.fields.size(); ++f) {
    for (std::size_t axis = 0; axis < 3; ++axis) {
      if (header.xyz[axis] == f) column[axis] = columns;
    }
    if (header.time == f) column[3] = columns;
    const auto next = checked_add(columns, header.fields[f].count);
    if (!next) fail_line(name, header.data_line, "COUNT values overflow");
    columns = *next;
  }

  sink.reserve(header.points, cursor.remaining() / kMinTextPointBytes);
  std::uint64_t read = 0;
  std::string_view line;
  while (read < header.points) {
    if (!cursor.next_line(line)) {
      fail_line(name, cursor.line(),
                "expected " + std::to_string(header.points) + " points, file ends after " +
                    std::to_string(read));
    }
    std::array<std::string_view, 4> xyzt;
    std::uint64_t count = 0;
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && is_space(line[i])) ++i;
      const std::size_t start = i;
      while (i < line.size() && !is_space(line[i])) ++i;
      if (i == start) break;
      for (std::size_t k = 0; k < 4; ++k) {
        if (column[k] == count) xyzt[k] = line.substr(start, i - start);
      }
      ++count;
    }
    if (count == 0) continue;  // blank line
    if (count != columns) {
      fail_line(name, cursor.line(),
                "expected " + std::to_string(columns) + " values, got " + std::to_string(count));
    }
    check_pcd_values(name, cursor.line(), header, line);
    std::array<double, 4> p{};
    for (std::size_t k = 0; k < (header.time ? 4 : 3); ++k) {
      if (!parse_number(xyzt[k], p[k])) {
        fail_line(name, cursor.line(), shown(xyzt[k]) + " is not a number");
      }
    }
    if (header.time) {
      sink.add(p[0], p[1], p[2], p[3] * pcd_time_unit_s(header.fields[*header.time]));
    } else {
      sink.add(p[0], p[1], p[2]);
    }
    ++read;
  }
  while (cursor.next_line(line)) {
    if (!trim(line).empty()) {
      fail_line(name, cursor.line(),
                "more data than POINTS " + std::to_string(header.points) + " declares");
    }
  }
}

double load_pcd_coordinate(const char* p, std::size_t size) {
  return size == 4 ? load<float>(p, false) : load<double>(p, false);
}

template <typename Signed, typename Unsigned>
double load_pcd_integer(const char* p, bool is_signed) {
  return is_signed ? static_cast<double>(load<Signed>(p, false))
                   : static_cast<double>(load<Unsigned>(p, false));
}

// A value of any PCD type (TYPE I, U or F and its SIZE, checked by the header).
double load_pcd_value(const char* p, const PcdField& field) {
  if (field.type == 'F') return load_pcd_coordinate(p, field.size);
  const bool is_signed = field.type == 'I';
  switch (field.size) {
    case 1:
      return load_pcd_integer<std::int8_t, std::uint8_t>(p, is_signed);
    case 2:
      return load_pcd_integer<std::int16_t, std::uint16_t>(p, is_signed);
    case 4:
      return load_pcd_integer<std::int32_t, std::uint32_t>(p, is_signed);
    default:
      return load_pcd_integer<std::int64_t, std::uint64_t>(p, is_signed);
  }
}

// The time of the point whose time field is at p, in seconds.
double load_pcd_time_s(const char* p, const PcdField& field) {
  return load_pcd_value(p, field) * pcd_time_unit_s(field);
}

// Byte layout of one point: offset of each field and the total size.
struct PcdLayout {
  std::vector<std::uint64_t> field_offset;
  std::uint64_t point_size = 0;
};

PcdLayout pcd_layout(const std::string& name, const PcdHeader& header) {
  PcdLayout layout;
  for (const auto& field : header.fields) {
    layout.field_offset.push_back(layout.point_size);
    const auto bytes = checked_mul(field.size, field.count);
    const auto next = bytes ? checked_add(layout.point_size, *bytes) : std::nullopt;
    if (!next) fail_line(name, header.data_line, "point size overflows");
    layout.point_size = *next;
  }
  return layout;
}

// The bytes after binary point data must be none, or zeros that fill a page: PCL before 1.10
// stretched its files to a page (4096 bytes, up to 64 KiB on some systems) plus the data.
void check_pcd_end(const std::string& name, std::string_view data, std::size_t end) {
  constexpr std::size_t kLargestPage = std::size_t{1} << 16;
  const std::string_view rest = data.substr(end);
  const bool page_padding =
      rest.size() < kLargestPage && rest.find_first_not_of('\0') == std::string_view::npos;
  if (!page_padding) {
    fail_byte(name, end,
              std::to_string(rest.size()) +
                  " bytes after the point data (only zeros that fill a page may follow)");
  }
}

void read_pcd_binary(const std::string& name, const PcdHeader& header, std::string_view data,
                     PointSink& sink) {
  const PcdLayout layout = pcd_layout(name, header);
  const std::size_t available = data.size() - header.data_offset;
  const auto need = checked_mul(header.points, layout.point_size);
  if (!need || *need > available) {
    fail_byte(name, header.data_offset,
              "truncated binary data (need " + byte_count_text(need) +
                  " bytes of point data, have " + std::to_string(available) + ")");
  }
  check_pcd_end(name, data, header.data_offset + static_cast<std::size_t>(*need));
  const char* const base = data.data() + header.data_offset;
  const std::size_t step = static_cast<std::size_t>(layout.point_size);
  std::array<std::size_t, 3> offset{};
  std::array<std::size_t, 3> size{};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    offset[axis] = static_cast<std::size_t>(layout.field_offset[header.xyz[axis]]);
    size[axis] = header.fields[header.xyz[axis]].size;
  }
  const PcdField* const time = header.time ? &header.fields[*header.time] : nullptr;
  const auto time_offset =
      time ? static_cast<std::size_t>(layout.field_offset[*header.time]) : std::size_t{0};
  const auto n = static_cast<std::size_t>(header.points);
  sink.reserve(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    const char* const point = base + i * step;
    const double x = load_pcd_coordinate(point + offset[0], size[0]);
    const double y = load_pcd_coordinate(point + offset[1], size[1]);
    const double z = load_pcd_coordinate(point + offset[2], size[2]);
    if (time) {
      sink.add(x, y, z, load_pcd_time_s(point + time_offset, *time));
    } else {
      sink.add(x, y, z);
    }
  }
}

// Size of the output of an LZF block, found by walking its control bytes without writing
// anything, so that a lying or corrupt block is rejected before its output is allocated.
// nullopt when the block is corrupt: a run or reference cut off by the end, or a back reference
// to before the start of the output. Format: a control byte c < 32 starts a run of c + 1 literal
// bytes; otherwise it is a back reference of length (c >> 5) + 2 (a second byte extends length
// 7), its offset ((c & 31) << 8) + the next byte + 1.
std::optional<std::uint64_t> lzf_output_size(std::string_view block) {
  std::uint64_t out = 0;
  std::size_t in = 0;
  while (in < block.size()) {
    const auto control = static_cast<unsigned char>(block[in++]);
    if (control < 32) {
      const std::size_t run = control + 1u;
      if (run > block.size() - in) return std::nullopt;
      in += run;
      out += run;
      continue;
    }
    std::uint64_t length = control >> 5;
    if (length == 7) {
      if (in >= block.size()) return std::nullopt;
      length += static_cast<unsigned char>(block[in++]);
    }
    if (in >= block.size()) return std::nullopt;
    const std::uint64_t offset =
        ((std::uint64_t{control} & 31u) << 8) + static_cast<unsigned char>(block[in++]) + 1;
    if (offset > out) return std::nullopt;
    out += length + 2;
  }
  return out;
}

// The points of decompressed data, stored as structure of arrays: all values of the first
// field, then all of the second, ...
void add_pcd_columns(const PcdHeader& header, const PcdLayout& layout, const std::vector<char>& raw,
                     PointSink& sink) {
  const auto n = static_cast<std::size_t>(header.points);
  std::array<const char*, 3> column{};
  std::array<std::size_t, 3> size{};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const std::size_t field = header.xyz[axis];
    column[axis] = raw.data() + n * static_cast<std::size_t>(layout.field_offset[field]);
    size[axis] = header.fields[field].size;
  }
  const PcdField* const time = header.time ? &header.fields[*header.time] : nullptr;
  const char* const times =
      time ? raw.data() + n * static_cast<std::size_t>(layout.field_offset[*header.time]) : nullptr;
  sink.reserve(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = load_pcd_coordinate(column[0] + i * size[0], size[0]);
    const double y = load_pcd_coordinate(column[1] + i * size[1], size[1]);
    const double z = load_pcd_coordinate(column[2] + i * size[2], size[2]);
    if (time) {
      sink.add(x, y, z, load_pcd_time_s(times + i * time->size, *time));
    } else {
      sink.add(x, y, z);
    }
  }
}

void read_pcd_compressed(const std::string& name, const PcdHeader& header, std::string_view data,
                         PointSink& sink) {
  // The most LZF can expand: a 3-byte back reference emits at most 264 bytes.
  constexpr std::uint64_t kMaxLzfRatio = 264 / 3;
  const PcdLayout layout = pcd_layout(name, header);
  const std::size_t start = header.data_offset;
  const std::size_t available = data.size() - start;
  if (available < 8) {
    fail_byte(name, start,
              "truncated compressed header (need 8 bytes, have " + std::to_string(available) + ")");
  }
  const auto compressed = load<std::uint32_t>(data.data() + start, false);
  const auto uncompressed = load<std::uint32_t>(data.data() + start + 4, false);
  const auto need = checked_mul(header.points, layout.point_size);
  if (!need || *need != uncompressed) {
    fail_byte(name, start + 4,
              "uncompressed size " + std::to_string(uncompressed) +
                  " does not match POINTS x point size = " + byte_count_text(need));
  }
  if (compressed > available - 8) {
    fail_byte(name, start + 8,
              "truncated compressed data (need " + std::to_string(compressed) + " bytes, have " +
                  std::to_string(available - 8) + ")");
  }
  check_pcd_end(name, data, start + 8 + compressed);
  if (uncompressed == 0) return;
  if (uncompressed > std::uint64_t{compressed} * kMaxLzfRatio) {
    fail_byte(name, start + 4,
              "uncompressed size " + std::to_string(uncompressed) + " is impossible for " +
                  std::to_string(compressed) + " bytes of LZF data");
  }
  const std::string_view block = data.substr(start + 8, compressed);
  if (const auto decoded = lzf_output_size(block); decoded != uncompressed) {
    fail_byte(name, start + 8,
              !decoded ? "corrupt LZF data"
                       : "LZF data decompress to " + std::to_string(*decoded) +
                             " bytes, expected " + std::to_string(uncompressed));
  }
  std::vector<char> raw(uncompressed);
  const unsigned int got =
      lzf_decompress(data.data() + start + 8, compressed, raw.data(), uncompressed);
  if (got != uncompressed) {
    fail_byte(name, start + 8,
              got == 0 ? "corrupt LZF data"
                       : "LZF data decompress to " + std::to_string(got) + " bytes, expected " +
                             std::to_string(uncompressed));
  }
  add_pcd_columns(header, layout, raw, sink);
}

}  // namespace

void read_pcd(const std::string& name, std::string_view data, PointSink& sink) {
  TextCursor cursor(data, 0, 1);
  const PcdHeader header = parse_pcd_header(name, cursor);
  sink.result().points_in_file = static_cast<std::size_t>(header.points);
  if (header.time) sink.record_times();
  switch (header.data) {
    case PcdData::ascii:
      read_pcd_ascii(name, header, cursor, sink);
      break;
    case PcdData::binary:
      read_pcd_binary(name, header, data, sink);
      break;
    case PcdData::binary_compressed:
      read_pcd_compressed(name, header, data, sink);
      break;
  }
}

std::string pcd_text(const PointCloud& cloud, Encoding encoding) {
  // A cloud with times gets a float field `time` (seconds), which the reader reads back.
  const bool times = cloud.has_times();
  const auto with_time = [&](const std::string& xyz, const std::string& time) {
    return times ? xyz + " " + time : xyz;
  };
  const std::string n = std::to_string(cloud.size());
  const std::string sizes = written_in_double(cloud) ? "8 8 8" : "4 4 4";
  std::string out = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " +
                    with_time("x y z", "time") + "\nSIZE " + with_time(sizes, "4") + "\nTYPE " +
                    with_time("F F F", "F") + "\nCOUNT " + with_time("1 1 1", "1") + "\nWIDTH " +
                    n + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + n + "\nDATA " +
                    (encoding == Encoding::ascii ? "ascii" : "binary") + "\n";
  if (encoding == Encoding::ascii) {
    append_points_text(out, cloud, times);
  } else {
    append_points_binary(out, cloud, times);
  }
  return out;
}

}  // namespace sgdicp::io_detail
