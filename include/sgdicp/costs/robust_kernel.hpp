#pragma once
// Robust kernels rho(s) applied to the squared residual s = e^T Omega e of a pair, with scale c
// (the residual size where the kernel starts to down-weight). Each kernel is normalised so that
// rho(s) ~ s near 0; its weight w(s) = d rho / d s is the factor each pair gets in the gradient
// and in iteratively reweighted least squares.
//   Huber:          rho = s                      if s <= c^2,   2 c sqrt(s) - c^2   otherwise
//   Cauchy:         rho = c^2 log(1 + s / c^2)
//   Geman-McClure:  rho = s c^2 / (c^2 + s)
//   Welsch:         rho = c^2 (1 - exp(-s / c^2))
#include <array>
#include <cmath>
#include <string>
#include <string_view>

#include "sgdicp/core/enum_names.hpp"

namespace sgdicp {

enum class KernelType { none, huber, cauchy, geman_mcclure, welsch };

inline constexpr std::array<EnumName<KernelType>, 5> kKernelNames{{
    {KernelType::none, "none"},
    {KernelType::huber, "huber"},
    {KernelType::cauchy, "cauchy"},
    {KernelType::geman_mcclure, "geman-mcclure"},
    {KernelType::welsch, "welsch"},
}};
constexpr const auto& enum_names(KernelType) {
  return kKernelNames;
}
constexpr std::string_view enum_noun(KernelType) {
  return "kernel";
}

[[nodiscard]] inline std::string_view to_string(KernelType t) {
  return enum_name(t);
}

/// Parses a name of kKernelNames ('_' for '-' too); throws InvalidSettingsError otherwise.
[[nodiscard]] inline KernelType kernel_from_string(std::string_view name) {
  return parse_enum<KernelType>(name);
}

/// rho(s) for squared residual s >= 0 and scale c > 0 (same unit as sqrt(s)).
[[nodiscard]] inline double kernel_rho(KernelType type, double s, double c) {
  const double c2 = c * c;
  switch (type) {
    case KernelType::none:
      return s;
    case KernelType::huber:
      return s <= c2 ? s : 2.0 * c * std::sqrt(s) - c2;
    case KernelType::cauchy:
      return c2 * std::log1p(s / c2);
    case KernelType::geman_mcclure:
      return s * c2 / (c2 + s);
    case KernelType::welsch:
      return c2 * -std::expm1(-s / c2);
  }
  return s;
}

/// w(s) = d rho / d s.
[[nodiscard]] inline double kernel_weight(KernelType type, double s, double c) {
  const double c2 = c * c;
  switch (type) {
    case KernelType::none:
      return 1.0;
    case KernelType::huber:
      return s <= c2 ? 1.0 : c / std::sqrt(s);
    case KernelType::cauchy:
      return 1.0 / (1.0 + s / c2);
    case KernelType::geman_mcclure: {
      const double d = c2 + s;
      return c2 * c2 / (d * d);
    }
    case KernelType::welsch:
      return std::exp(-s / c2);
  }
  return 1.0;
}

}  // namespace sgdicp
