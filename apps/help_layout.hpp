#pragma once
// What --help and --help-all show: a command's --help lists the options a user of it sets (at
// most 15, one line each); --help-all lists every option, grouped by the part of the library
// that reads it (docs/cli.md).
#include <span>
#include <string>
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
// Of the commands over a folder of frames (odometry, localize).
inline constexpr CommonOption kGroundTruthBrief{
    "ground-truth", "Reference poses (KITTI, TUM, a 7-Scenes folder): prints RPE, ATE, drift"};
inline constexpr CommonOption kReportBrief{
    "report", "Write one CSV row per frame (start, time, inliers, failure)"};
inline constexpr CommonOption kCovariancesBrief{
    "covariances-out", "Write each frame's 6x6 covariance (with --uncertainty)"};
inline constexpr CommonOption kMaxRangeBrief{"max-range",
                                             "Points farther from the sensor are dropped, m"};
inline constexpr CommonOption kThreadsBrief{"threads",
                                            "Threads of each frame's registration, 0 = every core"};
inline constexpr CommonOption kUncertaintyBrief{
    "uncertainty", "Each frame's covariance: none, laplace, sgld, svgd"};

/// What an unknown option given to `app`'s subcommand may have meant, one line per option: a
/// setting of an earlier release that is none now, or the command's nearest long option (at most
/// 3 edits away); empty when there is no such option or no guess.
std::string unknown_option_hints(const CLI::App& app);

/// Lays out `command`'s help: with --help, the options in `common` under "Options" and the others
/// hidden; with --help-all, every option with its whole help, in the group of the part that reads
/// it. Adds --help-all.
void arrange_help(CLI::App& command, std::span<const CommonOption> common);

}  // namespace sgdicp::cli
