// One names table per enum: printing, parsing and the choices of a message come from it.
#include "engine/common/enum_names.h"

#include <gtest/gtest.h>

namespace gesweep {

enum class Colour { kRed, kGreen, kBlue };
template <>
struct EnumNames<Colour> {
  static constexpr EnumName<Colour> kTable[] = {
      {Colour::kRed, "red"}, {Colour::kGreen, "green"}, {Colour::kBlue, "blue"}};
};

enum class Single { kOnly };
template <>
struct EnumNames<Single> {
  static constexpr EnumName<Single> kTable[] = {{Single::kOnly, "only"}};
};

enum class Pair { kA, kB };
template <>
struct EnumNames<Pair> {
  static constexpr EnumName<Pair> kTable[] = {{Pair::kA, "a"}, {Pair::kB, "b"}};
};

namespace {

TEST(EnumNames, PrintsAndParsesEveryValueBothWays) {
  for (Colour c : {Colour::kRed, Colour::kGreen, Colour::kBlue}) {
    EXPECT_EQ(ParseEnum<Colour>(ToString(c)), c);
  }
  EXPECT_EQ(ToString(Colour::kGreen), "green");
  static_assert(ToString(Colour::kBlue) == "blue");
  static_assert(ParseEnum<Colour>("red") == Colour::kRed);
}

TEST(EnumNames, ParsingIsExactAndRefusesAnythingElse) {
  EXPECT_FALSE(ParseEnum<Colour>("Red"));
  EXPECT_FALSE(ParseEnum<Colour>(" red"));
  EXPECT_FALSE(ParseEnum<Colour>(""));
  EXPECT_FALSE(ParseEnum<Colour>("redd"));
}

TEST(EnumNames, ChoicesReadLikeASentence) {
  EXPECT_EQ(EnumChoices<Single>(), "only");
  EXPECT_EQ(EnumChoices<Pair>(), "a or b");
  EXPECT_EQ(EnumChoices<Colour>(), "red, green or blue");
}

TEST(EnumNamesDeathTest, AValueMissingFromTheTableIsABrokenInvariant) {
  EXPECT_DEATH((void)ToString(static_cast<Colour>(7)), "unreachable");
}

}  // namespace
}  // namespace gesweep
