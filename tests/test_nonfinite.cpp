// NaN and infinity in any input are rejected with a message that says where: a point of either
// cloud, an entry of the initial transform, every floating setting of every settings table.
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "sgdicp/core/error.hpp"
#include "sgdicp/global/global_registration.hpp"
#include "sgdicp/odometry/odometry.hpp"
#include "sgdicp/registration/batch_icp.hpp"
#include "sgdicp/registration/registration.hpp"
#include "sgdicp/registration/settings.hpp"
#include "test_support.hpp"

namespace sgdicp {
namespace {

const std::vector<double> kNonFinite{std::numeric_limits<double>::quiet_NaN(),
                                     std::numeric_limits<double>::infinity(),
                                     -std::numeric_limits<double>::infinity()};

// The message of the exception `call` throws, which must be an E; "" when it returns.
template <typename E>
std::string thrown(const std::function<void()>& call) {
  try {
    call();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("wrong exception: ") + e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

class NonFiniteInput : public ::testing::Test {
 protected:
  PointCloud source_ = test::synthetic_scene(5, 800);
  PointCloud reference_ = test::synthetic_scene(6, 800);
};

TEST_F(NonFiniteInput, PointsOfEitherCloudAreRejectedWithTheirIndex) {
  for (const double bad : kNonFinite) {
    for (int axis = 0; axis < 3; ++axis) {
      SCOPED_TRACE(std::to_string(bad) + " in coordinate " + std::to_string(axis));
      PointCloud source = source_;
      source.points[321][axis] = static_cast<float>(bad);
      const ReferenceIndex index(reference_);
      const std::string sgd =
          thrown<InvalidInputError>([&] { (void)align(source, index, SgdSettings{}); });
      EXPECT_TRUE(contains(sgd, "source cloud has a non-finite point at index 321")) << sgd;
      const std::string batch =
          thrown<InvalidInputError>([&] { (void)align_batch(source, index, BatchSettings{}); });
      EXPECT_TRUE(contains(batch, "source cloud has a non-finite point at index 321")) << batch;

      PointCloud reference = reference_;
      reference.points[17][axis] = static_cast<float>(bad);
      const std::string ref = thrown<InvalidInputError>([&] { ReferenceIndex{reference}; });
      EXPECT_TRUE(contains(ref, "non-finite point at index 17")) << ref;
    }
  }
}

TEST_F(NonFiniteInput, EveryEntryOfTheInitialTransformIsChecked) {
  const ReferenceIndex index(reference_);
  for (const double bad : kNonFinite) {
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) {
        Eigen::Matrix4d T_init = Eigen::Matrix4d::Identity();
        T_init(r, c) = bad;
        SCOPED_TRACE(std::to_string(bad) + " at " + std::to_string(r) + "," + std::to_string(c));
        const std::string sgd =
            thrown<InvalidInputError>([&] { (void)align(source_, index, SgdSettings{}, T_init); });
        EXPECT_TRUE(contains(sgd, "initial transform is not a finite rigid transform")) << sgd;
        const std::string batch = thrown<InvalidInputError>(
            [&] { (void)align_batch(source_, index, BatchSettings{}, T_init); });
        EXPECT_TRUE(contains(batch, "initial transform is not a finite rigid transform")) << batch;
      }
    }
  }
}

// Every real and distance setting of the table, in each unit, set to NaN, +inf and -inf.
template <typename S>
void expect_table_rejects_non_finite(const std::vector<Setting<S>>& table) {
  for (const auto& setting : table) {
    if (setting.kind != SettingKind::real && setting.kind != SettingKind::distance) continue;
    for (const double bad : kNonFinite) {
      for (const auto unit : {Distance::Unit::scaled, Distance::Unit::metres}) {
        if (setting.kind == SettingKind::real && unit == Distance::Unit::metres) continue;
        S settings{};
        setting.set(settings, setting.kind == SettingKind::real
                                  ? SettingValue{bad}
                                  : SettingValue{Distance{bad, unit}});
        const std::string cli =
            thrown<InvalidSettingsError>([&] { settings.validate(SettingNames::cli); });
        EXPECT_TRUE(contains(cli, "--" + std::string(setting.name) + " "))
            << setting.field << " = " << bad << ": '" << cli << "'";
        const std::string python =
            thrown<InvalidSettingsError>([&] { settings.validate(SettingNames::python); });
        EXPECT_FALSE(python.empty()) << setting.field << " = " << bad;
      }
    }
  }
}

TEST(NonFiniteSettings, EveryFloatingSettingOfEveryTableIsRejected) {
  expect_table_rejects_non_finite(sgd_settings_table());
  expect_table_rejects_non_finite(batch_settings_table());
  expect_table_rejects_non_finite(odometry_settings_table());
  expect_table_rejects_non_finite(global_settings_table());
}

// The neighbourhood's epsilon and viewpoint are not in the table (no CLI option) but are
// floating settings of both solvers all the same: validate() checks them before any work.
TEST(NonFiniteSettings, NeighbourhoodEpsilonAndViewpointAreRejectedByValidate) {
  for (const double bad : kNonFinite) {
    SgdSettings sgd;
    BatchSettings batch;
    sgd.neighborhood.epsilon = batch.neighborhood.epsilon = bad;
    EXPECT_TRUE(contains(thrown<InvalidSettingsError>([&] { sgd.validate(); }), "epsilon"));
    EXPECT_TRUE(contains(thrown<InvalidSettingsError>([&] { batch.validate(); }), "epsilon"));
    for (int axis = 0; axis < 3; ++axis) {
      SgdSettings s;
      BatchSettings b;
      s.neighborhood.viewpoint[axis] = b.neighborhood.viewpoint[axis] = static_cast<float>(bad);
      EXPECT_TRUE(contains(thrown<InvalidSettingsError>([&] { s.validate(); }), "viewpoint"));
      EXPECT_TRUE(contains(thrown<InvalidSettingsError>([&] { b.validate(); }), "viewpoint"));
    }
  }
}

// align() validates first: a non-finite setting fails before the clouds are looked at, with
// point-to-point too (which never reads the neighbourhood).
TEST_F(NonFiniteInput, AlignRejectsNonFiniteSettingsBeforeRunning) {
  const ReferenceIndex index(reference_);
  SgdSettings s;
  s.optimizer.learning_rate = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(thrown<InvalidSettingsError>([&] { (void)align(source_, index, s); }).empty());
  SgdSettings v;
  v.neighborhood.viewpoint.x() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(
      contains(thrown<InvalidSettingsError>([&] { (void)align(source_, index, v); }), "viewpoint"));
  BatchSettings b;
  b.initial_damping = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(thrown<InvalidSettingsError>([&] { (void)align_batch(source_, index, b); }).empty());
}

}  // namespace
}  // namespace sgdicp
