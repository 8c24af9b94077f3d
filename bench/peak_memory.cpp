// Peak memory of one registration (issue 6 target: peak memory at most twice the size of the two
// input clouds plus 50 MB). Run one process per pair, because the peak is per process:
//   sgdicp_peak_memory SOURCE REFERENCE
// Prints one JSON object with the resident set size (RSS, from /proc/self/status) at start, the
// peak while reading the files, and the peak while building the KD-tree and registering (the
// peak is reset after reading by writing 5 to /proc/self/clear_refs; "reset" says if that
// worked), plus the input sizes and the limits: 2 x input + 50 MB with the input counted as the
// in-memory clouds (12 bytes per point) and as the files on disk.
#include <sys/resource.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include <sgdicp/index/nearest_neighbor.hpp>
#include <sgdicp/io/io.hpp>
#include <sgdicp/registration/registration.hpp>

namespace {

// A "Vm...:  123 kB" field of /proc/self/status, in kB (-1 if absent).
long status_kb(const std::string& field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(field + ":", 0) == 0) return std::stol(line.substr(field.size() + 1));
  }
  return -1;
}

bool reset_peak() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.flush();
  return static_cast<bool>(out);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: sgdicp_peak_memory SOURCE REFERENCE\n";
    return 2;
  }
  try {
    const long rss_start = status_kb("VmRSS");
    sgdicp::PointCloud source = sgdicp::read_point_cloud(argv[1]).cloud;
    sgdicp::PointCloud reference = sgdicp::read_point_cloud(argv[2]).cloud;
    const long peak_read = status_kb("VmHWM");
    const long rss_after_read = status_kb("VmRSS");
    const bool reset = reset_peak();
    const std::size_t ns = source.size(), nr = reference.size();
    // As in the library's documented use: the index takes the reference cloud by move.
    const sgdicp::ReferenceIndex index(std::move(reference));
    const long rss_after_build = status_kb("VmRSS");
    const sgdicp::RegistrationResult r = sgdicp::align(source, index, sgdicp::SgdSettings{});
    const long peak_register = status_kb("VmHWM");
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);

    const double mb = 1024.0 * 1024.0;
    const double input_xyz = 12.0 * static_cast<double>(ns + nr);
    const double input_files = static_cast<double>(std::filesystem::file_size(argv[1]) +
                                                   std::filesystem::file_size(argv[2]));
    std::printf(
        "{\"source\": \"%s\", \"reference\": \"%s\", \"source_points\": %zu, "
        "\"reference_points\": %zu, \"input_xyz_mb\": %.3f, \"input_files_mb\": %.3f, "
        "\"rss_start_mb\": %.3f, \"peak_read_mb\": %.3f, \"rss_after_read_mb\": %.3f, "
        "\"rss_after_build_mb\": %.3f, \"peak_build_register_mb\": %.3f, \"peak_reset\": %s, "
        "\"ru_maxrss_mb\": %.3f, \"limit_xyz_mb\": %.3f, \"limit_files_mb\": %.3f, "
        "\"converged\": %s, \"iterations\": %zu}\n",
        argv[1], argv[2], ns, nr, input_xyz / mb, input_files / mb, rss_start / 1024.0,
        peak_read / 1024.0, rss_after_read / 1024.0, rss_after_build / 1024.0,
        peak_register / 1024.0, reset ? "true" : "false", usage.ru_maxrss / 1024.0,
        2 * input_xyz / mb + 50, 2 * input_files / mb + 50, r.converged ? "true" : "false",
        r.iterations);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
