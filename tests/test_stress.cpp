// Load and soak: one ReferenceIndex shared by 8 threads gives each registration the result of a
// sequential run, and 10 000 registrations in one process do not grow its memory.
#include <cstddef>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "sgdicp/io/io.hpp"
#include "sgdicp/points/random_downsample.hpp"
#include "sgdicp/registration/batch_icp.hpp"
#include "sgdicp/registration/methods.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"
#include "sgdicp/tools/pairs.hpp"
#include "test_support.hpp"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SGDICP_TEST_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define SGDICP_TEST_SANITIZED 1
#endif
#endif

namespace sgdicp {
namespace {

// Sanitized builds run 10-50x slower: there the load and soak tests run a fifth and a tenth of
// their work (scripts/sanitize.sh), enough for the race and leak checkers to see every path.
#ifdef SGDICP_TEST_SANITIZED
constexpr std::size_t kLoadJobs = 20, kSoakRuns = 1000;
#else
constexpr std::size_t kLoadJobs = 100, kSoakRuns = 10000;
#endif

using test::make_transform;
using test::synthetic_scene;

// The points of a cloud moved by T (the clouds here have no normals or covariances).
PointCloud moved(PointCloud cloud, const Eigen::Matrix4d& T) {
  const Eigen::Matrix4f t = T.cast<float>();
  for (auto& p : cloud.points) p = t.topLeftCorner<3, 3>() * p + t.topRightCorner<3, 1>();
  return cloud;
}

// One registration of the load test: a method, a source and an initial pose.
struct Job {
  std::size_t source = 0;
  Solver solver = Solver::sgd;
  CostType cost = CostType::point_to_point;
  std::uint64_t seed = 0;
  Eigen::Matrix4d T_init = Eigen::Matrix4d::Identity();
};

RegistrationResult run(const Job& job, const std::vector<PointCloud>& sources,
                       const ReferenceIndex& index) {
  if (job.solver == Solver::sgd) {
    SgdSettings s;
    s.cost = job.cost;
    s.sampling.seed = job.seed;
    return align(sources[job.source], index, s, job.T_init);
  }
  BatchSettings b;
  b.cost = job.cost;
  return align_batch(sources[job.source], index, b, job.T_init);
}

// Every field but the wall time.
void expect_same(const RegistrationResult& a, const RegistrationResult& b, std::size_t job) {
  EXPECT_EQ(a.T_reference_source, b.T_reference_source) << "job " << job;
  EXPECT_EQ(a.stop_reason, b.stop_reason) << "job " << job;
  EXPECT_EQ(a.iterations, b.iterations) << "job " << job;
  EXPECT_EQ(a.inliers, b.inliers) << "job " << job;
  EXPECT_EQ(a.inlier_rmse_m, b.inlier_rmse_m) << "job " << job;
  EXPECT_EQ(a.constraint_ratio, b.constraint_ratio) << "job " << job;
  EXPECT_EQ(a.message, b.message) << "job " << job;
}

// Mixes both solvers and the three costs (normals and covariances read from the shared index),
// five sources and random initial poses within ~0.1 m and ~3 deg.
std::vector<Job> load_jobs(std::size_t count, std::size_t sources) {
  constexpr std::array<std::pair<Solver, CostType>, 4> kinds{{
      {Solver::sgd, CostType::point_to_point},
      {Solver::sgd, CostType::point_to_plane},
      {Solver::batch, CostType::point_to_point},
      {Solver::batch, CostType::plane_to_plane},
  }};
  std::mt19937_64 rng(11);
  std::vector<Job> jobs(count);
  for (std::size_t i = 0; i < count; ++i) {
    const auto u = [&] { return test::uniform(rng, -1.0, 1.0); };
    jobs[i] = {i % sources, kinds[i % kinds.size()].first, kinds[i % kinds.size()].second, 100 + i,
               make_transform(0.05 * u(), 0.05 * u(), 0.05 * u(),
                              Eigen::Vector3d(0.1 * u(), 0.1 * u(), 0.1 * u()))};
  }
  return jobs;
}

TEST(Load, EightThreadsOnOneIndexGiveTheSequentialResults) {
  constexpr std::size_t kThreads = 8, kJobs = kLoadJobs;
  PointCloud reference = synthetic_scene(1, 4000);
  ReferenceIndex index(reference);
  prepare_reference(index, CostType::point_to_plane);
  prepare_reference(index, CostType::plane_to_plane);
  std::vector<PointCloud> sources;
  for (std::uint64_t s = 0; s < 5; ++s) {
    sources.push_back(moved(synthetic_scene(20 + s, 1000),
                            make_transform(0.01, -0.02, 0.03, {0.05, -0.04, 0.02})));
  }
  const std::vector<Job> jobs = load_jobs(kJobs, sources.size());
  std::vector<RegistrationResult> sequential;
  for (const Job& job : jobs) sequential.push_back(run(job, sources, index));

  // Each thread runs every job, starting at its own offset so that different jobs overlap.
  std::vector<std::vector<RegistrationResult>> parallel(kThreads,
                                                        std::vector<RegistrationResult>(kJobs));
  std::vector<std::exception_ptr> errors(kThreads);
  {
    std::vector<std::jthread> threads;
    for (std::size_t t = 0; t < kThreads; ++t) {
      threads.emplace_back([&, t] {
        try {
          for (std::size_t k = 0; k < kJobs; ++k) {
            const std::size_t j = (k + t * kJobs / kThreads) % kJobs;
            parallel[t][j] = run(jobs[j], sources, index);
          }
        } catch (...) {
          errors[t] = std::current_exception();
        }
      });
    }
  }
  for (const auto& e : errors) ASSERT_FALSE(e);
  std::size_t converged = 0;
  for (std::size_t t = 0; t < kThreads; ++t) {
    for (std::size_t j = 0; j < kJobs; ++j) expect_same(parallel[t][j], sequential[j], j);
  }
  for (const auto& r : sequential) converged += r.converged ? 1 : 0;
  EXPECT_GE(converged, kJobs * 9 / 10);  // the results compared are real registrations
}

// Resident set size in bytes (/proc/self/statm, second field, in pages).
std::size_t resident_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  unsigned long size = 0, resident = 0;  // NOLINT(google-runtime-int): fscanf's %lu
  const int read = std::fscanf(f, "%lu %lu", &size, &resident);
  std::fclose(f);
  return read == 2 ? resident * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE)) : 0;
}

// Runs `count` registrations of small clouds through each solver, discarding the results.
void soak(std::size_t count, const std::vector<PointCloud>& sources, const ReferenceIndex& index) {
  SgdSettings sgd;
  sgd.sampling.batch_size = 32;
  sgd.max_iterations = 80;
  BatchSettings batch;
  batch.max_iterations = 20;
  for (std::size_t i = 0; i < count; ++i) {
    const PointCloud& source = sources[i % sources.size()];
    sgd.sampling.seed = i;
    const RegistrationResult r =
        i % 2 == 0 ? align(source, index, sgd) : align_batch(source, index, batch);
    ASSERT_TRUE(r.T_reference_source.allFinite()) << i;
  }
}

// 10 000 registrations after a warm-up of 1 000: the resident set may grow by less than 1 MiB,
// which a leak of 100 bytes per registration would exceed. Under ASan and TSan the allocator
// keeps freed memory in quarantine, so there the leak checker judges instead of this bound.
TEST(Soak, TenThousandRegistrationsKeepMemoryBounded) {
  const ReferenceIndex index(synthetic_scene(3, 1000));
  std::vector<PointCloud> sources;
  for (std::uint64_t s = 0; s < 4; ++s) {
    sources.push_back(
        moved(synthetic_scene(30 + s, 200), make_transform(0.01, 0.0, -0.02, {0.03, 0, 0})));
  }
  soak(kSoakRuns / 10, sources, index);
  const std::size_t before = resident_bytes();
  ASSERT_GT(before, 0U) << "cannot read /proc/self/statm";
  soak(kSoakRuns, sources, index);
  const std::size_t after = resident_bytes();
  const std::size_t growth = after > before ? after - before : 0;
  RecordProperty("rss_growth_bytes", std::to_string(growth));
  std::printf("resident set: %zu -> %zu bytes after %zu registrations\n", before, after, kSoakRuns);
#ifdef SGDICP_TEST_SANITIZED
  GTEST_SKIP() << "resident set grew by " << growth << " bytes (not bounded under a sanitizer)";
#else
  EXPECT_LT(growth, std::size_t{1} << 20) << before << " -> " << after << " bytes";
#endif
}

// The real case: 8 threads register the KITTI pairs of ../shared/data against shared indexes.
TEST(Load, KittiPairsFromEightThreadsGiveTheSequentialResults) {
  const auto file = std::filesystem::path(SGDICP_SHARED_DATA) / "pairs/kitti_seq00.txt";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "missing " << file;
  const RegistrationPair pair = read_pairs_file(file).front();
  const std::vector<PointCloud> sources{
      random_downsample_ratio(read_point_cloud(pair.source).cloud, 0.2, 5)};
  const ReferenceIndex index(read_point_cloud(pair.reference).cloud);
  std::vector<Job> jobs;
  for (std::uint64_t seed = 0; seed < 8; ++seed) {
    jobs.push_back({0, Solver::sgd, CostType::point_to_point, seed, pair.T_reference_source_gt});
  }
  std::vector<RegistrationResult> sequential;
  for (const Job& job : jobs) sequential.push_back(run(job, sources, index));
  std::vector<RegistrationResult> parallel(jobs.size());
  {
    std::vector<std::jthread> threads;
    for (std::size_t t = 0; t < jobs.size(); ++t) {
      threads.emplace_back([&, t] { parallel[t] = run(jobs[t], sources, index); });
    }
  }
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    expect_same(parallel[j], sequential[j], j);
    EXPECT_TRUE(sequential[j].converged) << sequential[j].message;
  }
}

}  // namespace
}  // namespace sgdicp
