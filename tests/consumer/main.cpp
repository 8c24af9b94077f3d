// Registers a cloud to a shifted copy of itself through the installed package (the shift is
// below half the 5 cm grid spacing, so the grid cannot alias).
#include <cstdio>

#include <sgdicp/sgdicp.hpp>

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
  std::printf("converged=%d translation error=%.3g m\n", r.converged ? 1 : 0, error);
  return r.converged && error < 0.005 ? 0 : 1;
}
