#include "sgdicp/tools/render.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "sgdicp/core/error.hpp"

// stb_image_write is third-party C code; its implementation does not compile warning-free with
// our flags. The functions are made static so they cannot clash with another copy in the program.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image_write.h>
#pragma GCC diagnostic pop

namespace sgdicp {
namespace {

constexpr int kMinSize = 64;
constexpr int kMaxSize = 8192;

struct Rgb {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
};

constexpr Rgb kBackground{255, 255, 255};
constexpr Rgb kReferenceColour{70, 130, 180};  // steel blue
constexpr Rgb kSourceColour{255, 140, 0};      // dark orange
constexpr Rgb kTextColour{40, 40, 40};
constexpr Rgb kFrameColour{190, 190, 190};

// ---------------------------------------------------------------------------------------------
// A tiny bitmap font: 5 columns, 7 rows from the top of a digit to the baseline plus 2 rows for
// descenders (g, p, y). Each glyph is 9 rows of 5 characters separated by spaces, '#' = ink.
// Only the characters the picture needs are defined; anything else is drawn blank.

constexpr int kGlyphColumns = 5;
constexpr int kGlyphRows = 9;
constexpr int kGlyphAdvance = kGlyphColumns + 1;  // one column of spacing
constexpr int kSpaceAdvance = 4;                  // a narrower space reads better

[[nodiscard]] constexpr int advance_of(const char c) {
  return c == ' ' ? kSpaceAdvance : kGlyphAdvance;
}

struct Glyph {
  char character;
  std::string_view rows;
};

// clang-format off
constexpr std::array kFont{
    Glyph{'a', "..... ..... .###. ....# .#### #...# .#### ..... ....."},
    Glyph{'c', "..... ..... .###. #...# #.... #...# .###. ..... ....."},
    Glyph{'d', "....# ....# .#### #...# #...# #...# .#### ..... ....."},
    Glyph{'e', "..... ..... .###. #...# ##### #.... .###. ..... ....."},
    Glyph{'f', "..##. .#... ####. .#... .#... .#... .#... ..... ....."},
    Glyph{'g', "..... ..... .#### #...# #...# #...# .#### ....# .###."},
    Glyph{'h', "#.... #.... #.##. ##..# #...# #...# #...# ..... ....."},
    Glyph{'i', "..#.. ..... .##.. ..#.. ..#.. ..#.. .###. ..... ....."},
    Glyph{'l', ".##.. ..#.. ..#.. ..#.. ..#.. ..#.. .###. ..... ....."},
    Glyph{'m', "..... ..... ##.#. #.#.# #.#.# #.#.# #.#.# ..... ....."},
    Glyph{'n', "..... ..... #.##. ##..# #...# #...# #...# ..... ....."},
    Glyph{'o', "..... ..... .###. #...# #...# #...# .###. ..... ....."},
    Glyph{'p', "..... ..... ####. #...# #...# #...# ####. #.... #...."},
    Glyph{'r', "..... ..... #.##. ##..# #.... #.... #.... ..... ....."},
    Glyph{'s', "..... ..... .#### #.... .###. ....# ####. ..... ....."},
    Glyph{'t', ".#... .#... ####. .#... .#... .#..# ..##. ..... ....."},
    Glyph{'u', "..... ..... #...# #...# #...# #..## .##.# ..... ....."},
    Glyph{'v', "..... ..... #...# #...# #...# .#.#. ..#.. ..... ....."},
    Glyph{'w', "..... ..... #...# #...# #.#.# #.#.# .#.#. ..... ....."},
    Glyph{'x', "..... ..... #...# .#.#. ..#.. .#.#. #...# ..... ....."},
    Glyph{'y', "..... ..... #...# #...# #...# #...# .#### ....# .###."},
    Glyph{'z', "..... ..... ##### ...#. ..#.. .#... ##### ..... ....."},
    Glyph{'(', "...#. ..#.. .#... .#... .#... ..#.. ...#. ..... ....."},
    Glyph{')', ".#... ..#.. ...#. ...#. ...#. ..#.. .#... ..... ....."},
    Glyph{'-', "..... ..... ..... ..... .###. ..... ..... ..... ....."},
    Glyph{'.', "..... ..... ..... ..... ..... .##.. .##.. ..... ....."},
    Glyph{'0', ".###. #...# #..## #.#.# ##..# #...# .###. ..... ....."},
    Glyph{'1', "..#.. .##.. ..#.. ..#.. ..#.. ..#.. .###. ..... ....."},
    Glyph{'2', ".###. #...# ....# ...#. ..#.. .#... ##### ..... ....."},
    Glyph{'3', "##### ...#. ..#.. ...#. ....# #...# .###. ..... ....."},
    Glyph{'4', "...#. ..##. .#.#. #..#. ##### ...#. ...#. ..... ....."},
    Glyph{'5', "##### #.... ####. ....# ....# #...# .###. ..... ....."},
    Glyph{'6', "..##. .#... #.... ####. #...# #...# .###. ..... ....."},
    Glyph{'7', "##### ....# ...#. ..#.. .#... .#... .#... ..... ....."},
    Glyph{'8', ".###. #...# #...# .###. #...# #...# .###. ..... ....."},
    Glyph{'9', ".###. #...# #...# .#### ....# ...#. .##.. ..... ....."},
};
// clang-format on

constexpr bool font_is_well_formed() {
  for (const auto& glyph : kFont) {
    if (glyph.rows.size() != kGlyphRows * kGlyphAdvance - 1) return false;
    for (std::size_t i = 0; i < glyph.rows.size(); ++i) {
      const char c = glyph.rows[i];
      const bool separator = (i + 1) % kGlyphAdvance == 0;
      if (separator ? c != ' ' : (c != '.' && c != '#')) return false;
    }
  }
  return true;
}
static_assert(font_is_well_formed(), "every glyph must be 9 rows of 5 '.'/'#' separated by ' '");

const Glyph* find_glyph(const char c) {
  const auto it =
      std::find_if(kFont.begin(), kFont.end(), [c](const Glyph& g) { return g.character == c; });
  return it == kFont.end() ? nullptr : &*it;
}

// ---------------------------------------------------------------------------------------------

struct Rect {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
};

/// An RGB picture, row-major from the top-left, with clipped drawing primitives.
class Image {
 public:
  Image(const int width, const int height)
      : width_(width),
        height_(height),
        pixels_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3) {
    fill_rect({0, 0, width, height}, kBackground);
  }

  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }
  [[nodiscard]] const std::uint8_t* data() const { return pixels_.data(); }

  /// Mixes `colour` into the pixel with weight `alpha` in [0, 1]; outside the picture: no-op.
  void blend(const int x, const int y, const Rgb colour, const double alpha) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
    const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                           static_cast<std::size_t>(x)) *
                          3;
    const auto mix = [alpha](const std::uint8_t old_value, const std::uint8_t new_value) {
      const double v = old_value + alpha * (static_cast<double>(new_value) - old_value);
      return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    };
    pixels_[i] = mix(pixels_[i], colour.r);
    pixels_[i + 1] = mix(pixels_[i + 1], colour.g);
    pixels_[i + 2] = mix(pixels_[i + 2], colour.b);
  }

  void set(const int x, const int y, const Rgb colour) { blend(x, y, colour, 1.0); }

  void fill_rect(const Rect& r, const Rgb colour) {
    const int x0 = std::max(r.x, 0);
    const int y0 = std::max(r.y, 0);
    const int x1 = std::min(r.x + r.width, width_);
    const int y1 = std::min(r.y + r.height, height_);
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) set(x, y, colour);
    }
  }

  /// One-pixel outline of a rectangle.
  void outline_rect(const Rect& r, const Rgb colour) {
    fill_rect({r.x, r.y, r.width, 1}, colour);
    fill_rect({r.x, r.y + r.height - 1, r.width, 1}, colour);
    fill_rect({r.x, r.y, 1, r.height}, colour);
    fill_rect({r.x + r.width - 1, r.y, 1, r.height}, colour);
  }

  /// Draws `text` with its top-left corner at (x, y), each font pixel as a scale x scale block.
  void text(const int x, const int y, const std::string_view text, const int scale,
            const Rgb colour) {
    int pen_x = x;
    for (const char c : text) {
      if (const Glyph* glyph = find_glyph(c)) {
        for (int row = 0; row < kGlyphRows; ++row) {
          for (int col = 0; col < kGlyphColumns; ++col) {
            if (glyph->rows[static_cast<std::size_t>(row * kGlyphAdvance + col)] == '#') {
              fill_rect({pen_x + col * scale, y + row * scale, scale, scale}, colour);
            }
          }
        }
      }
      pen_x += advance_of(c) * scale;
    }
  }

 private:
  int width_;
  int height_;
  std::vector<std::uint8_t> pixels_;
};

/// Width in pixels of `text` drawn at `scale` (without the spacing after the last character).
[[nodiscard]] int text_width(const std::string_view text, const int scale) {
  int columns = 0;
  for (const char c : text) columns += advance_of(c);
  return text.empty() ? 0 : (columns - 1) * scale;
}

// ---------------------------------------------------------------------------------------------

/// Applies the rigid part (upper 3x4) of a homogeneous transform.
struct RigidMap {
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;

  explicit RigidMap(const Eigen::Matrix4d& T)
      : rotation(T.topLeftCorner<3, 3>()), translation(T.topRightCorner<3, 1>()) {}

  [[nodiscard]] Eigen::Vector3d operator()(const Eigen::Vector3f& p) const {
    return rotation * p.cast<double>() + translation;
  }
};

[[nodiscard]] std::size_t stride_for(const std::size_t n, const std::size_t max_points) {
  return std::max<std::size_t>(1, (n + max_points - 1) / max_points);
}

/// The largest 1, 2 or 5 times a power of ten not above `limit` (> 0), and its exponent.
struct RoundLength {
  double value = 1.0;
  int exponent = 0;
};

[[nodiscard]] RoundLength round_length_below(const double limit) {
  const int exponent = static_cast<int>(std::floor(std::log10(limit)));
  const double base = std::pow(10.0, exponent);
  const double mantissa = limit / base;
  const double leading = mantissa >= 5.0 ? 5.0 : (mantissa >= 2.0 ? 2.0 : 1.0);
  return {leading * base, exponent};
}

[[nodiscard]] std::string length_label(const RoundLength& length) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(std::max(0, -length.exponent));
  out << length.value << " m";
  return out.str();
}

/// Maps two coordinates of a 3D point (u to the right, v upwards) into a panel's plot area.
struct Projection {
  int u_axis = 0;
  int v_axis = 1;
  double u_min = 0.0;
  double v_min = 0.0;
  double pixels_per_metre = 1.0;
  double origin_x = 0.0;  ///< pixel column of u = u_min
  double origin_y = 0.0;  ///< pixel row of v = v_min (rows grow downwards)

  [[nodiscard]] double x(const Eigen::Vector3d& p) const {
    return origin_x + (p[u_axis] - u_min) * pixels_per_metre;
  }
  [[nodiscard]] double y(const Eigen::Vector3d& p) const {
    return origin_y - (p[v_axis] - v_min) * pixels_per_metre;
  }
};

/// A point to draw, already in the reference frame, with its colour.
struct Dot {
  Eigen::Vector3d position;
  Rgb colour;
};

/// Puts the dots in a pseudo-random but fixed order, so that where the clouds overlap neither
/// is painted entirely over the other: the overlap shows as a speckle of both colours.
void mix_drawing_order(std::vector<Dot>& dots) {
  std::uint64_t state = 0x9e3779b97f4a7c15ULL;
  const auto next = [&state] {  // splitmix64
    state += 0x9e3779b97f4a7c15ULL;
    std::uint64_t z = state;
    z = (z ^ (z >> 30U)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27U)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31U);
  };
  for (std::size_t i = dots.size(); i > 1; --i) {
    std::swap(dots[i - 1], dots[static_cast<std::size_t>(next() % i)]);
  }
}

/// Draws alpha-blended square dots of `size` pixels, skipping those outside `clip`.
void draw_dots(Image& image, const Rect& clip, const Projection& projection,
               const std::vector<Dot>& dots, const int size, const double alpha) {
  for (const auto& dot : dots) {
    const double fx = std::floor(projection.x(dot.position));
    const double fy = std::floor(projection.y(dot.position));
    // The bounds test is done in double, before the conversion to int, so it cannot overflow.
    if (!(fx >= clip.x && fx < clip.x + clip.width && fy >= clip.y && fy < clip.y + clip.height)) {
      continue;
    }
    const int x0 = static_cast<int>(fx);
    const int y0 = static_cast<int>(fy);
    const int x1 = std::min(x0 + size, clip.x + clip.width);
    const int y1 = std::min(y0 + size, clip.y + clip.height);
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) image.blend(x, y, dot.colour, alpha);
    }
  }
}

void check_render_settings(const RenderSettings& settings) {
  const auto check_size = [](const int value, const char* name) {
    if (value < kMinSize || value > kMaxSize) {
      throw InvalidSettingsError("render " + std::string(name) + " must be in [" +
                                 std::to_string(kMinSize) + ", " + std::to_string(kMaxSize) +
                                 "] pixels, got " + std::to_string(value));
    }
  };
  check_size(settings.width, "width");
  check_size(settings.height, "height");
  if (settings.max_points == 0) {
    throw InvalidSettingsError("render max_points must be at least 1");
  }
}

// Scale bar at the bottom right of `frame`: a round length of at most a quarter of a plot's
// width, labelled; returns its left end.
int draw_scale_bar(Image& image, const Rect& frame, const int footer_y, const double plot_width,
                   const double pixels_per_metre, const int text_scale) {
  const RoundLength bar_length = round_length_below(0.25 * plot_width / pixels_per_metre);
  const int bar_pixels =
      std::max(1, static_cast<int>(std::lround(bar_length.value * pixels_per_metre)));
  const std::string bar_label = length_label(bar_length);
  const int label_x = frame.x + frame.width - text_width(bar_label, text_scale);
  image.text(label_x, footer_y, bar_label, text_scale, kTextColour);
  const int bar_right = label_x - 3 * text_scale;
  const int bar_left = bar_right - bar_pixels;
  const int bar_y = footer_y + 3 * text_scale;  // middle of the digits
  const int thickness = text_scale;
  image.fill_rect({bar_left, bar_y, bar_pixels, thickness}, kTextColour);
  for (const int x : {bar_left, bar_right - thickness}) {
    image.fill_rect({x, bar_y - 2 * text_scale, thickness, 4 * text_scale + thickness},
                    kTextColour);
  }
  return bar_left;
}

// Legend at the bottom left: a coloured square and the name of each entry with a name; the names
// are left out when the picture is too narrow for them to fit beside the scale bar.
void draw_legend(Image& image, const std::array<std::pair<Rgb, std::string_view>, 2>& legend,
                 const int left, const int footer_y, const int bar_left, const int text_scale) {
  const int square = 7 * text_scale;
  const int square_gap = 4 * text_scale;
  const int entry_gap = 16 * text_scale;
  int legend_width = 0;
  for (const auto& entry : legend) {
    legend_width += square + square_gap + text_width(entry.second, text_scale) + entry_gap;
  }
  const bool with_names = left + legend_width <= bar_left;
  int pen_x = left;
  for (const auto& [colour, name] : legend) {
    if (name.empty()) continue;
    image.fill_rect({pen_x, footer_y, square, square}, colour);
    pen_x += square + square_gap;
    if (with_names) {
      image.text(pen_x, footer_y, name, text_scale, kTextColour);
      pen_x += text_width(name, text_scale) + entry_gap;
    }
  }
}

/// What one picture shows: dots of up to two colours in one frame, the box they span (which may
/// hold points not drawn), the two views' titles and the legend (colour, name).
struct Scene {
  std::vector<Dot> dots;
  BoundingBox box;
  std::array<std::string_view, 2> titles;
  std::array<std::pair<Rgb, std::string_view>, 2> legend;
};

// Two panels side by side, x-y (left) and x-z (right), sharing one metric scale, under a title
// row and above a footer with the legend and a scale bar.
void write_views_png(const std::filesystem::path& path, Scene scene,
                     const RenderSettings& settings) {
  const BoundingBox& box = scene.box;
  if (!box.valid() || !box.min.allFinite() || !box.max.allFinite()) {
    throw InvalidInputError("cannot render: no finite points");
  }
  mix_drawing_order(scene.dots);

  const int width = settings.width;
  const int height = settings.height;
  Image image(width, height);
  const int text_scale = std::max(1, std::min(width / 2, height) / 300);
  const int line_height = kGlyphRows * text_scale;
  const int pad = 4 * text_scale;
  const int header = line_height + 2 * pad;
  const int footer = line_height + 2 * pad;
  const int dot_size = std::min(width, height) >= 400 ? 2 : 1;

  std::array<Rect, 2> frames;
  for (int i = 0; i < 2; ++i) {
    const int x0 = i * width / 2;
    const int x1 = (i + 1) * width / 2;
    frames[static_cast<std::size_t>(i)] = {x0 + pad, header, std::max(1, x1 - x0 - 2 * pad),
                                           std::max(1, height - header - footer)};
  }
  // Both frames have (nearly) the same size; points stay a margin away from the frame lines.
  const int margin = std::max(pad, std::min(frames[0].width, frames[0].height) / 30);
  const double plot_width = std::max(1, std::min(frames[0].width, frames[1].width) - 2 * margin);
  const double plot_height = std::max(1, std::min(frames[0].height, frames[1].height) - 2 * margin);

  // One scale for both views: the x extent must fit the plot width, y and z its height.
  const Eigen::Vector3d span = box.max - box.min;
  if (!span.allFinite()) {
    throw InvalidInputError("cannot render: the points extend too far to be drawn");
  }
  double pixels_per_metre = std::numeric_limits<double>::infinity();
  if (span.x() > 0.0) pixels_per_metre = std::min(pixels_per_metre, plot_width / span.x());
  if (span.y() > 0.0) pixels_per_metre = std::min(pixels_per_metre, plot_height / span.y());
  if (span.z() > 0.0) pixels_per_metre = std::min(pixels_per_metre, plot_height / span.z());
  if (!std::isfinite(pixels_per_metre)) {
    pixels_per_metre = std::min(plot_width, plot_height);  // a single point: show 1 m
  }

  constexpr double alpha = 0.55;  // dense regions saturate, sparse ones stay light
  for (std::size_t i = 0; i < 2; ++i) {
    const Rect& frame = frames[i];
    const int v_axis = i == 0 ? 1 : 2;
    Projection projection;
    projection.u_axis = 0;
    projection.v_axis = v_axis;
    projection.u_min = box.min.x();
    projection.v_min = box.min[v_axis];
    projection.pixels_per_metre = pixels_per_metre;
    // Centre the content in the frame.
    const double content_width = span.x() * pixels_per_metre;
    const double content_height = span[v_axis] * pixels_per_metre;
    projection.origin_x = frame.x + 0.5 * (frame.width - content_width);
    projection.origin_y = frame.y + 0.5 * (frame.height + content_height);

    image.outline_rect(frame, kFrameColour);
    if (text_width(scene.titles[i], text_scale) <= frame.width) {
      image.text(frame.x, pad, scene.titles[i], text_scale, kTextColour);
    }
    const Rect inside{frame.x + 1, frame.y + 1, frame.width - 2, frame.height - 2};
    draw_dots(image, inside, projection, scene.dots, dot_size, alpha);
  }

  const int footer_y = height - footer + pad;
  const int bar_left =
      draw_scale_bar(image, frames[1], footer_y, plot_width, pixels_per_metre, text_scale);
  draw_legend(image, scene.legend, frames[0].x, footer_y, bar_left, text_scale);

  const std::string filename = path.string();
  if (stbi_write_png(filename.c_str(), image.width(), image.height(), 3, image.data(),
                     image.width() * 3) == 0) {
    throw IoError("cannot write PNG '" + filename + "'");
  }
}

// Dots every `spacing` metres along the polyline through the positions of `poses` (in the frame
// `to_frame` maps them into), so that the path draws as a line.
void add_path(const std::vector<Eigen::Matrix4d>& poses, const Eigen::Matrix4d& to_frame,
              const double spacing_m, const Rgb colour, Scene& scene) {
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const Eigen::Vector3d p = (to_frame * poses[k]).topRightCorner<3, 1>();
    scene.box.extend(p);
    const double length = k == 0 ? 0.0 : (p - previous).norm();
    const auto steps = static_cast<std::size_t>(std::ceil(length / spacing_m));
    for (std::size_t s = 1; s <= steps; ++s) {
      const double f = static_cast<double>(s) / static_cast<double>(steps);
      scene.dots.push_back({previous + f * (p - previous), colour});
    }
    if (k == 0) scene.dots.push_back({p, colour});
    previous = p;
  }
}

[[nodiscard]] double path_length(const std::vector<Eigen::Matrix4d>& poses) {
  double length = 0.0;
  for (std::size_t k = 1; k < poses.size(); ++k) {
    length += (poses[k].topRightCorner<3, 1>() - poses[k - 1].topRightCorner<3, 1>()).norm();
  }
  return length;
}

}  // namespace

void render_alignment_png(const std::filesystem::path& path, const PointCloud& reference,
                          const PointCloud& source, const Eigen::Matrix4d& T_reference_source,
                          const RenderSettings& settings) {
  check_render_settings(settings);
  if (reference.empty()) throw InvalidInputError("cannot render: the reference cloud is empty");
  if (source.empty()) throw InvalidInputError("cannot render: the source cloud is empty");
  if (!T_reference_source.allFinite()) {
    throw InvalidInputError("cannot render: the transform has a non-finite entry");
  }
  // The dots to draw (strided clouds) in the reference frame, and the box of all points.
  const RigidMap move_source(
      between_stored(T_reference_source, source.origin_m, reference.origin_m));
  Scene scene{{},
              {},
              {"top view x-y", "side view x-z"},
              {std::pair{kReferenceColour, std::string_view("reference")},
               std::pair{kSourceColour, std::string_view("source (aligned)")}}};
  const auto collect = [&](const PointCloud& cloud, const Rgb colour, const auto& to_reference) {
    const std::size_t stride = stride_for(cloud.size(), settings.max_points);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (!cloud.points[i].allFinite()) continue;
      const Eigen::Vector3d p = to_reference(cloud.points[i]);
      scene.box.extend(p);
      if (i % stride == 0) scene.dots.push_back({p, colour});
    }
  };
  scene.dots.reserve(std::min(reference.size(), settings.max_points) +
                     std::min(source.size(), settings.max_points));
  collect(reference, kReferenceColour,
          [](const Eigen::Vector3f& p) -> Eigen::Vector3d { return p.cast<double>(); });
  collect(source, kSourceColour, move_source);
  write_views_png(path, std::move(scene), settings);
}

void render_trajectories_png(const std::filesystem::path& path,
                             const std::vector<Eigen::Matrix4d>& estimate,
                             const std::vector<Eigen::Matrix4d>& truth,
                             const Eigen::Matrix4d& T_truth_estimate,
                             const RenderSettings& settings) {
  check_render_settings(settings);
  if (estimate.empty()) throw InvalidInputError("cannot render: the trajectory is empty");
  const auto finite = [](const std::vector<Eigen::Matrix4d>& poses) {
    return std::all_of(poses.begin(), poses.end(), [](const auto& T) { return T.allFinite(); });
  };
  if (!finite(estimate) || !finite(truth) || !T_truth_estimate.allFinite()) {
    throw InvalidInputError("cannot render: a pose has a non-finite entry");
  }
  // The longer path sets the dot spacing: max_points dots along it, at least one per ~mm.
  const double length = std::max(path_length(estimate), path_length(truth));
  const double spacing_m = std::max(length / static_cast<double>(settings.max_points), 1e-3);
  Scene scene{{},
              {},
              {"view x-y", "view x-z"},
              {std::pair{kReferenceColour, std::string_view(truth.empty() ? "" : "ground truth")},
               std::pair{kSourceColour, std::string_view("estimate")}}};
  add_path(truth, Eigen::Matrix4d::Identity(), spacing_m, kReferenceColour, scene);
  add_path(estimate, T_truth_estimate, spacing_m, kSourceColour, scene);
  write_views_png(path, std::move(scene), settings);
}

}  // namespace sgdicp
