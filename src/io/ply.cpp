// PLY: reading ascii, binary little and big endian; writing binary little endian or ascii.
#include "io/io_internal.hpp"

namespace sgdicp::io_detail {
namespace {

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };
enum class PlyEncoding { ascii, binary_little_endian, binary_big_endian };

std::optional<PlyType> ply_type(std::string_view name) {
  static constexpr std::array<std::pair<std::string_view, PlyType>, 16> kNames = {{
      {"char", PlyType::i8},
      {"int8", PlyType::i8},
      {"uchar", PlyType::u8},
      {"uint8", PlyType::u8},
      {"short", PlyType::i16},
      {"int16", PlyType::i16},
      {"ushort", PlyType::u16},
      {"uint16", PlyType::u16},
      {"int", PlyType::i32},
      {"int32", PlyType::i32},
      {"uint", PlyType::u32},
      {"uint32", PlyType::u32},
      {"float", PlyType::f32},
      {"float32", PlyType::f32},
      {"double", PlyType::f64},
      {"float64", PlyType::f64},
  }};
  for (const auto& [text, type] : kNames) {
    if (text == name) return type;
  }
  return std::nullopt;
}

// The PLY name of a type, from the table above (its first spelling).
std::string ply_type_name(PlyType type) {
  for (const std::string_view name :
       {"char", "uchar", "short", "ushort", "int", "uint", "float", "double"}) {
    if (ply_type(name) == type) return std::string(name);
  }
  return "value";
}

std::size_t ply_size(PlyType type) {
  switch (type) {
    case PlyType::i8:
    case PlyType::u8:
      return 1;
    case PlyType::i16:
    case PlyType::u16:
      return 2;
    case PlyType::i32:
    case PlyType::u32:
    case PlyType::f32:
      return 4;
    case PlyType::f64:
      return 8;
  }
  return 0;
}

double ply_value(PlyType type, const char* p, bool big_endian) {
  switch (type) {
    case PlyType::i8:
      return load<std::int8_t>(p, big_endian);
    case PlyType::u8:
      return load<std::uint8_t>(p, big_endian);
    case PlyType::i16:
      return load<std::int16_t>(p, big_endian);
    case PlyType::u16:
      return load<std::uint16_t>(p, big_endian);
    case PlyType::i32:
      return load<std::int32_t>(p, big_endian);
    case PlyType::u32:
      return load<std::uint32_t>(p, big_endian);
    case PlyType::f32:
      return load<float>(p, big_endian);
    case PlyType::f64:
      return load<double>(p, big_endian);
  }
  return 0.0;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::f32;  // the item type for a list
  bool is_list = false;
  PlyType count_type = PlyType::u8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  std::size_t line = 0;
};

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::ascii;
  std::vector<PlyElement> elements;
  std::size_t vertex = 0;            // index of the vertex element
  std::array<std::size_t, 3> xyz{};  // property index of x, y, z in it
  std::optional<std::size_t> time;   // property index of the per-point time in it, if any
  std::size_t data_offset = 0;
  std::size_t end_line = 0;  // line of end_header
};

// One header line: its tokens, its text and its number, for the messages.
struct PlyHeaderLine {
  const std::string& name;
  std::size_t at;
  std::string_view text;
  std::span<const std::string_view> tokens;

  [[noreturn]] void fail(const std::string& what) const { fail_line(name, at, what); }
};

PlyEncoding parse_ply_format(const PlyHeaderLine& line) {
  const auto& tokens = line.tokens;
  const bool known_version = tokens.size() == 3 && (tokens[2] == "1.0" || tokens[2] == "1");
  if (known_version && tokens[1] == "ascii") return PlyEncoding::ascii;
  if (known_version && tokens[1] == "binary_little_endian") {
    return PlyEncoding::binary_little_endian;
  }
  if (known_version && tokens[1] == "binary_big_endian") return PlyEncoding::binary_big_endian;
  line.fail("bad format line " + shown(trim(line.text)) +
            " (expected 'format ascii|binary_little_endian|binary_big_endian 1.0')");
}

PlyElement parse_ply_element(const PlyHeaderLine& line) {
  std::uint64_t count = 0;
  if (line.tokens.size() != 3 || !parse_uint(line.tokens[2], count)) {
    line.fail("bad element line " + shown(trim(line.text)) +
              " (expected 'element <name> <count>')");
  }
  return PlyElement{std::string(line.tokens[1]), count, {}, line.at};
}

PlyProperty parse_ply_property(const PlyHeaderLine& line) {
  const auto& tokens = line.tokens;
  if (tokens.size() == 5 && tokens[1] == "list") {
    const auto count_type = ply_type(tokens[2]);
    const auto item_type = ply_type(tokens[3]);
    if (!count_type || !item_type) line.fail("unknown type in " + shown(trim(line.text)));
    if (*count_type == PlyType::f32 || *count_type == PlyType::f64) {
      line.fail("list length type must be an integer type");
    }
    return PlyProperty{std::string(tokens[4]), *item_type, true, *count_type};
  }
  if (tokens.size() == 3) {
    const auto type = ply_type(tokens[1]);
    if (!type) line.fail("unknown property type " + shown(tokens[1]));
    return PlyProperty{std::string(tokens[2]), *type};
  }
  line.fail("bad property line " + shown(trim(line.text)));
}

// Reads the header lines up to end_header: the format, the elements and their properties.
void parse_ply_header_lines(const std::string& name, TextCursor& cursor, PlyHeader& header) {
  bool have_format = false;
  bool have_end = false;
  std::string_view text;
  while (!have_end && cursor.next_line(text)) {
    const auto tokens = split_whitespace(text);
    if (tokens.empty()) continue;
    const PlyHeaderLine line{name, cursor.line(), text, tokens};
    const std::string_view keyword = tokens[0];
    if (keyword == "format") {
      if (have_format) line.fail("second format line");
      header.encoding = parse_ply_format(line);
      have_format = true;
    } else if (keyword == "comment" || keyword == "obj_info") {
      continue;
    } else if (keyword == "element") {
      header.elements.push_back(parse_ply_element(line));
    } else if (keyword == "property") {
      if (header.elements.empty()) line.fail("property before any element");
      header.elements.back().properties.push_back(parse_ply_property(line));
    } else if (keyword == "end_header") {
      have_end = true;
      header.end_line = line.at;
      header.data_offset = cursor.offset();
    } else {
      line.fail("unknown PLY header keyword " + shown(keyword));
    }
  }
  if (!have_end) fail_line(name, cursor.line(), "PLY header has no end_header line");
  if (!have_format) fail_line(name, header.end_line, "PLY header has no format line");
}

// Index of the one vertex element.
std::size_t find_ply_vertex(const std::string& name, const PlyHeader& header) {
  const auto is_vertex = [](const PlyElement& e) { return e.name == "vertex"; };
  const auto vertex = std::find_if(header.elements.begin(), header.elements.end(), is_vertex);
  if (vertex == header.elements.end())
    fail_line(name, header.end_line, "PLY has no vertex element");
  if (std::find_if(vertex + 1, header.elements.end(), is_vertex) != header.elements.end()) {
    fail_line(name, header.end_line, "PLY has two vertex elements");
  }
  return static_cast<std::size_t>(vertex - header.elements.begin());
}

// Property index of x, y and z in the vertex element: each must be there, and not a list.
std::array<std::size_t, 3> find_ply_xyz(const std::string& name, const PlyElement& vertex) {
  std::array<std::size_t, 3> xyz{};
  constexpr std::array<std::string_view, 3> kAxes = {"x", "y", "z"};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const auto& props = vertex.properties;
    const auto found = std::find_if(props.begin(), props.end(),
                                    [&](const PlyProperty& p) { return p.name == kAxes[axis]; });
    if (found == props.end()) {
      fail_line(name, vertex.line,
                "vertex element has no '" + std::string(kAxes[axis]) + "' property");
    }
    if (found->is_list)
      fail_line(name, vertex.line, "vertex property '" + found->name + "' is a list");
    xyz[axis] = static_cast<std::size_t>(found - props.begin());
  }
  return xyz;
}

// Property index of the per-point time in the vertex element (docs/io.md, "Per-point times"):
// a scalar, named once.
std::optional<std::size_t> find_ply_time(const std::string& name, const PlyElement& vertex) {
  const auto& props = vertex.properties;
  const auto time = find_time_field(
      props.size(), [&](std::size_t i) -> std::string_view { return props[i].name; });
  if (!time) return std::nullopt;
  const PlyProperty& property = props[*time];
  if (std::count_if(props.begin(), props.end(),
                    [&](const PlyProperty& p) { return p.name == property.name; }) > 1) {
    fail_line(name, vertex.line, "vertex property '" + property.name + "' appears twice");
  }
  if (property.is_list) {
    fail_line(name, vertex.line,
              "vertex property '" + property.name + "' (the per-point time) is a list");
  }
  return time;
}

// Seconds per unit of a time property: an integer counts nanoseconds.
double ply_time_unit_s(PlyType type) {
  return time_field_unit_s(type != PlyType::f32 && type != PlyType::f64);
}

PlyHeader parse_ply_header(const std::string& name, TextCursor& cursor) {
  PlyHeader header;
  std::string_view line;
  if (!cursor.next_line(line) || trim(line) != "ply") {
    fail_line(name, 1, "not a PLY file (the first line must be 'ply')");
  }
  parse_ply_header_lines(name, cursor, header);
  header.vertex = find_ply_vertex(name, header);
  const PlyElement& vertex = header.elements[header.vertex];
  header.xyz = find_ply_xyz(name, vertex);
  header.time = find_ply_time(name, vertex);
  if (beyond_cloud_limit(vertex.count)) {
    fail_line(name, vertex.line, "element vertex: " + cloud_limit_text(vertex.count));
  }
  return header;
}

// Whether a token is a value of a PLY type: a number for float and double, an integer that
// fits the type for the others.
bool is_ply_value(PlyType type, std::string_view token) {
  double ignored = 0.0;
  if (type == PlyType::f32 || type == PlyType::f64) return parse_number(token, ignored);
  const bool is_signed = type == PlyType::i8 || type == PlyType::i16 || type == PlyType::i32;
  return is_integer_token(token, ply_size(type), is_signed);
}

void read_ply_ascii(const std::string& name, const PlyHeader& header, TextCursor& cursor,
                    PointSink& sink) {
  std::string_view token;
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    const bool is_vertex = e == header.vertex;
    if (element.properties.empty()) continue;  // records without properties take no text
    if (is_vertex) sink.reserve(element.count, cursor.remaining() / kMinTextPointBytes);
    for (std::uint64_t r = 0; r < element.count; ++r) {
      const auto next = [&]() {
        if (!cursor.next_token(token)) {
          fail_line(name, cursor.line(),
                    "unexpected end of file in element '" + element.name + "' (record " +
                        std::to_string(r + 1) + " of " + std::to_string(element.count) + ")");
        }
        return token;
      };
      std::array<double, 4> p{};  // x, y, z and the time
      for (std::size_t k = 0; k < element.properties.size(); ++k) {
        const PlyProperty& property = element.properties[k];
        const std::string_view value = next();
        const auto check = [&](PlyType type, std::string_view text) {
          if (!is_ply_value(type, text)) {
            fail_line(name, cursor.line(),
                      shown(text) + " is not " +
                          (type == PlyType::f32 || type == PlyType::f64
                               ? std::string("a number")
                               : "a " + ply_type_name(type) + " value") +
                          " (property '" + property.name + "')");
          }
        };
        if (property.is_list) {
          std::uint64_t length = 0;
          if (!parse_uint(value, length) || !is_ply_value(property.count_type, value)) {
            fail_line(name, cursor.line(),
                      shown(value) + " is not a list length of type " +
                          ply_type_name(property.count_type) + " (property '" + property.name +
                          "')");
          }
          for (std::uint64_t i = 0; i < length; ++i) check(property.type, next());
          continue;
        }
        check(property.type, value);
        if (is_vertex) {
          for (std::size_t w = 0; w < 4; ++w) {
            const bool wanted = w < 3 ? header.xyz[w] == k : header.time == k;
            if (wanted && !parse_number(value, p[w])) {
              fail_line(name, cursor.line(),
                        shown(value) + " is not a number (property '" + property.name + "')");
            }
          }
        }
      }
      if (is_vertex && header.time) {
        const PlyType time_type = element.properties[*header.time].type;
        sink.add(p[0], p[1], p[2], p[3] * ply_time_unit_s(time_type));
      } else if (is_vertex) {
        sink.add(p[0], p[1], p[2]);
      }
    }
  }
  if (cursor.next_token(token)) {
    fail_line(name, cursor.line(), "unexpected data after the last element: " + shown(token));
  }
}

// Fixed record size of an element without list properties.
std::optional<std::size_t> ply_fixed_stride(const PlyElement& element) {
  std::size_t stride = 0;
  for (const auto& property : element.properties) {
    if (property.is_list) return std::nullopt;
    stride += ply_size(property.type);
  }
  return stride;
}

// Reads binary records element by element, from the end of the header to the end of the data,
// and hands the vertices to the sink.
class PlyBinaryReader {
 public:
  PlyBinaryReader(const std::string& name, const PlyHeader& header, std::string_view data,
                  PointSink& sink)
      : name_(name),
        header_(header),
        data_(data),
        sink_(sink),
        big_endian_(header.encoding == PlyEncoding::binary_big_endian),
        pos_(header.data_offset) {
    const PlyElement& vertex = header.elements[header.vertex];
    for (std::size_t axis = 0; axis < 3; ++axis) {
      wanted_[axis] = header.xyz[axis];
      xyz_type_[axis] = vertex.properties[header.xyz[axis]].type;
    }
    // Without a time, x stands in for it: its position is found but never read as a time.
    wanted_[3] = header.time.value_or(header.xyz[0]);
    if (header.time) time_type_ = vertex.properties[*header.time].type;
  }

  void read() {
    for (std::size_t e = 0; e < header_.elements.size(); ++e) {
      const PlyElement& element = header_.elements[e];
      const bool is_vertex = e == header_.vertex;
      if (const auto stride = ply_fixed_stride(element)) {
        read_fixed(element, is_vertex, *stride);
      } else {
        read_with_lists(element, is_vertex);
      }
    }
    if (pos_ != data_.size()) {
      fail_byte(name_, pos_,
                std::to_string(data_.size() - pos_) +
                    " bytes after the last element (binary PLY ends with its data)");
    }
  }

 private:
  // Fixed-size records: one bounds check for the whole element.
  void read_fixed(const PlyElement& element, bool is_vertex, std::size_t stride) {
    const std::size_t available = data_.size() - pos_;
    const auto need = checked_mul(element.count, stride);
    if (!need || *need > available) {
      fail_byte(name_, pos_,
                "truncated binary data (need " + byte_count_text(need) + " bytes of " +
                    element.name + " data, have " + std::to_string(available) + ")");
    }
    if (is_vertex) {
      std::array<std::size_t, 4> offset{};  // of x, y, z and the time in a vertex record
      for (std::size_t w = 0; w < 4; ++w) {
        for (std::size_t k = 0; k < wanted_[w]; ++k) {
          offset[w] += ply_size(element.properties[k].type);
        }
      }
      const auto n = static_cast<std::size_t>(element.count);
      sink_.reserve(n, n);
      for (std::size_t i = 0; i < n; ++i) add_vertex(data_.data() + pos_ + i * stride, offset);
    }
    pos_ += static_cast<std::size_t>(*need);
  }

  // Records with lists: walk them one property at a time.
  void read_with_lists(const PlyElement& element, bool is_vertex) {
    if (is_vertex) sink_.reserve(element.count, (data_.size() - pos_) / 3);
    for (std::uint64_t r = 0; r < element.count; ++r) {
      const std::array<std::size_t, 4> at = walk_record(element, r);
      if (is_vertex) add_vertex(data_.data(), at);
    }
  }

  // Steps over record r of an element; returns the byte positions of its x, y, z and time
  // properties (meaningful for a vertex record only).
  std::array<std::size_t, 4> walk_record(const PlyElement& element, std::uint64_t r) {
    std::array<std::size_t, 4> wanted_at{};
    for (std::size_t k = 0; k < element.properties.size(); ++k) {
      const PlyProperty& property = element.properties[k];
      if (!property.is_list) {
        const std::size_t at = take(element, r, ply_size(property.type));
        for (std::size_t w = 0; w < 4; ++w) {
          if (wanted_[w] == k) wanted_at[w] = at;
        }
        continue;
      }
      const std::size_t at = take(element, r, ply_size(property.count_type));
      const double length = ply_value(property.count_type, data_.data() + at, big_endian_);
      if (length < 0) {
        fail_byte(name_, at, "negative list length in element '" + element.name + "'");
      }
      const auto bytes = checked_mul(static_cast<std::uint64_t>(length), ply_size(property.type));
      take(element, r, bytes ? *bytes : std::numeric_limits<std::uint64_t>::max());
    }
    return wanted_at;
  }

  // Steps over the next bytes of record r; returns where they start.
  std::size_t take(const PlyElement& element, std::uint64_t r, std::uint64_t bytes) {
    const std::size_t start = pos_;
    if (bytes > data_.size() - pos_) {
      fail_byte(name_, pos_,
                "truncated binary data in element '" + element.name + "' (record " +
                    std::to_string(r + 1) + " of " + std::to_string(element.count) + ")");
    }
    pos_ += static_cast<std::size_t>(bytes);
    return start;
  }

  // The vertex whose x, y, z and time values are at base + offset.
  void add_vertex(const char* base, const std::array<std::size_t, 4>& offset) {
    const double x = ply_value(xyz_type_[0], base + offset[0], big_endian_);
    const double y = ply_value(xyz_type_[1], base + offset[1], big_endian_);
    const double z = ply_value(xyz_type_[2], base + offset[2], big_endian_);
    if (time_type_) {
      const double time = ply_value(*time_type_, base + offset[3], big_endian_);
      sink_.add(x, y, z, time * ply_time_unit_s(*time_type_));
    } else {
      sink_.add(x, y, z);
    }
  }

  const std::string& name_;
  const PlyHeader& header_;
  std::string_view data_;
  PointSink& sink_;
  bool big_endian_;
  std::size_t pos_;                      // the next byte to read
  std::array<std::size_t, 4> wanted_{};  // property index of x, y, z and the time in a vertex
  std::array<PlyType, 3> xyz_type_{};    // type of x, y, z in the vertex element
  std::optional<PlyType> time_type_;     // type of the time, if the vertices have one
};

void read_ply_binary(const std::string& name, const PlyHeader& header, std::string_view data,
                     PointSink& sink) {
  PlyBinaryReader(name, header, data, sink).read();
}

}  // namespace

void read_ply(const std::string& name, std::string_view data, PointSink& sink) {
  TextCursor cursor(data, 0, 1);
  const PlyHeader header = parse_ply_header(name, cursor);
  sink.result().points_in_file = static_cast<std::size_t>(header.elements[header.vertex].count);
  if (header.time) sink.record_times();
  if (header.encoding == PlyEncoding::ascii) {
    read_ply_ascii(name, header, cursor, sink);
  } else {
    read_ply_binary(name, header, data, sink);
  }
}

std::string ply_text(const PointCloud& cloud, Encoding encoding) {
  // A cloud with times gets a float property `time` (seconds), which the reader reads back.
  const bool times = cloud.has_times();
  const std::string type = written_in_double(cloud) ? "double" : "float";
  std::string out = "ply\nformat ";
  out += encoding == Encoding::ascii ? "ascii" : "binary_little_endian";
  out += " 1.0\ncomment written by sgdicp\nelement vertex " + std::to_string(cloud.size()) +
         "\nproperty " + type + " x\nproperty " + type + " y\nproperty " + type + " z\n" +
         (times ? "property float time\n" : "") + "end_header\n";
  if (encoding == Encoding::ascii) {
    append_points_text(out, cloud, times);
  } else {
    append_points_binary(out, cloud, times);
  }
  return out;
}

}  // namespace sgdicp::io_detail
