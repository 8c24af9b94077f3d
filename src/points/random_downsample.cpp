#include "sgdicp/points/random_downsample.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/format_number.hpp"

namespace sgdicp {
namespace {

// Uniform integer in [0, bound): reject the top partial block so that the modulo is unbiased
// (same scheme as EpochSampler, independent of the standard library's distributions).
std::uint64_t bounded(std::mt19937_64& rng, std::uint64_t bound) {
  const std::uint64_t limit = std::mt19937_64::max() - std::mt19937_64::max() % bound;
  std::uint64_t x = rng();
  while (x >= limit) x = rng();
  return x % bound;
}

void validate_attributes(const PointCloud& cloud) {
  if (!cloud.normals.empty() && cloud.normals.size() != cloud.size()) {
    throw InvalidInputError("cloud has " + std::to_string(cloud.normals.size()) + " normals for " +
                            std::to_string(cloud.size()) + " points");
  }
  if (!cloud.covariances.empty() && cloud.covariances.size() != cloud.size()) {
    throw InvalidInputError("cloud has " + std::to_string(cloud.covariances.size()) +
                            " covariances for " + std::to_string(cloud.size()) + " points");
  }
}

}  // namespace

PointCloud random_downsample(const PointCloud& cloud, std::size_t count, std::uint64_t seed) {
  validate_attributes(cloud);
  const std::size_t n = cloud.size();
  if (count >= n) return cloud;
  PointCloud out;
  out.origin_m = cloud.origin_m;
  out.points.reserve(count);
  if (cloud.has_normals()) out.normals.reserve(count);
  if (cloud.has_covariances()) out.covariances.reserve(count);
  // Selection sampling (Knuth's Algorithm S): point i is kept with probability
  // needed / remaining, which makes every subset of size `count` equally likely and keeps
  // input order without sorting.
  std::mt19937_64 rng(seed);
  std::size_t needed = count;
  for (std::size_t i = 0; i < n && needed > 0; ++i) {
    if (bounded(rng, n - i) < needed) {
      out.points.push_back(cloud.points[i]);
      if (cloud.has_normals()) out.normals.push_back(cloud.normals[i]);
      if (cloud.has_covariances()) out.covariances.push_back(cloud.covariances[i]);
      --needed;
    }
  }
  return out;
}

PointCloud random_downsample_ratio(const PointCloud& cloud, double ratio, std::uint64_t seed) {
  if (!std::isfinite(ratio) || ratio <= 0.0 || ratio > 1.0) {
    throw InvalidSettingsError("downsampling ratio must be in (0, 1], got " + format_number(ratio));
  }
  const double wanted = std::round(ratio * static_cast<double>(cloud.size()));
  const auto count = std::max<std::size_t>(static_cast<std::size_t>(wanted), 1);
  return random_downsample(cloud, count, seed);
}

}  // namespace sgdicp
