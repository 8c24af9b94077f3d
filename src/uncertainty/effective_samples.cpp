#include "uncertainty/effective_samples.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace sgdicp::detail {

double effective_sample_size(const std::vector<double>& x) {
  const std::size_t n = x.size();
  if (n < 4) return 0.0;
  double mean = 0.0;
  for (const double v : x) mean += v;
  mean /= static_cast<double>(n);
  // The autocovariance at lag k, divided by n (the biased estimate keeps the sequence positive
  // definite, as Geyer's argument needs).
  const auto autocovariance = [&](std::size_t k) {
    double sum = 0.0;
    for (std::size_t i = 0; i + k < n; ++i) sum += (x[i] - mean) * (x[i + k] - mean);
    return sum / static_cast<double>(n);
  };
  const double variance = autocovariance(0);
  // A chain that never moved: the rounding of its mean is all the spread it has.
  const double rounding = 16.0 * std::numeric_limits<double>::epsilon() * std::abs(mean);
  if (!(variance > rounding * rounding)) return 0.0;
  // tau = -1 + 2 sum_m Gamma_m, Gamma_m = rho_2m + rho_2m+1, while positive and non-increasing.
  double tau = -1.0;
  double previous = std::numeric_limits<double>::infinity();
  for (std::size_t m = 0; 2 * m + 1 < n; ++m) {
    const double pair = (autocovariance(2 * m) + autocovariance(2 * m + 1)) / variance;
    if (!(pair > 0.0)) break;
    previous = std::min(previous, pair);
    tau += 2.0 * previous;
  }
  return static_cast<double>(n) / std::max(tau, 1.0 / static_cast<double>(n));
}

double effective_sample_size(const std::vector<PoseVector>& chain) {
  if (chain.size() < 4) return 0.0;
  double smallest = std::numeric_limits<double>::infinity();
  std::vector<double> coordinate(chain.size());
  for (int k = 0; k < 6; ++k) {
    for (std::size_t i = 0; i < chain.size(); ++i) coordinate[i] = chain[i][k];
    smallest = std::min(smallest, effective_sample_size(coordinate));
  }
  return smallest;
}

}  // namespace sgdicp::detail
