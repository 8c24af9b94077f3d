#include "cli_common.hpp"

#include <cctype>
#include <filesystem>
#include <iostream>
#include <string_view>
#include <type_traits>
#include <utility>

#include "sgdicp/core/error.hpp"
#include "sgdicp/io/transform_io.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp::cli {
namespace {

// The options of the depth settings, to name them in the messages of validate().
constexpr std::pair<std::string_view, std::string_view> kDepthOptionOf[] = {
    {"depth_units_per_m", "--depth-scale"},
    {"max_depth_m", "--max-depth"},
    {"min_depth_m", "--min-depth"},
    {"pixel_stride", "--pixel-stride"},
    {"border_px", "--depth-border"}};

}  // namespace

void throw_naming_depth_option(const InvalidSettingsError& e) {
  std::string what = e.what();
  for (const auto& [field, option] : kDepthOptionOf) {
    if (what.starts_with(field)) what = std::string(option) + what.substr(field.size());
  }
  throw InvalidSettingsError(what);
}

namespace {

// --intrinsics as a file or four numbers; without it, camera-intrinsics.txt beside the image
// (the 7-Scenes layout), said on stderr.
PinholeIntrinsics intrinsics_for(const std::string& image, const DepthOptions& o, bool verbose) {
  std::error_code ec;
  if (o.intrinsics.empty()) {
    const std::filesystem::path beside =
        std::filesystem::path(image).parent_path() / "camera-intrinsics.txt";
    if (!std::filesystem::is_regular_file(beside, ec)) {
      throw InvalidSettingsError(image +
                                 ": a depth image needs --intrinsics FILE or fx,fy,cx,cy (and "
                                 "there is no camera-intrinsics.txt beside it)");
    }
    if (verbose) std::cerr << "note: " << image << ": intrinsics from " << beside.string() << '\n';
    return read_intrinsics(beside);
  }
  try {
    if (std::filesystem::exists(o.intrinsics, ec)) return read_intrinsics(o.intrinsics);
    return parse_intrinsics(o.intrinsics);
  } catch (const FormatError& e) {
    throw FormatError(std::string("--intrinsics: ") + e.what());
  } catch (const InvalidSettingsError& e) {
    throw InvalidSettingsError(std::string("--intrinsics: ") + e.what());
  }
}

PointCloud load_depth_image(const std::string& path, bool verbose, const DepthOptions& o) {
  naming_depth_options([&] { o.settings.validate(); });
  const PinholeIntrinsics K = intrinsics_for(path, o, verbose);
  DepthImageReport report;
  // An image too small for the border is found when read: named by its option too.
  PointCloud cloud =
      naming_depth_options([&] { return read_depth_image(path, K, o.settings, &report); });
  if (verbose) {
    std::cerr << "note: " << path << ": depth image " << report.width << " x " << report.height
              << ", " << report.valid << " of " << report.pixels << " pixels back-projected ("
              << report.invalid_zero << " without depth, " << report.invalid_range
              << " out of range)\n";
  }
  return cloud;
}

}  // namespace

void add_depth_options(CLI::App& app, DepthOptions& o) {
  const DepthImageSettings d;
  app.add_option("--intrinsics", o.intrinsics,
                 "Pinhole intrinsics of .png depth images (pixels): a 3x3 K file or fx,fy,cx,cy "
                 "[default: camera-intrinsics.txt beside the image]");
  app.add_option("--depth-scale", o.settings.depth_units_per_m,
                 "Depth units per metre of 16-bit .png depth images; 0 = the data's own: 5000 for "
                 "a TUM RGB-D sequence, else 1000 (millimetres) [default: " +
                     format_number(d.depth_units_per_m) + "]");
  app.add_option("--max-depth", o.settings.max_depth_m,
                 "Depth image pixels deeper than this are dropped, m [default: " +
                     format_number(d.max_depth_m) + "]");
  app.add_option("--min-depth", o.settings.min_depth_m,
                 "Depth image pixels shallower than this are dropped, m (depth 0 always is) "
                 "[default: " +
                     format_number(d.min_depth_m) + "]");
  app.add_option("--pixel-stride", o.settings.pixel_stride,
                 "Back-project every n-th pixel of depth images in x and y, pixels [default: " +
                     std::to_string(d.pixel_stride) + "]");
  app.add_option("--depth-border", o.settings.border_px,
                 "Drop a band this wide along each edge of depth images (a Kinect v1's depth is "
                 "off by up to ~1 cm toward its left and right edges), pixels [default: " +
                     std::to_string(d.border_px) + "]");
}

bool is_depth_image(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".png";
}

PointCloud load_cloud(const std::string& path, const std::string& role, bool verbose,
                      const DepthOptions& depth) {
  if (is_depth_image(path)) {
    PointCloud cloud = load_depth_image(path, verbose, depth);
    if (cloud.empty()) {
      throw InvalidInputError(path + ": the " + role + " depth image has no valid depth pixel");
    }
    return cloud;
  }
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

// Whether text is meant as an inline matrix rather than a file name: its first token starts
// like a number (or is nan/inf). Then parse_transform's message says what is wrong with it
// ("expected a number, got '0.0.5'"), rather than "no such transform file".
bool looks_like_numbers(const std::string& text) {
  const std::size_t first = text.find_first_not_of(" \t\r\n,;[");
  if (first == std::string::npos) return false;
  const auto digit = [&](std::size_t i) {
    return i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])) != 0;
  };
  const char c = text[first];
  if (digit(first) || c == '+' || (c == '.' && digit(first + 1)) ||
      (c == '-' && (digit(first + 1) || text.compare(first + 1, 1, ".") == 0))) {
    return true;
  }
  std::string word = text.substr(first, 3);
  for (char& w : word) w = static_cast<char>(std::tolower(static_cast<unsigned char>(w)));
  return word == "nan" || word == "inf";
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
  if (!looks_like_numbers(text)) {
    throw IoError(option + " " + text +
                  ": no such transform file (and not 12 or 16 numbers either)");
  }
  try {
    return parse_transform(text, option);
  } catch (const FormatError& e) {
    if (text.find_first_of(" \t\r\n,;") != std::string::npos) throw;
    throw FormatError(std::string(e.what()) + " (and no transform file of that name)");
  }
}

void check_picture_name(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension != ".png") {
    throw InvalidSettingsError("--picture " + path +
                               ": the picture is written as PNG, give it a .png name");
  }
}

nlohmann::json matrix_to_json(const Eigen::Matrix4d& T) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) {
    rows.push_back({T(r, 0), T(r, 1), T(r, 2), T(r, 3)});
  }
  return rows;
}

nlohmann::json pose_matrix_to_json(const Eigen::Matrix<double, 6, 6>& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 6; ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < 6; ++c) row.push_back(m(r, c));
    rows.push_back(row);
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
  if (r.uncertainty_ms > 0.0 || r.uncertainty_pairs > 0) {
    j["covariance"] = pose_matrix_to_json(r.covariance);
    j["covariance_se3"] = pose_matrix_to_json(r.covariance_se3);
    if (!r.samples.empty()) {
      j["sample_mean"] = std::vector<double>(r.sample_mean.data(), r.sample_mean.data() + 6);
      j["samples"] = r.samples.size();
    }
    if (!r.modes.empty()) {
      nlohmann::json modes = nlohmann::json::array();
      for (const PoseMode& m : r.modes) {
        modes.push_back({{"weight", m.weight},
                         {"mean", std::vector<double>(m.mean.data(), m.mean.data() + 6)},
                         {"covariance", pose_matrix_to_json(m.covariance)}});
      }
      j["modes"] = modes;
    }
  }
  return j;
}

}  // namespace sgdicp::cli
