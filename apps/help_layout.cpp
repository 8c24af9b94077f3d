#include "help_layout.hpp"

#include <algorithm>
#include <cstring>
#include <string>

#include "sgdicp/odometry/odometry.hpp"
#include "sgdicp/registration/settings.hpp"

namespace sgdicp::cli {
namespace {

// The option's first long name without "--" (--output for -o,--output).
std::string long_name(const CLI::Option& option) {
  const auto& names = option.get_lnames();
  return names.empty() ? std::string() : names.front();
}

// The group of an option in --help-all: a registration setting by its part of the table, an
// odometry setting (in the odometry command), the --global-* and the depth-image options in
// their own, any other one (files in and out) among the command's options.
std::string group_of(const CLI::Option& option, bool odometry) {
  const std::string name = long_name(option);
  if (odometry) {  // its --voxel-size is the map's, not a registration's grid
    for (const auto& s : odometry_settings_table()) {
      if (s.name == name) return "Odometry";
    }
  }
  if (const auto* s = find_sgd_setting(name)) return std::string(setting_part(s->field));
  if (name.rfind("global-", 0) == 0)
    return "Global registration (with --init global; docs/global.md)";
  if (name.find("depth") != std::string::npos || name == "intrinsics" || name == "pixel-stride") {
    return "Depth images (docs/depth.md)";
  }
  return "Options";
}

// The brief help of `brief` with the default of the option's whole help.
std::string brief_help(std::string_view brief, const std::string& help) {
  const auto at = help.rfind(" [default:");
  return std::string(brief) + (at == std::string::npos ? std::string() : help.substr(at));
}

const CommonOption* find_common(const CLI::Option& option, std::span<const CommonOption> common) {
  const std::string name = long_name(option);
  const auto it = std::find_if(common.begin(), common.end(),
                               [&](const CommonOption& c) { return c.name == name; });
  return it == common.end() ? nullptr : &*it;
}

}  // namespace

bool& help_all_requested() {
  static bool requested = false;
  return requested;
}

void take_help_all(int argc, char** argv) {
  static char help[] = "--help";
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--help-all") == 0) {
      help_all_requested() = true;
      argv[i] = help;
    }
  }
}

void arrange_help(CLI::App& command, std::span<const CommonOption> common) {
  const bool all = help_all_requested();
  for (CLI::Option* option : command.get_options()) {
    if (option == command.get_help_ptr() || !option->nonpositional()) continue;
    const CommonOption* shown = find_common(*option, common);
    if (all) {
      option->group(group_of(*option, command.get_name() == "odometry"));
    } else if (shown != nullptr) {
      option->group("Options");
      if (!shown->brief.empty()) {
        option->description(brief_help(shown->brief, option->get_description()));
      }
    } else {
      option->group("");
    }
  }
  const std::string name = "--help-all";
  const std::string description = "Print every option, grouped by the part that reads it, and exit";
  command.add_flag(name, description)->group("Options");
}

}  // namespace sgdicp::cli
