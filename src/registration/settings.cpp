#include "sgdicp/registration/settings.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <type_traits>

#include "registration/setting_rows.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/core/threads.hpp"
#include "sgdicp/uncertainty/uncertainty.hpp"

namespace sgdicp {

// ---- presets

SgdSettings SgdSettings::paper(OptimizerType optimizer) {
  SgdSettings s;
  s.sampling.batch_size = 160;
  s.adapt_small_sources = false;
  s.pairing.max_correspondence_distance = Distance::scaled(0.5);
  s.optimizer.type = optimizer;
  // The paper states alpha = 2 for the fixed step. Adam's step is a length per iteration (it
  // divides by the gradient's RMS), so alpha = 2 would jump twice across the unit cube; we use
  // the original implementation's Adam step 0.1 scaled down by the measured factor
  // (docs/design.md). Both come from the one table of step sizes.
  s.optimizer.learning_rate = default_learning_rate(optimizer);
  s.scaling.origin = ScalingOrigin::lower_corner;
  s.scaling.robust = false;
  s.refinement.stages = 0;
  s.average_iterates = false;
  s.cost = s.coarse_cost = CostType::point_to_point;
  s.downsampling.downsample_to = 0;
  return s;
}

namespace {
std::size_t window_of(const SgdSettings& settings) {
  return std::max<std::size_t>(settings.convergence.window, 1);
}
}  // namespace

bool is_small_source(const SgdSettings& settings, std::size_t source_points) {
  return 2 * source_points < settings.sampling.batch_size * window_of(settings);
}

std::size_t batch_size_for(const SgdSettings& settings, std::size_t source_points) {
  if (!settings.adapt_small_sources || !is_small_source(settings, source_points)) {
    return settings.sampling.batch_size;
  }
  const std::size_t window = window_of(settings);
  const std::size_t twice_per_window = (2 * source_points + window - 1) / window;
  return std::min(settings.sampling.batch_size, std::max(kMinCappedBatch, twice_per_window));
}

bool is_default_step_rule(const OptimizerSettings& optimizer) {
  OptimizerSettings rule = optimizer;
  const OptimizerSettings defaults = SgdSettings{}.optimizer;
  rule.damping = defaults.damping;
  return rule == defaults;
}

OptimizerSettings optimizer_for(const SgdSettings& settings, std::size_t source_points) {
  if (!settings.adapt_small_sources || !is_default_step_rule(settings.optimizer) ||
      !is_small_source(settings, source_points)) {
    return settings.optimizer;
  }
  return with_gauss_newton_steps(settings.optimizer);
}

std::size_t min_source_points(const SgdSettings& settings) {
  return settings.adapt_small_sources ? std::min(settings.sampling.batch_size, kMinCappedBatch)
                                      : settings.sampling.batch_size;
}

BatchSettings BatchSettings::icp() {
  return BatchSettings{};
}

BatchSettings BatchSettings::icp_plane() {
  BatchSettings s;
  s.cost = CostType::point_to_plane;
  return s;
}

BatchSettings BatchSettings::gicp() {
  BatchSettings s;
  s.cost = CostType::plane_to_plane;
  return s;
}

// ---- values

std::string ValueRange::to_string() const {
  const auto bound = [](double v) {
    return v >= 0x1p64 ? std::string("2^64-1") : format_number(v);
  };
  std::string out = min_open ? "(" : "[";
  out += bound(min);
  out += ", ";
  out += bound(max);
  out += max_open ? ")" : "]";
  return out;
}

std::string format_value(const SettingValue& value) {
  struct Visitor {
    std::string operator()(std::uint64_t v) const { return std::to_string(v); }
    std::string operator()(double v) const { return format_number(v); }
    std::string operator()(bool v) const { return v ? "true" : "false"; }
    std::string operator()(const Distance& d) const {
      return format_number(d.value) + (d.unit == Distance::Unit::metres ? " m" : " scaled");
    }
    std::string operator()(const std::string& name) const { return name; }
  };
  return std::visit(Visitor{}, value);
}

// The part of SgdSettings the field lives in (the table's own grouping).
std::string_view setting_part(std::string_view field) {
  const std::string_view part = field.substr(0, field.find('.'));
  if (part == "sampling") return "Sampling (the mini-batches)";
  if (part == "optimizer") return "Step rule";
  if (part == "convergence") return "Convergence";
  if (part == "refinement") return "Refinement";
  if (part == "pairing") return "Pairs and robust costs";
  if (part == "neighborhood") return "Surfaces (normals, covariances)";
  if (part == "downsampling") return "Downsampling";
  if (part == "scaling") return "Scaling";
  if (part == "uncertainty") return "Uncertainty";
  return "Registration run";
}

std::string SettingDescription::spelled(SettingNames names) const {
  switch (names) {
    case SettingNames::cli:
      return "--" + std::string(name);
    case SettingNames::python: {
      std::string keyword(name);
      for (char& c : keyword) c = c == '-' ? '_' : c;
      return keyword + "=";
    }
    case SettingNames::field:
      break;
  }
  return std::string(field);
}

void check_range(const SettingDescription& setting, const SettingValue& value, SettingNames names) {
  double number = 0.0;
  const ValueRange* range = &setting.range;
  std::string unit;
  if (!setting.unit.empty()) unit.append(" ").append(setting.unit);
  if (const auto* count = std::get_if<std::uint64_t>(&value)) {
    number = static_cast<double>(*count);
  } else if (const auto* real = std::get_if<double>(&value)) {
    number = *real;
  } else if (const auto* distance = std::get_if<Distance>(&value)) {
    number = distance->value;
    const bool metres = distance->unit == Distance::Unit::metres;
    if (metres) range = &setting.metres_range;
    unit = metres ? " m" : " scaled units";
  } else {
    return;  // flags and choices have no range
  }
  if (std::isfinite(number) && range->contains(number)) return;
  const std::string separator = names == SettingNames::cli     ? " "
                                : names == SettingNames::field ? " = "
                                                               : "";
  throw InvalidSettingsError(setting.spelled(names) + separator + format_value(value) +
                             ": must be in " + range->to_string() + unit);
}

namespace {

// batch_size x window pair distances are kept for the refinement (4 bytes each, twice).
constexpr double kMaxWindowPairs = 1e8;

}  // namespace

void SgdSettings::validate(SettingNames names) const {
  detail::check_table(*this, sgd_settings_table(), names);
  detail::check_table(*this, sgd_fixed_rules_table(), SettingNames::field);
  neighborhood.validate();  // epsilon and the viewpoint are not in the table
  // The secant never reports a softening below kMinSoftening: a smaller one is no value it uses.
  if (uncertainty.softening > 0.0 && uncertainty.softening < kMinSoftening) {
    throw InvalidSettingsError("uncertainty.softening = " + format_number(uncertainty.softening) +
                               ": must be 0 (measure it) or in [" + format_number(kMinSoftening) +
                               ", 1]");
  }
  const double pairs =
      static_cast<double>(sampling.batch_size) * static_cast<double>(convergence.window);
  if (pairs > kMaxWindowPairs) {
    const auto* b = find_sgd_setting("batch-size");
    const auto* w = find_sgd_setting("window");
    throw InvalidSettingsError(b->spelled(names) + " x " + w->spelled(names) + " = " +
                               format_number(pairs) + ": must be at most " +
                               format_number(kMaxWindowPairs) +
                               " (the pair distances of a window are kept, 8 bytes each)");
  }
}

void BatchSettings::validate(SettingNames names) const {
  detail::check_table(*this, batch_settings_table(), names);
  neighborhood.validate();  // epsilon and the viewpoint are not in the table
}

void OptimizerSettings::validate() const {
  SgdSettings s;
  s.optimizer = *this;
  for (const auto& setting : sgd_settings_table()) {
    if (setting.field.starts_with("optimizer.")) {
      check_range(setting, setting.get(s), SettingNames::field);
    }
  }
}

}  // namespace sgdicp
