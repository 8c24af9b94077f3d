// A 10-million-point cloud end to end: make it (a KITTI scan repeated with jitter, or a synthetic
// scene without one), write it, read it back, index it and register a subsampled moved copy.
//   sgdicp_large_cloud [POINTS [SCAN.bin [OUT.ply]]]   (defaults: 10000000, none, /tmp)
// Prints the wall time of each stage and the peak resident set so far (getrusage ru_maxrss),
// and the error of the registration against the known motion.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <random>
#include <string>

#include <sgdicp/core/pose.hpp>
#include <sgdicp/index/nearest_neighbor.hpp>
#include <sgdicp/io/io.hpp>
#include <sgdicp/metrics/metrics.hpp>
#include <sgdicp/points/random_downsample.hpp>
#include <sgdicp/registration/registration.hpp>

namespace {

using Clock = std::chrono::steady_clock;

rusage usage_now() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage;
}

double cpu_s(const rusage& u) {
  const auto s = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * t.tv_usec; };
  return s(u.ru_utime) + s(u.ru_stime);
}

// The start of a stage: wall clock and CPU time (the CPU time does not depend on the load of a
// shared machine, the wall time does).
struct Stage {
  Clock::time_point wall = Clock::now();
  double cpu = cpu_s(usage_now());
};

// Prints one stage: its wall and CPU time and the peak resident set so far.
void report(const char* stage, const Stage& start) {
  const rusage now = usage_now();
  const double wall = std::chrono::duration<double>(Clock::now() - start.wall).count();
  std::printf("%-10s %8.2f s wall %8.2f s CPU   peak RSS %5.0f MB\n", stage, wall,
              cpu_s(now) - start.cpu, static_cast<double>(now.ru_maxrss) / 1024.0);
  std::fflush(stdout);
}

// Floor and two walls of 40 m x 30 m x 5 m with a few boxes: a fallback without real data.
sgdicp::PointCloud synthetic_seed(std::size_t n) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> u(0.0F, 1.0F);
  sgdicp::PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const float a = u(rng), b = u(rng);
    switch (i % 4) {
      case 0:
        cloud.points.emplace_back(40.0F * a, 30.0F * b, 0.0F);
        break;
      case 1:
        cloud.points.emplace_back(40.0F * a, 0.0F, 5.0F * b);
        break;
      case 2:
        cloud.points.emplace_back(0.0F, 30.0F * a, 5.0F * b);
        break;
      default:
        cloud.points.emplace_back(10.0F + 2.0F * static_cast<float>(i % 7) + a, 8.0F + 3.0F * b,
                                  1.5F);
    }
  }
  return cloud;
}

// `points` points: copies of the seed cloud, each point moved by up to +-2 cm of jitter, so
// that the copies interleave into one denser scene.
sgdicp::PointCloud repeated(const sgdicp::PointCloud& seed, std::size_t points) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> jitter(-0.02F, 0.02F);
  sgdicp::PointCloud cloud;
  cloud.points.reserve(points);
  for (std::size_t i = 0; i < points; ++i) {
    const Eigen::Vector3f& p = seed.points[i % seed.size()];
    cloud.points.push_back(p + Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng)));
  }
  return cloud;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::size_t points = argc > 1 ? std::stoull(argv[1]) : 10'000'000;
    const std::filesystem::path scan = argc > 2 ? argv[2] : "";
    const std::filesystem::path out =
        argc > 3 ? std::filesystem::path(argv[3])
                 : std::filesystem::temp_directory_path() / "sgdicp_large_cloud.ply";
    Stage start;
    {
      const sgdicp::PointCloud seed =
          scan.empty() ? synthetic_seed(100'000) : sgdicp::read_point_cloud(scan).cloud;
      const sgdicp::PointCloud cloud = repeated(seed, points);
      std::printf("%zu points from %s\n", cloud.size(),
                  scan.empty() ? "a synthetic scene" : scan.c_str());
      report("make", start);
      start = Stage{};
      sgdicp::write_point_cloud(out, cloud);
      std::printf("%s: %.0f MB\n", out.c_str(),
                  static_cast<double>(std::filesystem::file_size(out)) / 1e6);
      report("write", start);
    }
    start = Stage{};
    sgdicp::PointCloud reference = sgdicp::read_point_cloud(out).cloud;
    report("read", start);
    // The source: 100 000 points of the cloud moved by a known motion (0.5 m, 3 deg).
    const Eigen::Matrix4d T_reference_source = sgdicp::transform_from_pose(
        (sgdicp::PoseVector() << 0.4, -0.3, 0.1, 0.01, -0.02, 0.05).finished());
    sgdicp::PointCloud source = sgdicp::random_downsample(reference, 100'000, 3);
    const Eigen::Matrix4f T_source_reference = T_reference_source.inverse().cast<float>();
    for (auto& p : source.points) {
      p = T_source_reference.topLeftCorner<3, 3>() * p + T_source_reference.topRightCorner<3, 1>();
    }
    start = Stage{};
    const sgdicp::ReferenceIndex index(std::move(reference));
    report("index", start);
    start = Stage{};
    const sgdicp::RegistrationResult r = sgdicp::align(source, index);
    report("register", start);
    std::printf("%s after %zu iterations: %.3f mm, %.4f deg off\n",
                r.converged ? "converged" : "not converged", r.iterations,
                1000.0 * sgdicp::translation_error(r.T_reference_source, T_reference_source),
                sgdicp::rotation_error_geodesic(r.T_reference_source, T_reference_source) * 180.0 /
                    3.141592653589793);
    std::filesystem::remove(out);
    return r.converged ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sgdicp_large_cloud: %s\n", e.what());
    return 1;
  }
}
