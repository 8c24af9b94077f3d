// Stein variational gradient descent (Liu and Wang 2016) for svgd's particles: the kernel, its
// bandwidth, the descent and the modes of the particles (uncertainty.hpp).
#include "uncertainty/stein.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "sgdicp/solver/optimizer.hpp"
#include "sgdicp/uncertainty/uncertainty.hpp"

namespace sgdicp {
namespace {

// The RBF bandwidth of the median heuristic (Liu and Wang 2016, section 5): h = med^2 /
// log(K + 1), med the median pairwise distance, so that a particle's own term weighs about as
// much as all the others together.
double median_bandwidth(const std::vector<PoseVector>& z) {
  std::vector<double> pairs;
  for (std::size_t i = 0; i < z.size(); ++i) {
    for (std::size_t j = i + 1; j < z.size(); ++j) pairs.push_back((z[i] - z[j]).squaredNorm());
  }
  if (pairs.empty()) return 1.0;  // one particle: any bandwidth gives k = 1
  const auto mid = pairs.begin() + static_cast<std::ptrdiff_t>(pairs.size() / 2);
  std::nth_element(pairs.begin(), mid, pairs.end());
  return *mid > 0.0 ? *mid / std::log(static_cast<double>(z.size()) + 1.0) : 1.0;
}

// Particles closer than this belong to one mode (kModeLinkDistance, kModeLinkBandwidth), given
// the median heuristic's bandwidth of the particles.
double mode_link(double median_h) {
  return std::max(kModeLinkDistance, kModeLinkBandwidth * std::sqrt(median_h));
}

// The Stein direction of every particle (Liu and Wang 2016, eq. 8): the kernel-weighted mean of
// the particles' descent directions plus the kernel's gradient, which repels them from each
// other. While the particles form one mode the bandwidth is the median heuristic's times
// kSvgdBandwidthScale (its measurement in uncertainty.hpp); over several modes the median is
// set by the distances between them, and a wider kernel would merge them.
std::vector<PoseVector> stein_direction(const std::vector<PoseVector>& z,
                                        const std::vector<PoseVector>& grads) {
  const double median = median_bandwidth(z);
  const bool one_mode = particle_modes(z, mode_link(median)).size() == 1;
  const double h = one_mode ? kSvgdBandwidthScale * median : median;
  std::vector<PoseVector> phi(z.size(), PoseVector::Zero());
  for (std::size_t i = 0; i < z.size(); ++i) {
    for (std::size_t j = 0; j < z.size(); ++j) {
      const double k = std::exp(-(z[i] - z[j]).squaredNorm() / h);
      phi[i] += k * (-grads[j]) + (2.0 * k / h) * (z[i] - z[j]);
    }
    phi[i] /= static_cast<double>(z.size());
  }
  return phi;
}

}  // namespace

double detail::particle_link(const std::vector<PoseVector>& z) {
  return mode_link(median_bandwidth(z));
}

std::vector<PoseVector> stein_descent(std::vector<PoseVector> z,
                                      const ParticleGradients& energy_gradients,
                                      std::size_t iterations, double step_first, double step_last) {
  OptimizerSettings adam;
  adam.type = OptimizerType::adam;
  adam.learning_rate = 1.0;  // the schedule's step is the multiplier
  std::vector<Optimizer> optimizers(z.size(), Optimizer(adam));
  std::vector<PoseVector> grads(z.size(), PoseVector::Zero());
  const double last = static_cast<double>(std::max<std::size_t>(iterations, 2) - 1);
  for (std::size_t it = 0; it < iterations; ++it) {
    const double step =
        step_first * std::pow(step_last / step_first, static_cast<double>(it) / last);
    energy_gradients(z, grads);
    const std::vector<PoseVector> phi = stein_direction(z, grads);
    // Adam minimises along its argument: -phi ascends the Stein direction.
    for (std::size_t i = 0; i < z.size(); ++i) {
      z[i] += optimizers[i].step(-phi[i], PoseMatrix::Zero(), step);
    }
  }
  return z;
}

std::vector<std::vector<std::size_t>> particle_modes(const std::vector<PoseVector>& z,
                                                     double link) {
  const std::size_t n = z.size();
  std::vector<bool> taken(n, false);
  std::vector<std::vector<std::size_t>> modes;
  for (std::size_t first = 0; first < n; ++first) {
    if (taken[first]) continue;
    taken[first] = true;
    std::vector<std::size_t> mode{first};
    // Breadth-first over the particles within `link` of a member.
    for (std::size_t q = 0; q < mode.size(); ++q) {
      for (std::size_t j = 0; j < n; ++j) {
        if (!taken[j] && (z[mode[q]] - z[j]).norm() < link) {
          taken[j] = true;
          mode.push_back(j);
        }
      }
    }
    std::sort(mode.begin(), mode.end());
    modes.push_back(std::move(mode));
  }
  std::stable_sort(modes.begin(), modes.end(),
                   [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return modes;
}

}  // namespace sgdicp
