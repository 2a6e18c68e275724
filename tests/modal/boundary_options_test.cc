// BoundaryOptions described once (engine/common/describe.h): its settings' keys and the checks that
// depend on the aircraft, in those keys (ValidateBoundaryOptions); ModesOptions likewise.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "engine/modal/boundary.h"
#include "engine/modal/modal_analysis.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

std::vector<std::string> Keys(const std::vector<FieldRecord>& fields) {
  std::vector<std::string> keys;
  for (const FieldRecord& field : fields) keys.emplace_back(field.attributes.key);
  return keys;
}

TEST(BoundaryOptionsDescription, ListsTheStudyKeysOfTheBoundaryAnalysis) {
  // The keys of [analyses.boundary] (docs/model.md, the boundary search row; engine/analyses/
  // boundary_analysis.cc reads them), with the struct's defaults.
  const std::vector<FieldRecord> fields = ListFields(BoundaryOptions{});
  EXPECT_EQ(Keys(fields), (std::vector<std::string>{"method", "lower_height_m", "upper_height_m",
                                                    "tolerance_m", "samples_per_segment"}));
  EXPECT_EQ(fields[0].default_text, "hurwitz");
  EXPECT_EQ(fields[0].choices, (std::vector<std::string>{"hurwitz", "sampled"}));
  EXPECT_EQ(fields[3].default_text, "0.0001");
  EXPECT_EQ(fields[4].attributes.scope, FieldScope::kStudyOnly);  // not a flag
}

TEST(BoundaryOptionsDescription, ToleranceIsCheckedAgainstItsLimit) {
  BoundaryOptions options;
  // The heights default to NaN, "unset" (the aircraft's range), which is outside every range:
  // CheckFieldRanges checks given values (the flags are checked as they are parsed).
  options.lower_height_m = 1.0;
  options.upper_height_m = 5.0;
  EXPECT_NO_THROW(CheckFieldRanges(options, "test"));
  options.tolerance_m = 1.0;  // the limits table allows at most 1 mm
  EXPECT_THROW(CheckFieldRanges(options, "test"), InputError);
}

class BoundaryOptionsOnAnce : public ::testing::Test {
 protected:
  // The ANCE file's wheel-contact height and last finite table row (studies/aircraft/ance.toml).
  static constexpr double kWheelContact_m = 0.788;
  static constexpr double kLastRow_m = 13.373;
  Aircraft ance_ = LoadAircraftFile(testing::AnceAircraftPath());
};

TEST_F(BoundaryOptionsOnAnce, AcceptsTheDefaultsAndARangeInside) {
  EXPECT_NO_THROW(ValidateBoundaryOptions(BoundaryOptions{}, ance_, "test"));
  BoundaryOptions options;
  options.lower_height_m = kWheelContact_m;
  options.upper_height_m = 5.0;
  EXPECT_NO_THROW(ValidateBoundaryOptions(options, ance_, "test"));
}

TEST_F(BoundaryOptionsOnAnce, RefusesARangeBelowTheWheelsInTheFieldsKey) {
  BoundaryOptions options;
  options.lower_height_m = kWheelContact_m / 2;
  try {
    ValidateBoundaryOptions(options, ance_, "test");
    FAIL() << "accepted a range below the wheel contact";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "lower_height_m");
    EXPECT_NE(e.expected().find("wheel-contact height 0.788 m"), std::string::npos) << e.what();
  }
}

TEST_F(BoundaryOptionsOnAnce, RefusesAnEmptyRangeNamingBothKeys) {
  BoundaryOptions options;
  options.lower_height_m = 5.0;
  options.upper_height_m = 3.0;
  try {
    ValidateBoundaryOptions(options, ance_, "test");
    FAIL() << "accepted upper < lower";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "upper_height_m");
    EXPECT_EQ(e.expected(), "expected more than lower_height_m = 5 m");
  }
  // Above the default upper end (the last finite row) the lower end is the one named.
  BoundaryOptions above;
  above.lower_height_m = kLastRow_m + 1;
  try {
    ValidateBoundaryOptions(above, ance_, "test");
    FAIL() << "accepted a lower end above the last row";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "lower_height_m");
    EXPECT_NE(e.expected().find("upper_height_m = 13.373 m"), std::string::npos) << e.what();
  }
}

TEST(ModesOptionsDescription, SpeedIsACommandLineSettingWithTheSpeedLimit) {
  const std::vector<FieldRecord> fields = ListFields(ModesOptions{});
  ASSERT_EQ(fields.size(), 1u);
  EXPECT_EQ(fields[0].attributes.key, "speed_mps");
  EXPECT_EQ(fields[0].attributes.limit, "speed_mps");
  EXPECT_EQ(fields[0].attributes.scope, FieldScope::kCommandLineOnly);
}

}  // namespace
}  // namespace gesweep
