// Describe once (engine/common/describe.h): one field list gives the records, the key of a member,
// the range checks and the study-file reading, with the units, defaults and scopes it states.
#include "engine/common/describe.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/common/describe_toml.h"

namespace gesweep {

enum class Shape { kSquare, kCircle, kTriangle };
template <>
struct EnumNames<Shape> {  // table order differs from code order on purpose
  static constexpr EnumName<Shape> kTable[] = {
      {Shape::kCircle, "circle"}, {Shape::kSquare, "square"}, {Shape::kTriangle, "triangle"}};
};

namespace {

constexpr FieldComponent kPairComponents[] = {{"left_m", "m", "Left"}, {"right_m", "m", "Right"}};

struct Settings {
  double speed_mps = 30.0;
  double angle_rad = std::numbers::pi / 2;  // key in degrees: 90
  Shape shape = Shape::kCircle;
  bool enabled = true;
  double flag_only_m = 1.5;
  long count = 7;
  std::array<double, 2> pair{1.0, 2.0};

  template <class V>
  void Describe(V& v) {
    v(Field("speed_mps", &speed_mps).Unit("m/s").Limit("speed_mps").Doc("Speed"));
    v(Field("angle_deg", &angle_rad).Unit("deg").Scale(kRadiansPerDegree).Doc("Angle"));
    v(Field("shape", &shape).Doc("Shape"));
    v(Field("enabled", &enabled).Doc("On"));
    v(Field("flag_only_m", &flag_only_m).Unit("m").CommandLineOnly().Doc("A flag"));
    v(Field("count", &count).Stored(StoredAs::kInt32).Doc("A count"));
    v(Field("pair", &pair).Components(kPairComponents, "pair_").NotStored().Doc("A pair"));
  }
};

// The angle's key value: 90 deg exactly up to the round trip through radians.
constexpr double kDegreeRoundTrip = 1e-12;

TEST(Describe, ListsEveryFieldWithItsKindDefaultAndUnit) {
  const std::vector<FieldRecord> fields = ListFields(Settings{});
  ASSERT_EQ(fields.size(), 7u);
  EXPECT_EQ(fields[0].attributes.key, "speed_mps");
  EXPECT_EQ(fields[0].kind, FieldKind::kNumber);
  EXPECT_EQ(fields[0].default_text, "30");
  EXPECT_EQ(fields[0].attributes.unit, "m/s");
  EXPECT_NEAR(*fields[1].number, 90.0, kDegreeRoundTrip);  // in the key's unit
  EXPECT_EQ(fields[2].kind, FieldKind::kChoice);
  EXPECT_EQ(fields[2].default_text, "circle");
  EXPECT_EQ(fields[2].choices, (std::vector<std::string>{"circle", "square", "triangle"}));
  EXPECT_EQ(fields[2].levels, (std::vector<std::string>{"square", "circle", "triangle"}));  // by code
  EXPECT_EQ(fields[3].kind, FieldKind::kBoolean);
  EXPECT_EQ(fields[3].default_text, "true");
  EXPECT_EQ(fields[4].attributes.scope, FieldScope::kCommandLineOnly);
  EXPECT_EQ(fields[5].kind, FieldKind::kInteger);
  EXPECT_EQ(fields[5].attributes.stored, StoredAs::kInt32);
  EXPECT_EQ(fields[6].kind, FieldKind::kArray);
  EXPECT_EQ(fields[6].attributes.components.size(), 2u);
}

TEST(Describe, KeyOfNamesAMemberByItsKey) {
  const Settings s;
  EXPECT_EQ(KeyOf(s, &s.angle_rad), "angle_deg");
  EXPECT_EQ(KeyOf(s, &s.enabled), "enabled");
}

TEST(Describe, RangesAreCheckedInTheKeysUnit) {
  Settings s;
  EXPECT_NO_THROW(CheckFieldRanges(s, "test"));
  s.speed_mps = 0.5;  // below the limits table's 1 m/s
  try {
    CheckFieldRanges(s, "test");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "speed_mps");
    EXPECT_EQ(e.value(), "0.5");
    EXPECT_NE(e.expected().find("[1, 300] m/s"), std::string::npos) << e.expected();
  }
  s.speed_mps = std::nan("");
  EXPECT_THROW(CheckFieldRanges(s, "test"), InputError);
}

TEST(Describe, StudyTablesAreReadFromTheSameList) {
  const toml::table doc =
      ParseToml("speed_mps = 40\nangle_deg = 45\nshape = \"triangle\"\nenabled = false\n", "s.toml");
  Settings s;
  ReadFields(TomlSection(doc, "s.toml", ""), s);
  EXPECT_EQ(s.speed_mps, 40.0);
  EXPECT_NEAR(s.angle_rad, std::numbers::pi / 4, kDegreeRoundTrip);
  EXPECT_EQ(s.shape, Shape::kTriangle);
  EXPECT_FALSE(s.enabled);
  EXPECT_EQ(s.flag_only_m, 1.5);  // untouched
  EXPECT_EQ(StudyKeys(Settings{}),
            (std::vector<std::string>{"speed_mps", "angle_deg", "shape", "enabled", "count"}));
}

TEST(Describe, StudyTablesRefuseUnknownKeysBadNamesAndRanges) {
  auto refusal = [](const std::string& text) -> InputError {
    const toml::table doc = ParseToml(text, "s.toml");
    Settings s;
    try {
      ReadFields(TomlSection(doc, "s.toml", "analyses.x"), s);
    } catch (const InputError& e) {
      return e;
    }
    ADD_FAILURE() << "accepted: " << text;
    return InputError("", "", "", "");
  };
  const InputError unknown = refusal("sped_mps = 3\n");
  EXPECT_EQ(unknown.key(), "analyses.x.sped_mps");
  EXPECT_NE(unknown.expected().find("did you mean 'speed_mps'"), std::string::npos);
  // A command-line-only field is no study key.
  EXPECT_EQ(refusal("flag_only_m = 2\n").key(), "analyses.x.flag_only_m");
  const InputError name = refusal("shape = \"hexagon\"\n");
  EXPECT_EQ(name.value(), "\"hexagon\"");
  EXPECT_EQ(name.expected(), "expected circle, square or triangle");
  EXPECT_EQ(refusal("speed_mps = 400\n").key(), "analyses.x.speed_mps");
  EXPECT_EQ(refusal("enabled = 1\n").expected(), "expected true or false");
}

}  // namespace
}  // namespace gesweep
