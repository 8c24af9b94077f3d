#pragma once
// What --help and --help-all show: a command's --help lists the options a user of it sets (at
// most 15, one line each); --help-all lists every option, grouped by the part of the library
// that reads it (docs/cli.md).
#include <span>
#include <string_view>

#include <CLI/CLI.hpp>

namespace sgdicp::cli {

/// Whether this run asked for --help-all (main sets it before parsing).
bool& help_all_requested();

/// The arguments with --help-all turned into --help, and help_all_requested() set when one was.
void take_help_all(int argc, char** argv);

/// An option that --help shows (its long name without "--"), and its help there in one line: empty
/// for the option's own help, else a brief one, which gets the option's "[default: ...]".
struct CommonOption {
  std::string_view name;
  std::string_view brief;
};

/// The briefs of the options that several commands show.
inline constexpr CommonOption kMethodBrief{
    "method", "sgd (default), sgd-point, sgd-plane, sgd-gicp; batch: icp, icp-plane, gicp"};
inline constexpr CommonOption kPresetBrief{"preset", "default, or paper: the paper's settings"};
inline constexpr CommonOption kGridBrief{
    "voxel-size", "Thin both clouds on voxels of this side, m; 0 = ~20k points, from the data"};
inline constexpr CommonOption kMaxDistanceBrief{"max-distance",
                                                "Correspondence distance d_max, scaled or m"};
inline constexpr CommonOption kIntrinsicsBrief{
    "intrinsics", "Pinhole intrinsics of .png depth images: a 3x3 K file or fx,fy,cx,cy"};

/// Lays out `command`'s help: with --help, the options in `common` under "Options" and the others
/// hidden; with --help-all, every option with its whole help, in the group of the part that reads
/// it. Adds --help-all.
void arrange_help(CLI::App& command, std::span<const CommonOption> common);

}  // namespace sgdicp::cli
