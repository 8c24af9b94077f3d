// Tests of the surfaces (surfaces/normals.hpp): normals and covariances against brute force and
// known surfaces, thread-count independence, degenerate neighbourhoods, bad settings. The voxel
// and random downsampling are tested in test_downsampling.cpp.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "preprocessing_support.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/index/nearest_neighbor.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "surfaces/point_surfaces.hpp"
#include "test_support.hpp"

namespace {

using sgdicp::InvalidInputError;
using sgdicp::InvalidSettingsError;
using sgdicp::NeighborhoodSettings;
using sgdicp::PointCloud;
using sgdicp::test::random_box;
using sgdicp::test::uniform;

Eigen::Vector3d random_unit(std::mt19937_64& rng) {
  Eigen::Vector3d v;
  do {
    v = {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
  } while (v.norm() < 0.1 || v.norm() > 1.0);
  return v.normalized();
}

// A 2 m x 2 m patch of the plane through `centre` with unit normal `normal`, with Gaussian-like
// noise (sum of uniforms) of about sigma along the normal.
PointCloud noisy_plane(std::mt19937_64& rng, std::size_t n, const Eigen::Vector3d& centre,
                       const Eigen::Vector3d& normal, double sigma) {
  const Eigen::Vector3d u = normal.unitOrthogonal();
  const Eigen::Vector3d v = normal.cross(u);
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    double noise = 0.0;
    for (int j = 0; j < 12; ++j) noise += uniform(rng, -0.5, 0.5);
    const Eigen::Vector3d p =
        centre + uniform(rng, -1, 1) * u + uniform(rng, -1, 1) * v + sigma * noise * normal;
    c.points.push_back(p.cast<float>());
  }
  return c;
}

NeighborhoodSettings raw_settings(std::size_t k) {
  NeighborhoodSettings s;
  s.k = k;
  s.regularize = false;
  return s;
}

// ---------------------------------------------------------------- normals

TEST(Normals, NoisyPlaneGivesItsNormalFacingTheViewpoint) {
  std::mt19937_64 rng(11);
  const Eigen::Vector3d normal = random_unit(rng);
  const Eigen::Vector3d centre(4.0, -3.0, 1.5);
  PointCloud cloud = noisy_plane(rng, 3000, centre, normal, 0.002);

  for (const double side : {1.0, -1.0}) {
    NeighborhoodSettings s;
    s.viewpoint = (centre + side * 10.0 * normal).cast<float>();
    sgdicp::estimate_normals(cloud, s);
    ASSERT_EQ(cloud.normals.size(), cloud.size());
    EXPECT_TRUE(cloud.covariances.empty());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const Eigen::Vector3d n = cloud.normals[i].cast<double>();
      ASSERT_NEAR(n.norm(), 1.0, 1e-6) << i;
      EXPECT_GT(std::abs(n.dot(normal)), 0.99) << i;
      EXPECT_GE(n.dot(s.viewpoint.cast<double>() - cloud.points[i].cast<double>()), 0.0) << i;
      EXPECT_GT(side * n.dot(normal), 0.0) << i;  // faces the side the viewpoint is on
    }
  }
}

TEST(Normals, SphereNormalsAreRadial) {
  std::mt19937_64 rng(12);
  const Eigen::Vector3d centre(3.0, -2.0, 1.0);
  const double radius = 1.5;
  PointCloud cloud;
  for (int i = 0; i < 4000; ++i) {
    cloud.points.push_back((centre + radius * random_unit(rng)).cast<float>());
  }
  NeighborhoodSettings s;
  s.viewpoint = centre.cast<float>();  // inside: normals point inwards
  sgdicp::estimate_covariances(cloud, s);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d radial = (cloud.points[i].cast<double>() - centre).normalized();
    EXPECT_LT(cloud.normals[i].cast<double>().dot(radial), -0.99) << i;
  }
}

// ---------------------------------------------------------------- covariances

// The squared distance evaluated exactly as the kd-tree does (float, x then y then z).
float squared_distance(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  float sum = 0.0F;
  for (int k = 0; k < 3; ++k) {
    const float d = a[k] - b[k];
    sum += d * d;
  }
  return sum;
}

// Brute-force k nearest neighbours; nullopt-like false when the k-th and (k+1)-th distances tie
// (then the neighbourhood is not unique and the point is skipped).
bool brute_neighbors(const PointCloud& cloud, std::size_t i, std::size_t k,
                     std::vector<std::size_t>& out) {
  std::vector<std::pair<float, std::size_t>> all;
  for (std::size_t j = 0; j < cloud.size(); ++j) {
    all.emplace_back(squared_distance(cloud.points[i], cloud.points[j]), j);
  }
  std::sort(all.begin(), all.end());
  if (all.size() > k && all[k - 1].first == all[k].first) return false;
  out.clear();
  for (std::size_t j = 0; j < std::min(k, all.size()); ++j) out.push_back(all[j].second);
  return true;
}

Eigen::Matrix3d brute_covariance(const PointCloud& cloud, const std::vector<std::size_t>& idx) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto j : idx) mean += cloud.points[j].cast<double>();
  mean /= static_cast<double>(idx.size());
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  for (const auto j : idx) {
    const Eigen::Vector3d d = cloud.points[j].cast<double>() - mean;
    c += d * d.transpose();
  }
  return c / static_cast<double>(idx.size());
}

TEST(Covariances, RawEqualBruteForceOverBruteForceNeighbours) {
  std::mt19937_64 rng(13);
  // Anisotropic box away from the origin, so that a one-pass or wrong-neighbour computation
  // shows.
  PointCloud cloud = random_box(rng, 600, {10, -3, 5}, {12, -2.5, 5.8});
  for (const std::size_t k : {3UL, 10UL, 37UL}) {
    sgdicp::estimate_covariances(cloud, raw_settings(k));
    ASSERT_EQ(cloud.covariances.size(), cloud.size());
    std::size_t compared = 0;
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (!brute_neighbors(cloud, i, k, idx)) continue;
      ++compared;
      const Eigen::Matrix3d expected = brute_covariance(cloud, idx);
      const Eigen::Matrix3d got = cloud.covariances[i].cast<double>();
      ASSERT_LT((got - expected).cwiseAbs().maxCoeff(), 1e-5) << "k " << k << " point " << i;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(expected);
      EXPECT_GT(std::abs(es.eigenvectors().col(0).dot(cloud.normals[i].cast<double>())), 1.0 - 1e-4)
          << "k " << k << " point " << i;
    }
    EXPECT_GT(compared, cloud.size() - 5);
  }
}

// The surface variation lambda_0 / (lambda_0 + lambda_1 + lambda_2) of a covariance.
double surface_variation(const Eigen::Matrix3d& covariance) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(covariance);
  return es.eigenvalues()[0] / es.eigenvalues().sum();
}

TEST(FlatNeighbourhoods, FlatKWhereThoseLieFlatElseKAgainstBruteForce) {
  // A smooth sparse ellipsoid (flat neighbourhoods of 10) beside a rough slab (not flat).
  std::mt19937_64 rng(41);
  PointCloud cloud;
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d u = random_unit(rng);
    cloud.points.push_back((u.cwiseProduct(Eigen::Vector3d(0.8, 0.4, 0.2))).cast<float>());
  }
  const PointCloud slab = random_box(rng, 300, {3, 0, 0}, {4, 1, 0.3});
  cloud.points.insert(cloud.points.end(), slab.points.begin(), slab.points.end());
  NeighborhoodSettings s = raw_settings(20);
  s.flat_k = 10;
  s.flatness = 0.05;
  sgdicp::estimate_covariances(cloud, s);
  std::size_t flat = 0;
  std::size_t rough = 0;
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!brute_neighbors(cloud, i, s.flat_k, idx)) continue;
    const Eigen::Matrix3d few = brute_covariance(cloud, idx);
    const bool is_flat = surface_variation(few) <= s.flatness;
    if (!is_flat && !brute_neighbors(cloud, i, s.k, idx)) continue;
    (is_flat ? flat : rough) += 1;
    const Eigen::Matrix3d expected = is_flat ? few : brute_covariance(cloud, idx);
    ASSERT_LT((cloud.covariances[i].cast<double>() - expected).cwiseAbs().maxCoeff(), 1e-6)
        << "point " << i << (is_flat ? " (flat)" : " (rough)");
  }
  // Both rules were exercised.
  EXPECT_GT(flat, 200U);
  EXPECT_GT(rough, 200U);
  // flat_k = 0 is the plain k-nearest estimate.
  PointCloud plain = cloud;
  s.flat_k = 0;
  sgdicp::estimate_covariances(plain, s);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (brute_neighbors(plain, i, s.k, idx)) {
      ASSERT_LT((plain.covariances[i].cast<double>() - brute_covariance(plain, idx))
                    .cwiseAbs()
                    .maxCoeff(),
                1e-6);
    }
    differ += plain.covariances[i] != cloud.covariances[i] ? 1 : 0;
  }
  EXPECT_GT(differ, 200U);
}

TEST(FlatNeighbourhoods, KeepTheShapeOfASparseSmallObject) {
  // 400 points on an ellipsoid (curvature varying 16x over it), as sparse as the PCL bunny:
  // k = 20 neighbourhoods reach across its bends, flat ones of 10 do not.
  std::mt19937_64 rng(42);
  const Eigen::Vector3d axes(0.08, 0.04, 0.02);
  PointCloud cloud;
  std::vector<Eigen::Vector3d> truth;
  for (int i = 0; i < 400; ++i) {
    const Eigen::Vector3d p = random_unit(rng).cwiseProduct(axes);
    cloud.points.push_back(p.cast<float>());
    truth.push_back(p.cwiseQuotient(axes.cwiseProduct(axes)).normalized());
  }
  const auto mean_error_deg = [&](std::size_t flat_k) {
    PointCloud c = cloud;
    NeighborhoodSettings s;
    s.flat_k = flat_k;
    sgdicp::estimate_normals(c, s);
    double sum = 0.0;
    for (std::size_t i = 0; i < c.size(); ++i) {
      const double cosine = std::min(1.0, std::abs(c.normals[i].cast<double>().dot(truth[i])));
      sum += std::acos(cosine) * 180.0 / std::numbers::pi;
    }
    return sum / static_cast<double>(c.size());
  };
  const double plain = mean_error_deg(0);
  const double adaptive = mean_error_deg(10);
  EXPECT_LT(adaptive, 0.9 * plain) << "flat_k = 10: " << adaptive << " deg, k = 20: " << plain;
}

TEST(Covariances, RegularizedArePlaneModelWithRawEigenvectors) {
  std::mt19937_64 rng(14);
  PointCloud raw = noisy_plane(rng, 1500, {1, 2, 3}, random_unit(rng), 0.01);
  PointCloud box = random_box(rng, 500, {-1, -1, -1}, {1, 1, 1});
  raw.points.insert(raw.points.end(), box.points.begin(), box.points.end());
  sgdicp::estimate_covariances(raw, raw_settings(15));
  for (const double eps : {1e-3, 0.05}) {
    PointCloud reg = raw;
    NeighborhoodSettings s = raw_settings(15);
    s.regularize = true;
    s.epsilon = eps;
    sgdicp::estimate_covariances(reg, s);
    ASSERT_EQ(reg.covariances.size(), raw.size());
    EXPECT_EQ(reg.normals, raw.normals);  // regularization does not change the normals
    const Eigen::Vector3d expected_values(eps, 1.0, 1.0);
    for (std::size_t i = 0; i < raw.size(); ++i) {
      const Eigen::Matrix3d c = reg.covariances[i].cast<double>();
      ASSERT_LT((c - c.transpose()).cwiseAbs().maxCoeff(), 1e-12) << i;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> reg_es(c);
      ASSERT_LT((reg_es.eigenvalues() - expected_values).cwiseAbs().maxCoeff(), 1e-5) << i;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> raw_es(
          raw.covariances[i].cast<double>());
      for (int j = 0; j < 3; ++j) {
        const Eigen::Vector3d v = raw_es.eigenvectors().col(j);
        EXPECT_LT((c * v - expected_values[j] * v).norm(), 1e-5) << i << " eigenvector " << j;
      }
    }
  }
}

TEST(Covariances, IdenticalForAnyThreadCount) {
  std::mt19937_64 rng(15);
  PointCloud base = noisy_plane(rng, 12000, {0, 0, -1.7}, {0.1, 0.2, 0.97}, 0.03);
  const PointCloud box = random_box(rng, 8000, {-20, -20, -2}, {20, 20, 3});
  base.points.insert(base.points.end(), box.points.begin(), box.points.end());
  for (const bool regularize : {false, true}) {
    std::vector<PointCloud> results;
    for (const std::size_t threads : {1UL, 2UL, 4UL}) {
      PointCloud c = base;
      NeighborhoodSettings s;
      s.num_threads = threads;
      s.regularize = regularize;
      s.viewpoint = {0, 0, 2};
      sgdicp::estimate_covariances(c, s);
      results.push_back(std::move(c));
    }
    for (std::size_t r = 1; r < results.size(); ++r) {
      ASSERT_EQ(results[r].normals.size(), base.size());
      for (std::size_t i = 0; i < base.size(); ++i) {
        ASSERT_EQ(results[r].normals[i], results[0].normals[i]) << i;
        ASSERT_EQ(results[r].covariances[i], results[0].covariances[i]) << i;
      }
    }
  }
}

TEST(Covariances, PrebuiltIndexGivesTheSameResultAndMustMatchTheCloud) {
  std::mt19937_64 rng(16);
  PointCloud a = random_box(rng, 700, {0, 0, 0}, {1, 2, 0.3});
  PointCloud b = a;
  sgdicp::estimate_covariances(a);
  const sgdicp::ReferenceIndex index(b);
  sgdicp::estimate_covariances(b, index);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_EQ(a.covariances, b.covariances);
  PointCloud c = b;
  c.normals.clear();
  sgdicp::estimate_normals(c, index);
  EXPECT_EQ(c.normals, a.normals);

  PointCloud smaller = a;
  smaller.points.pop_back();
  EXPECT_THROW(sgdicp::estimate_covariances(smaller, index), InvalidInputError);
  PointCloud moved = a;
  moved.points[350].x() += 0.01F;
  EXPECT_THROW(sgdicp::estimate_covariances(moved, index), InvalidInputError);
  EXPECT_THROW(sgdicp::estimate_normals(moved, index), InvalidInputError);
}

TEST(Normals, EstimateNormalsLeavesCovariancesAlone) {
  std::mt19937_64 rng(17);
  PointCloud cloud = random_box(rng, 300, {0, 0, 0}, {1, 1, 0.1});
  PointCloud full = cloud;
  sgdicp::estimate_covariances(full);
  sgdicp::estimate_normals(cloud);
  EXPECT_EQ(cloud.normals, full.normals);
  EXPECT_TRUE(cloud.covariances.empty());
  // Existing covariances are kept as they were.
  cloud.covariances.assign(cloud.size(), Eigen::Matrix3f::Constant(7.0F));
  sgdicp::estimate_normals(cloud);
  EXPECT_EQ(cloud.covariances[0], Eigen::Matrix3f::Constant(7.0F));
}

void expect_finite(const PointCloud& c) {
  for (std::size_t i = 0; i < c.size(); ++i) {
    ASSERT_TRUE(c.normals[i].allFinite()) << i;
    ASSERT_TRUE(c.covariances[i].allFinite()) << i;
  }
}

TEST(Degenerate, DuplicatesAndLinesGiveFiniteMarkedOutput) {
  // Every point repeated 25 times: each 20-neighbourhood is one location repeated.
  std::mt19937_64 rng(18);
  const PointCloud plane = noisy_plane(rng, 40, {1, 2, 3}, {0, 0, 1}, 0.0);
  PointCloud duplicates;
  for (const auto& p : plane.points) duplicates.points.insert(duplicates.points.end(), 25, p);
  // 60 collinear points far from the origin, rounded to float (so only nearly collinear).
  PointCloud line;
  for (int i = 0; i < 60; ++i) {
    const double t = 0.1 * i;
    line.points.emplace_back(static_cast<float>(1000.0 + t), static_cast<float>(2000.0 + 2 * t),
                             static_cast<float>(3000.0 - t));
  }
  PointCloud one;
  one.points.emplace_back(1, 2, 3);
  PointCloud two = one;
  two.points.emplace_back(1, 2, 4);
  PointCloud same_three;
  same_three.points.assign(3, Eigen::Vector3f(0, 0, 0));

  for (const PointCloud* input : {&duplicates, &line, &one, &two, &same_three}) {
    for (const bool regularize : {false, true}) {
      PointCloud c = *input;
      NeighborhoodSettings s;
      s.regularize = regularize;
      sgdicp::estimate_covariances(c, s);
      ASSERT_EQ(c.normals.size(), c.size());
      expect_finite(c);
      for (std::size_t i = 0; i < c.size(); ++i) {
        EXPECT_TRUE(c.normals[i].isZero()) << i << ": " << c.normals[i].transpose();
        if (regularize) {
          EXPECT_EQ(c.covariances[i], Eigen::Matrix3f::Identity()) << i;
        }
      }
    }
  }
  // Raw covariances of a duplicate cluster are exactly zero; of a line, rank one.
  PointCloud c = duplicates;
  sgdicp::estimate_covariances(c, raw_settings(20));
  EXPECT_EQ(c.covariances[0], Eigen::Matrix3f::Zero());
}

TEST(Degenerate, PlaneWithSomeDuplicatesStillHasNormals) {
  std::mt19937_64 rng(19);
  PointCloud cloud = noisy_plane(rng, 2000, {0, 0, 0}, {0, 0, 1}, 0.0);
  for (std::size_t i = 0; i < 200; ++i) cloud.points.push_back(cloud.points[i]);
  NeighborhoodSettings s;
  s.viewpoint = {0, 0, 5};
  sgdicp::estimate_covariances(cloud, s);
  expect_finite(cloud);
  for (const auto& n : cloud.normals) EXPECT_GT(n.z(), 0.99F);
}

TEST(Settings, BadSettingsAndInputThrowAndLeaveTheCloudUnchanged) {
  std::mt19937_64 rng(20);
  const PointCloud cloud = random_box(rng, 50, {0, 0, 0}, {1, 1, 1});
  const auto expect_settings_error = [&](const NeighborhoodSettings& s) {
    PointCloud c = cloud;
    EXPECT_THROW(sgdicp::estimate_covariances(c, s), InvalidSettingsError);
    EXPECT_THROW(sgdicp::estimate_normals(c, s), InvalidSettingsError);
    EXPECT_TRUE(c.normals.empty());
    EXPECT_TRUE(c.covariances.empty());
  };
  NeighborhoodSettings s;
  s.k = 2;
  expect_settings_error(s);
  s.k = 1001;
  expect_settings_error(s);
  s = {};
  for (const double eps : {0.0, -1e-3, 1.5, std::nan(""), HUGE_VAL}) {
    s.epsilon = eps;
    expect_settings_error(s);
  }
  s = {};
  s.num_threads = 1025;
  expect_settings_error(s);
  s = {};
  s.viewpoint.x() = std::nanf("");
  expect_settings_error(s);
  s = {};
  for (const std::size_t flat_k : {1UL, 2UL, 1001UL}) {
    s.flat_k = flat_k;
    expect_settings_error(s);
  }
  s = {};
  for (const double flatness : {-1e-9, 0.34, std::nan(""), HUGE_VAL}) {
    s.flatness = flatness;
    expect_settings_error(s);
  }
  // Edges of the valid ranges are accepted.
  for (const std::size_t k : {3UL, 1000UL}) {
    PointCloud c = cloud;
    s = {};
    s.k = k;
    s.num_threads = 1024;
    s.epsilon = 1.0;
    s.flat_k = k;
    s.flatness = 1.0 / 3.0;
    EXPECT_NO_THROW(sgdicp::estimate_covariances(c, s));
  }

  PointCloud empty;
  EXPECT_THROW(sgdicp::estimate_covariances(empty), InvalidInputError);
  EXPECT_THROW(sgdicp::estimate_normals(empty), InvalidInputError);
  PointCloud bad = cloud;
  bad.points[7].y() = std::numeric_limits<float>::infinity();
  EXPECT_THROW(sgdicp::estimate_covariances(bad), InvalidInputError);
  bad.points[7].y() = std::nanf("");
  EXPECT_THROW(sgdicp::estimate_normals(bad), InvalidInputError);
  EXPECT_TRUE(bad.normals.empty());
}

// The surfaces of a subset are those the whole cloud's estimate gives its points (the odometry
// estimates them only for the points its map admits).
TEST(SubsetWithSurfaces, EqualTheWholeCloudsEstimateAtThosePoints) {
  std::mt19937_64 rng(12);
  const PointCloud cloud =
      random_box(rng, 3000, Eigen::Vector3d::Zero(), Eigen::Vector3d(2, 2, 0.2));
  NeighborhoodSettings settings;
  settings.flat_k = 10;
  PointCloud whole = cloud;
  sgdicp::estimate_covariances(whole, settings);
  const std::vector<std::uint32_t> which{2999, 0, 17, 17, 1500};
  for (const bool covariances : {false, true}) {
    const PointCloud subset = sgdicp::subset_with_surfaces(cloud, which, settings, covariances);
    ASSERT_EQ(subset.size(), which.size());
    EXPECT_EQ(subset.has_covariances(), covariances);
    for (std::size_t j = 0; j < which.size(); ++j) {
      EXPECT_EQ(subset.points[j], cloud.points[which[j]]);
      EXPECT_EQ(subset.normals[j], whole.normals[which[j]]) << j;
      if (covariances) {
        EXPECT_EQ(subset.covariances[j], whole.covariances[which[j]]) << j;
      }
    }
  }
  EXPECT_TRUE(sgdicp::subset_with_surfaces(cloud, {}, settings, false).empty());
  EXPECT_THROW((void)sgdicp::subset_with_surfaces(cloud, {3000}, settings, false),
               InvalidInputError);
  settings.k = 0;
  EXPECT_THROW((void)sgdicp::subset_with_surfaces(cloud, {1}, settings, false),
               InvalidSettingsError);
}

}  // namespace
