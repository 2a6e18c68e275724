// The one number formatter and the one escaping of a person's text in messages (engine/common/errors.h).
#include "engine/common/errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace gesweep {
namespace {

TEST(ShortNumber, WritesSmallAndLargeNumbersInScientificForm) {
  EXPECT_EQ(ShortNumber(1e-10), "1e-10");  // std::to_string gave "0.000000"
  EXPECT_EQ(ShortNumber(1e308), "1e+308");
  EXPECT_EQ(ShortNumber(0.015), "0.015");
  EXPECT_EQ(ShortNumber(32.0208), "32.0208");
  EXPECT_EQ(ShortNumber(-2.5), "-2.5");
  EXPECT_EQ(ShortNumber(0.1 + 0.2), "0.3");  // 10 significant digits, not the round-trip 17
}

TEST(ShortNumber, NamesNonFiniteValues) {
  EXPECT_EQ(ShortNumber(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(ShortNumber(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(ShortNumber(std::nan("")), "nan");
}

TEST(EscapeForMessage, LeavesPrintableTextAndValidUtf8Alone) {
  EXPECT_EQ(EscapeForMessage("height_m = 2.5: expected a number"), "height_m = 2.5: expected a number");
  EXPECT_EQ(EscapeForMessage("σ ≥ 0, Δθ, 日本, 🛩"), "σ ≥ 0, Δθ, 日本, 🛩");
  EXPECT_EQ(EscapeForMessage(""), "");
}

TEST(EscapeForMessage, EscapesControlCharacters) {
  EXPECT_EQ(EscapeForMessage("a\nb\r\tc"), "a\\nb\\r\\tc");
  EXPECT_EQ(EscapeForMessage("\x1b[2J\x1b[Hcleared"),
            "\\x1b[2J\\x1b[Hcleared");  // the ESC that cleared a terminal
  EXPECT_EQ(EscapeForMessage(std::string("nul\0byte", 8)), "nul\\x00byte");
  EXPECT_EQ(EscapeForMessage("del\x7f"), "del\\x7f");
  EXPECT_EQ(EscapeForMessage("csi\xc2\x9b"
                             "31m"),
            "csi\\u009b31m");  // U+009B, the 8-bit CSI
}

TEST(EscapeForMessage, EscapesEveryByteOfBrokenUtf8) {
  EXPECT_EQ(EscapeForMessage("\xce"), "\\xce");  // one byte of a two-byte character, alone
  EXPECT_EQ(EscapeForMessage("a\xce"
                             "b"),
            "a\\xceb");                                                     // a lead byte followed by ASCII
  EXPECT_EQ(EscapeForMessage("\x80\xbf"), "\\x80\\xbf");                    // stray continuation bytes
  EXPECT_EQ(EscapeForMessage("\xc0\xaf"), "\\xc0\\xaf");                    // an overlong '/'
  EXPECT_EQ(EscapeForMessage("\xed\xa0\x80"), "\\xed\\xa0\\x80");           // a UTF-16 surrogate
  EXPECT_EQ(EscapeForMessage("\xf4\x90\x80\x80"), "\\xf4\\x90\\x80\\x80");  // above U+10FFFF
  EXPECT_EQ(EscapeForMessage("\xe2\x89"), "\\xe2\\x89");  // a three-byte character cut short
}

TEST(EscapeForMessage, IsIdempotent) {
  const std::string once = EscapeForMessage("\x1b]0;title\x07\xff\n");
  EXPECT_EQ(EscapeForMessage(once), once);
}

TEST(InputError, MessageIsOnePrintableLine) {
  const InputError error("study\x1b[2J.toml", "key\nwith break", "\"\xce\"", "expected a number", 3);
  EXPECT_EQ(std::string(error.what()),
            "study\\x1b[2J.toml:3: key\\nwith break = \"\\xce\": expected a number");
  // The parts stay as the person wrote them, for code that matches on them.
  EXPECT_EQ(error.key(), "key\nwith break");
}

}  // namespace
}  // namespace gesweep
