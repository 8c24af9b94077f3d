// Registers a cloud to a shifted copy of itself through the installed package (the shift is
// below half the 5 cm grid spacing, so the grid cannot alias).
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <sgdicp/sgdicp.hpp>
#include <sgdicp/tools/pairs.hpp>
#include <sgdicp/version.hpp>

// sgdicp::tools links too: a pairs file written here reads back.
bool pairs_file_reads_back() {
  const auto path = std::filesystem::temp_directory_path() / "sgdicp_consumer_pairs.txt";
  std::ofstream(path) << "a.ply b.ply 1 0 0 0.5 0 1 0 0 0 0 1 0\n";
  const auto pairs = sgdicp::read_pairs_file(path);
  std::filesystem::remove(path);
  return pairs.size() == 1 && pairs[0].T_reference_source_gt(0, 3) == 0.5;
}

int main() {
  sgdicp::PointCloud source;
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 40; ++j) {
      const float x = 0.05F * static_cast<float>(i), y = 0.05F * static_cast<float>(j);
      source.points.emplace_back(x, y, 0.3F * x * x - 0.2F * y * y + 0.1F * x * y);
    }
  }
  sgdicp::PointCloud reference = source;
  for (auto& p : reference.points) p += Eigen::Vector3f(0.012F, -0.009F, 0.006F);
  const sgdicp::RegistrationResult r = sgdicp::align(source, reference);
  const double error =
      (r.T_reference_source.topRightCorner<3, 1>() - Eigen::Vector3d(0.012, -0.009, 0.006)).norm();
  std::printf("sgdicp %s: converged=%d translation error=%.3g m\n", sgdicp::kVersion,
              r.converged ? 1 : 0, error);
  return r.converged && error < 0.005 && pairs_file_reads_back() ? 0 : 1;
}
