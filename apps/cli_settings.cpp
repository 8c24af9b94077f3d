#include "cli_settings.hpp"

#include <charconv>
#include <chrono>
#include <cmath>

#include "sgdicp/core/error.hpp"
#include "sgdicp/global/global_registration.hpp"
#include "sgdicp/points/random_downsample.hpp"
#include "sgdicp/registration/batch_icp.hpp"
#include "sgdicp/registration/registration.hpp"

namespace sgdicp::cli {
namespace {

// CLI-only options: downsampling before the registration (metres; a fraction of the points).
constexpr ValueRange kRandomRatio{0.0, 1.0, true, false};

[[noreturn]] void bad_value(std::string_view option, std::string_view text, std::string_view what) {
  throw InvalidSettingsError(std::string(option) + " " + std::string(text) + ": " +
                             std::string(what));
}

[[noreturn]] void out_of_range(std::string_view option, std::string_view text,
                               const ValueRange& range, std::string_view unit) {
  bad_value(option, text, "must be in " + range.to_string() + std::string(unit));
}

// A number in the C locale's syntax, the whole text; a value beyond double is out of range.
double parse_real(std::string_view option, std::string_view text, const ValueRange& range,
                  std::string_view unit) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec == std::errc::result_out_of_range) out_of_range(option, text, range, unit);
  if (ec != std::errc() || end != text.data() + text.size())
    bad_value(option, text, "not a number");
  return v;
}

// A non-negative integer: no sign, no fraction, no wrap-around of values beyond 2^64-1.
std::uint64_t parse_count(std::string_view option, std::string_view text, const ValueRange& range) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec == std::errc::result_out_of_range) out_of_range(option, text, range, "");
  if (ec != std::errc() || end != text.data() + text.size()) {
    bad_value(option, text, "not a non-negative integer (valid: " + range.to_string() + ")");
  }
  return v;
}

bool parse_flag(std::string_view option, std::string_view text) {
  for (const char* yes : {"true", "1", "yes", "on"}) {
    if (text == yes) return true;
  }
  for (const char* no : {"false", "0", "no", "off"}) {
    if (text == no) return false;
  }
  bad_value(option, text, "expected true or false");
}

Distance::Unit unit_of(const SettingsOptions& o) {
  return parse_enum<Distance::Unit>(o.max_distance_unit);
}

std::optional<double> preprocessing_option(const std::optional<std::string>& text,
                                           std::string_view option, const ValueRange& range,
                                           std::string_view unit) {
  if (!text) return std::nullopt;
  const double v = parse_real(option, *text, range, unit);
  if (!std::isfinite(v) || !range.contains(v)) out_of_range(option, *text, range, unit);
  return v;
}

// "[default: D; paper preset: P]", D naming both solvers' defaults when they differ.
std::string default_text(const Setting<SgdSettings>& s) {
  const std::string sgd = format_value(s.get(SgdSettings{}));
  const std::string paper = format_value(s.get(SgdSettings::paper()));
  std::string text = sgd;
  if (const auto* b = find_batch_setting(s.name)) {
    const std::string batch = format_value(b->get(BatchSettings{}));
    if (batch != sgd) text = sgd + " for SGD methods, " + batch + " for batch methods";
  }
  if (paper != sgd) text += "; paper preset: " + paper;
  return " [default: " + text + "]";
}

// The help of one registration setting's option: the table's, the learning rate's per rule, and
// the defaults of both solvers and the paper preset.
std::string help_of(const Setting<SgdSettings>& s) {
  std::string help = detail::option_help(s);
  if (s.name == "learning-rate") {
    help += ". Unless given, each --optimizer's own:";
    for (const auto name : canonical_names<OptimizerType>()) {
      help += std::string(name == "sgd" ? " " : ", ") + std::string(name) + " " +
              format_number(default_learning_rate(parse_enum<OptimizerType>(name)));
    }
  }
  return help + default_text(s);
}

}  // namespace

SettingValue detail::option_value(const SettingDescription& s, const std::string& text,
                                  Distance::Unit unit) {
  const std::string option = s.spelled(SettingNames::cli);
  switch (s.kind) {
    case SettingKind::count:
      return parse_count(option, text, s.range);
    case SettingKind::real:
      return parse_real(option, text, s.range,
                        s.unit.empty() ? std::string() : std::string(" ").append(s.unit));
    case SettingKind::flag:
      return parse_flag(option, text);
    case SettingKind::distance: {
      const bool metres = unit == Distance::Unit::metres;
      return Distance{parse_real(option, text, metres ? s.metres_range : s.range,
                                 metres ? " m" : " scaled units"),
                      unit};
    }
    case SettingKind::choice:
      break;
  }
  return text;
}

std::string detail::option_help(const SettingDescription& s) {
  std::string help(s.help);
  if (s.kind == SettingKind::choice) {
    help += ": ";
    const auto names = s.choices();
    for (std::size_t i = 0; i < names.size(); ++i) help += (i ? ", " : "") + std::string(names[i]);
  } else if (s.kind == SettingKind::distance) {
    help += ", in the unit of --max-distance-unit, in " + s.range.to_string() + " scaled or " +
            s.metres_range.to_string() + " m";
  } else if (s.kind != SettingKind::flag) {
    help += ", " + (s.unit.empty() ? std::string("unitless") : std::string(s.unit)) + " in " +
            s.range.to_string();
  }
  return help;
}

std::string detail::option_type(const SettingDescription& s) {
  switch (s.kind) {
    case SettingKind::count:
      return "UINT";
    case SettingKind::real:
    case SettingKind::distance:
      return "FLOAT";
    case SettingKind::flag:
      return "BOOL";
    case SettingKind::choice:
      break;
  }
  std::string names;
  for (const auto name : s.choices()) names += (names.empty() ? "" : ",") + std::string(name);
  return "{" + names + "}";
}

void add_method_options(CLI::App& app, SettingsOptions& o, bool several) {
  std::string help = "Method:";
  for (const Method& m : kMethods) {
    help += std::string(&m == kMethods.data() ? " " : ", ") + std::string(m.name) + " (" +
            std::string(m.help) + ")";
  }
  if (several) help += "; several separated by commas are compared in one run";
  app.add_option("--method", o.method, help + " [default: " + o.method + "]");
  app.add_option("--random-ratio", o.random_ratio,
                 "Keep this random fraction of each cloud's points before registering (seeded "
                 "by --seed), in " +
                     kRandomRatio.to_string() + " [default: off]");
}

void add_settings_options(CLI::App& app, SettingsOptions& o, bool with_voxel_grid) {
  app.add_option("--preset", o.preset,
                 "Base settings of the SGD methods that the options below override: 'default' "
                 "(the best measured: paper coarse phase, then refinement) or 'paper' (m = 160, "
                 "d_max = 0.5 scaled, the step rule's own step, no refinement, last iterate "
                 "returned) [default: default]")
      ->check(CLI::IsMember({"default", "paper"}));
  app.add_option("--max-distance-unit", o.max_distance_unit,
                 "Unit of --max-distance, --min-distance and --kernel-scale: 'scaled' (fraction "
                 "of the largest side of the joint bounding box) or 'm' (metres) [default: "
                 "scaled]")
      ->check(CLI::IsMember({"scaled", "m"}));
  for (const auto& s : sgd_settings_table()) {
    if (s.keyword_only) continue;
    const std::string name(s.name);
    if (!with_voxel_grid && (name == "voxel-size" || name == "downsample-to")) continue;
    // The paper's symbols as short options: -m for the mini-batch size, -d for d_max.
    const std::string short_name = name == "batch-size"     ? "-m,"
                                   : name == "max-distance" ? "-d,"
                                                            : "";
    app.add_option_function<std::string>(
           short_name + "--" + name, [&o, name](const std::string& text) { o.values[name] = text; },
           help_of(s))
        ->type_name(detail::option_type(s));
  }
}

MethodSpec make_method(const std::string& name, const SettingsOptions& o) {
  const Method& method = method_from_string(name);
  MethodSpec m;
  m.name = std::string(method.name);
  m.stochastic = method.solver == Solver::sgd;
  m.sgd = o.preset == "paper" ? SgdSettings::paper() : SgdSettings{};
  // The method's cost first, so that an explicit --coarse-cost still sets the first stage's.
  apply_method_cost(method, m.sgd, m.batch);
  auto values = o.values;
  const Distance::Unit unit = unit_of(o);
  // In table order: --optimizer sets the learning rate before --learning-rate can override it.
  for (const auto& s : sgd_settings_table()) {
    const auto given = values.find(s.name);
    if (given == values.end()) continue;
    const SettingValue value = detail::option_value(s, given->second, unit);
    detail::apply_option(m.sgd, s, value);
    if (const auto* b = find_batch_setting(s.name)) detail::apply_option(m.batch, *b, value);
  }
  m.random_ratio = preprocessing_option(o.random_ratio, "--random-ratio", kRandomRatio, "");
  m.sgd.validate(SettingNames::cli);
  m.batch.validate(SettingNames::cli);
  check_method_uncertainty(method, m.sgd, SettingNames::cli);
  return m;
}

MethodRun run_method(const MethodSpec& m, const PointCloud& source, const PointCloud& reference,
                     const Eigen::Matrix4d& T_init, bool record_trace) {
  const auto start = std::chrono::steady_clock::now();
  std::optional<PointCloud> small_source;
  std::optional<PointCloud> small_reference;
  if (m.random_ratio) {
    small_source = random_downsample_ratio(source, *m.random_ratio, m.sgd.sampling.seed);
    small_reference = random_downsample_ratio(reference, *m.random_ratio, m.sgd.sampling.seed);
  }
  const PointCloud& src = small_source ? *small_source : source;
  const PointCloud& ref = small_reference ? *small_reference : reference;
  // The reference on the settings' voxel grid, with its KD-tree; a batch method also needs every
  // reference normal or covariance beforehand (align() estimates those of the pairs it uses). A
  // reference on a grid is only read, not copied.
  ReferenceIndex index =
      m.stochastic ? reference_index_for(ref, m.sgd) : reference_index_for(ref, m.batch);
  MethodRun run;
  run.prepare_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (m.stochastic) {
    SgdSettings s = m.sgd;
    s.record_trace = record_trace;
    run.result = align(src, index, s, T_init);
  } else {
    BatchSettings b = m.batch;
    b.record_trace = record_trace;
    run.result = align_batch(src, index, b, T_init);
  }
  run.source_points = run.result.source_points;
  run.reference_points = run.result.reference_points;
  return run;
}

MethodRun run_method_global(const MethodSpec& m, const PointCloud& source,
                            const PointCloud& reference, const GlobalSettings& global) {
  if (!m.stochastic || m.random_ratio) {
    throw InvalidSettingsError("--init global: only with an SGD method (--method " + m.name +
                               ") and without --random-ratio");
  }
  const auto start = std::chrono::steady_clock::now();
  const ReferenceIndex index = reference_index_for(reference, m.sgd);
  MethodRun run;
  run.prepare_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  run.result = align_global(source, index, m.sgd, global);
  run.source_points = run.result.source_points;
  run.reference_points = run.result.reference_points;
  return run;
}

}  // namespace sgdicp::cli
