// Legacy ASCII VTK POLYDATA (POINTS n float|double).
#include "io/io_internal.hpp"

namespace sgdicp::io_detail {

void read_vtk(const std::string& name, std::string_view data, PointSink& sink) {
  TextCursor cursor(data, 0, 1);
  std::string_view line;
  constexpr std::string_view kMagic = "# vtk DataFile Version";
  if (!cursor.next_line(line) || line.size() < kMagic.size() ||
      !iequals(line.substr(0, kMagic.size()), kMagic)) {
    fail_line(name, 1, "not a legacy VTK file (expected '# vtk DataFile Version x.y')");
  }
  if (!cursor.next_line(line)) fail_line(name, 1, "VTK header ends after the first line");

  std::string_view token;
  const auto next = [&](const char* what) {
    if (!cursor.next_token(token)) {
      fail_line(name, cursor.line(), std::string("unexpected end of file, expected ") + what);
    }
    return token;
  };
  if (const auto encoding = next("ASCII or BINARY"); iequals(encoding, "BINARY")) {
    fail_line(name, cursor.line(), "binary VTK not supported");
  } else if (!iequals(encoding, "ASCII")) {
    fail_line(name, cursor.line(), "expected ASCII or BINARY, got " + shown(encoding));
  }
  if (const auto keyword = next("DATASET"); !iequals(keyword, "DATASET")) {
    fail_line(name, cursor.line(), "expected DATASET, got " + shown(keyword));
  }
  if (const auto dataset = next("POLYDATA"); !iequals(dataset, "POLYDATA")) {
    fail_line(name, cursor.line(), "unsupported dataset " + shown(dataset) + " (only POLYDATA)");
  }
  if (const auto keyword = next("POINTS"); !iequals(keyword, "POINTS")) {
    fail_line(name, cursor.line(), "expected POINTS, got " + shown(keyword));
  }
  std::uint64_t count = 0;
  if (const auto text = next("the point count"); !parse_uint(text, count)) {
    fail_line(name, cursor.line(), "point count " + shown(text) + " is not a count");
  }
  if (const auto type = next("the point type");
      !iequals(type, "float") && !iequals(type, "double")) {
    fail_line(name, cursor.line(), "unsupported POINTS type " + shown(type) + " (float or double)");
  }

  if (beyond_cloud_limit(count)) fail_line(name, cursor.line(), cloud_limit_text(count));
  sink.result().points_in_file = static_cast<std::size_t>(count);
  sink.reserve(count, cursor.remaining() / kMinTextPointBytes);
  for (std::uint64_t i = 0; i < count; ++i) {
    std::array<double, 3> p{};
    for (std::size_t axis = 0; axis < 3; ++axis) {
      if (!cursor.next_token(token)) {
        fail_line(name, cursor.line(),
                  "POINTS declares " + std::to_string(count) + " points (" +
                      std::to_string(count * 3) + " numbers), file ends after " +
                      std::to_string(i * 3 + axis) + " numbers");
      }
      if (!parse_number(token, p[axis])) {
        fail_line(name, cursor.line(), shown(token) + " is not a number");
      }
    }
    sink.add(p[0], p[1], p[2]);
  }
}

}  // namespace sgdicp::io_detail
