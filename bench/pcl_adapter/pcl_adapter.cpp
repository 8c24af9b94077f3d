// PCL peer for bench/compare_peers.py: registers clouds with PCL's ICP variants and reports the
// time of search-structure build + normals/covariances + registration (file I/O excluded).
//
// A line protocol on stdin/stdout so that the clouds are read once per run:
//   load NAME FILE.f32            -> "ok POINTS"          (headerless float32 x y z, 12 B/point)
//   run METHOD SRC REF MAXDIST MAXITER
//                                 -> "ok WALL_MS CPU_MS ITERATIONS CONVERGED FITNESS T00 ... T33"
//   quit
// METHOD: icp (point-to-point), icp_plane (point-to-plane, target normals from 30 neighbours
// estimated inside the timed region), gicp (generalised ICP, covariances inside the timed region).
// Any failure answers "err MESSAGE" on that line; the process keeps running.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <map>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include <pcl/features/normal_3d.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>
#include <pcl/registration/icp.h>
#include <pcl/search/kdtree.h>

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using NormalCloud = pcl::PointCloud<pcl::PointNormal>;

// nr_iterations_ is protected in PCL 1.13 and has no getter.
template <class Base>
struct WithIterations : Base {
  [[nodiscard]] int iterations() const { return this->nr_iterations_; }
};

Cloud::Ptr read_f32(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw std::runtime_error("cannot open " + path);
  const auto bytes = static_cast<std::size_t>(in.tellg());
  if (bytes % 12 != 0) throw std::runtime_error(path + ": size is not a multiple of 12 bytes");
  in.seekg(0);
  std::vector<float> xyz(bytes / 4);
  in.read(reinterpret_cast<char*>(xyz.data()), static_cast<std::streamsize>(bytes));
  auto cloud = std::make_shared<Cloud>();
  cloud->resize(bytes / 12);
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    (*cloud)[i].x = xyz[3 * i];
    (*cloud)[i].y = xyz[3 * i + 1];
    (*cloud)[i].z = xyz[3 * i + 2];
  }
  return cloud;
}

// small_gicp's default convergence test (1 mm, 0.1 deg) so that PCL stops like the others; PCL's
// own default (epsilon 0) never stops before the iteration limit.
template <class Reg>
void configure(Reg& reg, double max_distance, int max_iterations) {
  reg.setMaxCorrespondenceDistance(max_distance);
  reg.setMaximumIterations(max_iterations);
  reg.setTransformationEpsilon(1e-3 * 1e-3);  // squared translation, m^2
  reg.setTransformationRotationEpsilon(
      std::cos(0.1 * std::numbers::pi / 180));  // cosine of the angle
}

struct Outcome {
  Eigen::Matrix4f T = Eigen::Matrix4f::Identity();
  int iterations = 0;
  bool converged = false;
  double fitness = 0.0;
};

Outcome run(const std::string& method, const Cloud::Ptr& source, const Cloud::Ptr& target,
            double max_distance, int max_iterations) {
  Outcome o;
  if (method == "icp") {
    WithIterations<pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ>> icp;
    configure(icp, max_distance, max_iterations);
    icp.setInputSource(source);
    icp.setInputTarget(target);  // the kd-tree is built in align()
    Cloud aligned;
    icp.align(aligned);
    o = {icp.getFinalTransformation(), icp.iterations(), icp.hasConverged(), icp.getFitnessScore()};
  } else if (method == "icp_plane") {
    pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
    ne.setInputCloud(target);
    ne.setSearchMethod(std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
    ne.setKSearch(30);
    pcl::PointCloud<pcl::Normal> normals;
    ne.compute(normals);
    auto tgt = std::make_shared<NormalCloud>();
    pcl::concatenateFields(*target, normals, *tgt);
    auto src = std::make_shared<NormalCloud>();
    pcl::copyPointCloud(*source, *src);
    WithIterations<pcl::IterativeClosestPointWithNormals<pcl::PointNormal, pcl::PointNormal>> icp;
    configure(icp, max_distance, max_iterations);
    icp.setInputSource(src);
    icp.setInputTarget(tgt);
    NormalCloud aligned;
    icp.align(aligned);
    o = {icp.getFinalTransformation(), icp.iterations(), icp.hasConverged(), icp.getFitnessScore()};
  } else if (method == "gicp") {
    WithIterations<pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ>> gicp;
    configure(gicp, max_distance, max_iterations);
    gicp.setInputSource(source);
    gicp.setInputTarget(target);
    Cloud aligned;
    gicp.align(aligned);
    o = {gicp.getFinalTransformation(), gicp.iterations(), gicp.hasConverged(),
         gicp.getFitnessScore()};
  } else {
    throw std::runtime_error("unknown method " + method + " (icp, icp_plane, gicp)");
  }
  return o;
}

}  // namespace

int main() {
  std::map<std::string, Cloud::Ptr> clouds;
  std::string line;
  while (std::getline(std::cin, line)) {
    std::istringstream in(line);
    std::string cmd;
    in >> cmd;
    try {
      if (cmd == "quit") break;
      if (cmd == "load") {
        std::string name, path;
        in >> name >> path;
        clouds[name] = read_f32(path);
        std::cout << "ok " << clouds[name]->size() << std::endl;
      } else if (cmd == "run") {
        std::string method, src, ref;
        double max_distance = 0;
        int max_iterations = 0;
        in >> method >> src >> ref >> max_distance >> max_iterations;
        if (!in || !clouds.count(src) || !clouds.count(ref))
          throw std::runtime_error("bad run line");
        const auto wall0 = std::chrono::steady_clock::now();
        const std::clock_t cpu0 = std::clock();
        const Outcome o = run(method, clouds[src], clouds[ref], max_distance, max_iterations);
        const double cpu_ms = 1e3 * static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
        const double wall_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall0)
                .count();
        std::ostringstream out;
        out.precision(17);
        out << "ok " << wall_ms << ' ' << cpu_ms << ' ' << o.iterations << ' '
            << (o.converged ? 1 : 0) << ' ' << o.fitness;
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 4; ++c) out << ' ' << o.T(r, c);
        std::cout << out.str() << std::endl;
      } else if (!cmd.empty()) {
        throw std::runtime_error("unknown command " + cmd);
      }
    } catch (const std::exception& e) {
      std::string msg = e.what();
      for (char& c : msg)
        if (c == '\n') c = ' ';
      std::cout << "err " << msg << std::endl;
    }
  }
  return 0;
}
