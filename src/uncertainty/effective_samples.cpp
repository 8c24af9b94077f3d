#include "uncertainty/effective_samples.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <limits>

#include <unsupported/Eigen/FFT>

namespace sgdicp::detail {

namespace {

// The autocovariances at every lag 0..n-1 of the centred `x`, each divided by n (the biased
// estimate keeps the sequence positive definite, as Geyer's argument needs). By FFT: the sum one
// lag at a time is O(n) per lag, and a chain that never decorrelates reaches lag n/2, minutes at
// the 1e6 samples a run may ask for; the FFT is O(n log n) for any chain (Eigen's FFT module).
std::vector<double> autocovariances(const std::vector<double>& x, double mean) {
  const std::size_t n = x.size();
  std::size_t padded = 1;
  while (padded < 2 * n) padded *= 2;  // zero padding: no wrap-around between lags
  std::vector<double> centred(padded, 0.0);
  for (std::size_t i = 0; i < n; ++i) centred[i] = x[i] - mean;
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, centred);
  for (std::complex<double>& c : spectrum) c = std::norm(c);
  std::vector<double> gamma;
  fft.inv(gamma, spectrum);
  gamma.resize(n);
  for (double& g : gamma) g /= static_cast<double>(n);
  return gamma;
}

}  // namespace

double effective_sample_size(const std::vector<double>& x) {
  const std::size_t n = x.size();
  if (n < 4) return 0.0;
  double mean = 0.0;
  for (const double v : x) mean += v;
  mean /= static_cast<double>(n);
  double variance = 0.0;
  for (const double v : x) variance += (v - mean) * (v - mean);
  variance /= static_cast<double>(n);
  // A chain that never moved: the rounding of its mean is all the spread it has.
  const double rounding = 16.0 * std::numeric_limits<double>::epsilon() * std::abs(mean);
  if (!(variance > rounding * rounding)) return 0.0;
  const std::vector<double> gamma = autocovariances(x, mean);
  // tau = -1 + 2 sum_m Gamma_m, Gamma_m = rho_2m + rho_2m+1, while positive and non-increasing.
  double tau = -1.0;
  double previous = std::numeric_limits<double>::infinity();
  for (std::size_t m = 0; 2 * m + 1 < n; ++m) {
    const double pair = (gamma[2 * m] + gamma[2 * m + 1]) / variance;
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
