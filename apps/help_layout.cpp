#include "help_layout.hpp"

#include <algorithm>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

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

// Edits (insertions, deletions, substitutions) from a to b: the classic two-row dynamic
// programme, for option names of a few dozen characters.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substitute = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitute});
    }
    std::swap(previous, current);
  }
  return previous[b.size()];
}

// The hint for one unknown "--name" given to `command`, or empty.
std::string hint_for(const CLI::App& command, std::string_view given) {
  const std::string_view name = given.substr(0, given.find('='));
  if (!name.starts_with("--")) return "";
  const std::string_view bare = name.substr(2);
  if (is_retired_setting(bare)) {
    return std::string(name) +
           " is no longer an option: a fixed rule of the default, or --preset paper's "
           "(docs/registration.md, What is no longer a setting)";
  }
  std::string best;
  std::size_t best_distance = 4;  // at most 3 edits
  for (const CLI::Option* option : command.get_options()) {
    for (const std::string& candidate : option->get_lnames()) {
      const std::size_t d = edit_distance(bare, candidate);
      if (d < best_distance) {
        best_distance = d;
        best = candidate;
      }
    }
  }
  return best.empty() ? "" : std::string(name) + ": did you mean --" + best + "?";
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

std::string unknown_option_hints(const CLI::App& app) {
  std::string out;
  for (const CLI::App* command : app.get_subcommands()) {
    for (const std::string& given : command->remaining()) {
      const std::string hint = hint_for(*command, given);
      if (!hint.empty()) out += (out.empty() ? "" : "\n") + hint;
    }
  }
  return out;
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
