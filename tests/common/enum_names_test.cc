// One names table per enum: printing, parsing and the choices of a message come from it.
#include "engine/common/enum_names.h"

#include <gtest/gtest.h>

namespace gesweep {

// Declared with the one-statement macro, as the engine's enums are.
enum class Colour { kRed, kGreen, kBlue };
GESWEEP_ENUM_NAMES(Colour, {kRed, "red"}, {kGreen, "green"}, {kBlue, "blue"});

enum class Single { kOnly };
GESWEEP_ENUM_NAMES(Single, {kOnly, "only"});

// Written out: the specialization the macro declares.
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

TEST(EnumNames, TheMacroKeepsTheTableInTheOrderGiven) {
  static_assert(std::size(EnumNames<Colour>::kTable) == 3);
  static_assert(EnumNames<Colour>::kTable[0].value == Colour::kRed);
  static_assert(EnumNames<Colour>::kTable[2].name == "blue");
  static_assert(std::size(EnumNames<Single>::kTable) == 1);
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
