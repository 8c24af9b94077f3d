// Tests of the settings tables (settings.hpp; the odometry's and the global registration's):
// every range is enforced by validate() with a message naming the setting as spelled, the
// defaults and presets lie inside their ranges, the enum and method names round-trip, and
// docs/registration.md, docs/odometry.md and docs/global.md list every setting as the tables say
// (default, paper() value, range), and no other.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <set>
#include <sstream>
#include <string>
#include <string_view>

#include "sgdicp/core/result.hpp"
#include "sgdicp/global/global_registration.hpp"
#include "sgdicp/odometry/odometry.hpp"
#include "sgdicp/registration/methods.hpp"
#include "sgdicp/registration/settings.hpp"

#ifndef SGDICP_SOURCE_DIR
#error "SGDICP_SOURCE_DIR must name the repository"
#endif

namespace {

using namespace sgdicp;

// A value just outside (or at) one end of a range, in the setting's kind.
template <typename S>
SettingValue value_at(const Setting<S>& s, double v, Distance::Unit unit) {
  switch (s.kind) {
    case SettingKind::count:
      return static_cast<std::uint64_t>(v);
    case SettingKind::distance:
      return Distance{v, unit};
    default:
      return v;
  }
}

template <typename S>
std::string message_of(const S& settings, SettingNames names) {
  try {
    settings.validate(names);
  } catch (const InvalidSettingsError& e) {
    return e.what();
  }
  return "";
}

// Every end of every range: inside passes, outside fails naming the setting and its range. The
// C++ message starts with `field_prefix` and the member; `bounded_together` are settings that
// another bounds too (a product, an order), whose ends are not valid on their own.
template <typename S>
void check_ranges(const std::vector<Setting<S>>& table, std::string_view field_prefix = "",
                  std::initializer_list<std::string_view> bounded_together = {}) {
  for (const auto& s : table) {
    if (s.kind == SettingKind::flag || s.kind == SettingKind::choice) continue;
    for (const auto unit : {Distance::Unit::scaled, Distance::Unit::metres}) {
      if (unit == Distance::Unit::metres && s.kind != SettingKind::distance) continue;
      const ValueRange& r = unit == Distance::Unit::metres ? s.metres_range : s.range;
      SCOPED_TRACE(std::string(s.field));
      const double below = r.min_open || r.min == 0.0 ? r.min : r.min * 0.5;
      const double above = r.max_open ? r.max : r.max * 2.0;
      for (const double bad : {below, above, std::nan("")}) {
        if (s.kind == SettingKind::count && (std::isnan(bad) || bad >= 0x1p64 || bad < 0)) continue;
        if (bad == r.min && !r.min_open) continue;  // a closed end at 0: no count below it
        S settings{};
        s.set(settings, value_at(s, bad, unit));
        const std::string cli = message_of(settings, SettingNames::cli);
        EXPECT_NE(cli.find("--" + std::string(s.name) + " "), std::string::npos) << cli;
        EXPECT_NE(cli.find(r.to_string()), std::string::npos) << cli;
        const std::string field = message_of(settings, SettingNames::field);
        EXPECT_EQ(field.rfind(std::string(field_prefix) + std::string(s.field) + " = ", 0), 0U)
            << field;
      }
      for (const double good : {r.min, r.max}) {
        if ((good == r.min && r.min_open) || (good == r.max && r.max_open)) continue;
        if (s.kind == SettingKind::count && good >= 0x1p64) continue;
        S settings{};
        s.set(settings, value_at(s, good, unit));
        if (std::find(bounded_together.begin(), bounded_together.end(), s.name) !=
            bounded_together.end()) {
          continue;
        }
        EXPECT_EQ(message_of(settings, SettingNames::field), "");
      }
    }
  }
}

TEST(SettingsTable, EveryRangeIsEnforcedWithTheSpelledName) {
  check_ranges(sgd_settings_table(), "", {"batch-size", "window"});  // their product is bounded
  check_ranges(batch_settings_table());
  check_ranges(odometry_settings_table(), "", {"min-range"});  // below max-range
  check_ranges(global_settings_table(), "GlobalSettings.");
}

TEST(SettingsTable, DefaultsAndPresetsAreValid) {
  EXPECT_NO_THROW(SgdSettings{}.validate());
  for (const auto type : {OptimizerType::sgd, OptimizerType::momentum, OptimizerType::rmsprop,
                          OptimizerType::adam, OptimizerType::gauss_newton}) {
    EXPECT_NO_THROW(SgdSettings::paper(type).validate());
  }
  EXPECT_NO_THROW(BatchSettings{}.validate());
  EXPECT_NO_THROW(BatchSettings::gicp().validate());
  EXPECT_NO_THROW(OdometrySettings{}.validate());
  EXPECT_NO_THROW(GlobalSettings{}.validate());
}

// `register --init global` takes the registration's options and the global ones together, and
// register(init="global") their keywords: no name may mean both.
TEST(SettingsTable, GlobalNamesArePrefixedAndUnique) {
  std::set<std::string_view> names;
  for (const auto& s : sgd_settings_table()) names.insert(s.name);
  for (const auto& g : global_settings_table()) {
    EXPECT_EQ(g.name.rfind("global-", 0), 0U) << g.name;
    EXPECT_TRUE(names.insert(g.name).second) << g.name;
    std::string keyword(g.name);
    std::replace(keyword.begin(), keyword.end(), '-', '_');
    EXPECT_EQ(find_global_setting(keyword), &g);  // Python's spelling finds it too
    EXPECT_NE(g.help, "");
  }
  EXPECT_EQ(find_global_setting("min-points"), nullptr);
}

TEST(SettingsTable, NamesAreUniqueAndSharedNamesMeanTheSameRange) {
  const auto& sgd = sgd_settings_table();
  for (std::size_t i = 0; i < sgd.size(); ++i) {
    for (std::size_t j = i + 1; j < sgd.size(); ++j) EXPECT_NE(sgd[i].name, sgd[j].name);
  }
  for (const auto& b : batch_settings_table()) {
    const auto* s = find_sgd_setting(b.name);
    ASSERT_NE(s, nullptr) << b.name;
    EXPECT_EQ(s->kind, b.kind) << b.name;
    EXPECT_EQ(s->range.to_string(), b.range.to_string()) << b.name;
  }
}

TEST(SettingsTable, ProductOfBatchAndWindowIsBounded) {
  SgdSettings s;
  s.sampling.batch_size = 100000;
  s.convergence.window = 10000;
  EXPECT_NE(message_of(s, SettingNames::cli).find("--batch-size x --window"), std::string::npos);
}

TEST(SettingsTable, OptimizerSetsItsOwnStepAndThePaperPresetAgrees) {
  const auto* optimizer = find_sgd_setting("optimizer");
  ASSERT_NE(optimizer, nullptr);
  EXPECT_EQ(sgd_settings_table().front().name, "optimizer");  // applied before learning-rate
  for (const auto name : canonical_names<OptimizerType>()) {
    SgdSettings s = SgdSettings::paper();
    optimizer->set(s, std::string(name));
    const OptimizerType type = parse_enum<OptimizerType>(name);
    EXPECT_EQ(s.optimizer.learning_rate, default_learning_rate(type)) << name;
    EXPECT_EQ(SgdSettings::paper(type).optimizer.learning_rate, default_learning_rate(type));
  }
  EXPECT_EQ(SgdSettings::paper(OptimizerType::gauss_newton).optimizer.learning_rate, 1.0);
  EXPECT_EQ(SgdSettings::paper().optimizer.learning_rate, 2.0);
  EXPECT_EQ(SgdSettings{}.optimizer.learning_rate, 0.01);
}

TEST(SettingsTable, EqualityIsFieldByField) {
  SgdSettings a;
  SgdSettings b;
  EXPECT_EQ(a, b);
  b.neighborhood.viewpoint.z() = 1.0F;
  EXPECT_NE(a, b);
  b = a;
  b.convergence.chi2 = 10.0;
  EXPECT_NE(a, b);
  EXPECT_NE(BatchSettings::icp(), BatchSettings::gicp());
}

template <typename E>
void check_round_trip() {
  for (const auto name : canonical_names<E>()) {
    EXPECT_EQ(enum_name(parse_enum<E>(name)), name);
    std::string underscored(name);
    for (char& c : underscored) c = c == '-' ? '_' : c;
    EXPECT_EQ(enum_name(parse_enum<E>(underscored)), name);
  }
  try {
    (void)parse_enum<E>("no-such-name");
    ADD_FAILURE() << "parsed an unknown name";
  } catch (const InvalidSettingsError& e) {
    EXPECT_NE(std::string(e.what()).find(name_list<E>()), std::string::npos) << e.what();
  }
}

TEST(EnumNames, EveryEnumRoundTripsAndListsItsNames) {
  check_round_trip<OptimizerType>();
  check_round_trip<CostType>();
  check_round_trip<KernelType>();
  check_round_trip<ScalingOrigin>();
  check_round_trip<StopReason>();
  check_round_trip<Distance::Unit>();
  EXPECT_EQ(parse_enum<ScalingOrigin>("corner"), ScalingOrigin::lower_corner);
  EXPECT_EQ(parse_enum<ScalingOrigin>("lower_corner"), ScalingOrigin::lower_corner);
  EXPECT_EQ(parse_enum<Distance::Unit>("metres"), Distance::Unit::metres);
  EXPECT_EQ(name_list<ScalingOrigin>(), "lower-corner or center");
}

TEST(Methods, NamesMapToSolverAndCost) {
  EXPECT_EQ(method_from_string("sgd").cost, std::nullopt);
  EXPECT_EQ(method_from_string("gicp").solver, Solver::batch);
  EXPECT_EQ(method_from_string("gicp").cost, CostType::plane_to_plane);
  EXPECT_EQ(method_from_string("sgd_gicp").solver, Solver::sgd);  // "gicp" in it, still SGD
  EXPECT_EQ(method_from_string("icp-plane").cost, CostType::point_to_plane);
  EXPECT_THROW((void)method_from_string("icp2"), InvalidSettingsError);
}

// ---- docs/registration.md, docs/odometry.md and docs/global.md against the tables

std::string range_text(const SettingDescription& s) {
  if (s.kind == SettingKind::distance) {
    return s.range.to_string() + " scaled, " + s.metres_range.to_string() + " m";
  }
  if (s.kind == SettingKind::choice) {
    std::string names;
    for (const auto n : s.choices()) names += (names.empty() ? "`" : ", `") + std::string(n) + "`";
    return names;
  }
  if (s.kind == SettingKind::flag) return "true, false";
  return s.range.to_string() + (s.unit.empty() ? "" : " " + std::string(s.unit));
}

// The first columns of a docs table's row: the C++ member, the CLI option, the Python keyword.
std::string names_columns(const SettingDescription& s) {
  std::string keyword(s.name);
  for (char& c : keyword) c = c == '-' ? '_' : c;
  const std::string cli = s.keyword_only ? "–" : "`--" + std::string(s.name) + "`";
  return "| `" + std::string(s.field) + "` | " + cli + " | `" + keyword + "` |";
}

// The row of docs/registration.md's settings table for one setting.
std::string doc_row(const Setting<SgdSettings>& s) {
  const auto* batch = find_batch_setting(s.name);
  const std::string batch_default = batch ? format_value(batch->get(BatchSettings{})) : "–";
  return names_columns(s) + " " + format_value(s.get(SgdSettings{})) + " | " +
         format_value(s.get(SgdSettings::paper())) + " | " + batch_default + " | " + range_text(s) +
         " |";
}

// The row of docs/odometry.md's settings table for one setting.
std::string doc_row(const Setting<OdometrySettings>& s) {
  return names_columns(s) + " " + format_value(s.get(OdometrySettings{})) + " | " + range_text(s) +
         " |";
}

// The row of docs/global.md's settings table for one setting.
std::string doc_row(const Setting<GlobalSettings>& s) {
  return names_columns(s) + " " + format_value(s.get(GlobalSettings{})) + " | " + range_text(s) +
         " |";
}

std::string read_doc(const std::string& name) {
  std::ifstream in(std::string(SGDICP_SOURCE_DIR) + "/docs/" + name);
  EXPECT_TRUE(in) << "docs/" << name << " not found";
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The rows of `table` that `doc` lacks (each row followed by its meaning column).
template <typename S>
std::string missing_rows(const std::string& doc, const std::vector<Setting<S>>& table) {
  std::string missing;
  for (const auto& s : table) {
    const std::string row = doc_row(s);
    if (doc.find(row + " ") == std::string::npos) missing += row + " ...\n";
  }
  return missing;
}

// The settings table's rows of a doc: `member` | `--option` or – | `keyword` | ...
// (a line scan: std::regex trips GCC 12's -Wmaybe-uninitialized in the sanitizer builds).
std::size_t setting_rows(const std::string& doc) {
  std::size_t rows = 0;
  std::istringstream lines(doc);
  for (std::string line; std::getline(lines, line);) {
    if (!line.starts_with("| `")) continue;
    const std::size_t second = line.find("` | ", 3);
    if (second == std::string::npos) continue;
    const std::string_view rest = std::string_view(line).substr(second + 4);
    if (!rest.starts_with("`--") && !rest.starts_with("–")) continue;
    const std::size_t third = rest.find(" | ");
    if (third != std::string_view::npos && rest.substr(third + 3).starts_with("`")) ++rows;
  }
  return rows;
}

TEST(SettingsDocs, RegistrationMdListsEverySettingAsTheTableSaysAndNoOther) {
  const std::string doc = read_doc("registration.md");
  EXPECT_EQ(missing_rows(doc, sgd_settings_table()), "")
      << "rows of docs/registration.md to update (keep the meaning column)";
  // No row of a setting the table does not have (a removed or renamed one).
  EXPECT_EQ(setting_rows(doc), sgd_settings_table().size());
}

TEST(SettingsDocs, OdometryMdListsEverySettingAsTheTableSaysAndNoOther) {
  const std::string doc = read_doc("odometry.md");
  EXPECT_EQ(missing_rows(doc, odometry_settings_table()), "")
      << "rows of docs/odometry.md to update (keep the meaning column)";
  EXPECT_EQ(setting_rows(doc), odometry_settings_table().size());
}

TEST(SettingsDocs, GlobalMdListsEverySettingAsTheTableSaysAndNoOther) {
  const std::string doc = read_doc("global.md");
  EXPECT_EQ(missing_rows(doc, global_settings_table()), "")
      << "rows of docs/global.md to update (keep the meaning column)";
  // No row of a setting the table does not have (a removed or renamed one).
  EXPECT_EQ(setting_rows(doc), global_settings_table().size());
}

}  // namespace
