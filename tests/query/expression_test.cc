// The --where language on a catalogue without an archive (tests/fuzz/where_contract.h's, shaped like
// a real one): the depth limits (the issue's crashing inputs refused in one line), `%` against
// Python's and NumPy's floored remainder worked by hand, `in`, `contains` and `matches` against
// selections written out by hand, column wildcards, and every input the fuzzer ever kept
// (tests/query/where_regressions/) replayed against the fuzz contract.
#include "engine/query/expression.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "engine/common/errors.h"
#include "engine/query/run_columns.h"
#include "tests/fuzz/where_contract.h"

namespace gesweep {
namespace {

// An error message echoes a long expression by its start only: a refusal of a 125,000-character
// expression stays a short line.
constexpr std::size_t kLongestMessage = 400;

std::string Repeat(const std::string& piece, int times) {
  std::string text;
  text.reserve(piece.size() * static_cast<std::size_t>(times));
  for (int i = 0; i < times; ++i) text += piece;
  return text;
}

class ExpressionTest : public ::testing::Test {
 protected:
  ExpressionTest() : catalog_(testing::WhereFuzzCatalog()) {}

  std::string Error(const std::string& where) const {
    try {
      RowFilter::Parse(where, catalog_);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }

  // The rows (of `values`) that `where` keeps.
  std::vector<int> Rows(const std::string& where, const std::vector<ColumnValues>& values,
                        std::int64_t n) const {
    const RowFilter filter = RowFilter::Parse(where, catalog_);
    std::vector<char> keep;
    filter.Evaluate(values, n, keep);
    std::vector<int> rows;
    for (std::size_t i = 0; i < keep.size(); ++i) {
      if (keep[i]) rows.push_back(static_cast<int>(i));
    }
    return rows;
  }

  // A block where column `name` holds `numbers` (or `texts`) and every other column zeros/empty.
  std::vector<ColumnValues> Block(const std::string& name, const std::vector<double>& numbers,
                                  const std::vector<std::string>& texts = {}) const {
    const std::size_t n = std::max(numbers.size(), texts.size());
    std::vector<ColumnValues> values(catalog_.columns().size());
    for (std::size_t c = 0; c < values.size(); ++c) {
      values[c].numbers.assign(n, 0.0);
      values[c].texts.assign(n, "");
      values[c].unsigned_values.assign(n, 0);
    }
    const int c = catalog_.Require(name, "test", "column");
    if (!numbers.empty()) values[static_cast<std::size_t>(c)].numbers = numbers;
    if (!texts.empty()) values[static_cast<std::size_t>(c)].texts = texts;
    return values;
  }

  ColumnCatalog catalog_;
};

TEST_F(ExpressionTest, TheIssuesCrashingInputsAreRefusedInOneShortLine) {
  // Issue 13 §4: these crashed `query` with SIGSEGV (stack overflow).
  const std::vector<std::string> inputs = {
      Repeat("(", 10000) + "height_m < 3" + Repeat(")", 10000),
      Repeat("abs(", 25000) + "height_m" + Repeat(")", 25000) + " < 3",
      Repeat("-", 120000) + "height_m < 3",
      Repeat("not ", 30000) + "stable",
  };
  for (const std::string& input : inputs) {
    const std::string message = Error(input);
    EXPECT_NE(message.find("nested deeper than 256 levels"), std::string::npos) << message.substr(0, 200);
    EXPECT_TRUE(testing::OneLine(message));
    EXPECT_LT(message.size(), kLongestMessage) << message;
    EXPECT_NE(message.find(std::to_string(input.size()) + " characters"), std::string::npos) << message;
  }
}

TEST_F(ExpressionTest, NestingIsAllowedUpTo256LevelsAndRefusedAt257) {
  for (const char* open : {"(", "abs(", "-"}) {
    const bool call = std::string(open) != "-";
    auto nested = [&](int levels) {
      return Repeat(open, levels) + "height_m" + (call ? Repeat(")", levels) : "") + " < 3";
    };
    EXPECT_EQ(Error(nested(256)), "") << open;
    EXPECT_NE(Error(nested(257)).find("nested deeper than 256"), std::string::npos) << open;
  }
  // The refusal names the column of the first operator past the limit.
  EXPECT_NE(Error(Repeat("(", 300) + "x").find("at column 257:"), std::string::npos);
}

TEST_F(ExpressionTest, LongChainsAreBoundedByTheTreeHeight) {
  // 1023 "or"s make a tree 1024 levels high (each comparison node 2 levels under its or): refused
  // well before; a chain of 500 comparisons (height 501) passes.
  auto chain = [](int terms) {
    std::string text = "height_m < 0";
    for (int i = 1; i < terms; ++i) text += " or height_m < " + std::to_string(i);
    return text;
  };
  EXPECT_EQ(Error(chain(500)), "");
  const std::string refused = Error(chain(100000));
  EXPECT_NE(refused.find("more than 1024 levels of operators"), std::string::npos) << refused.substr(0, 300);
  EXPECT_LT(refused.size(), kLongestMessage);
  EXPECT_NE(Error(Repeat("height_m + ", 5000) + "1 < 2").find("levels of operators"), std::string::npos);
}

TEST_F(ExpressionTest, RemainderHasTheSignOfTheDivisorAsInPythonAndNumPy) {
  // Python: 7 % 3 = 1, -7 % 3 = 2, 7 % -3 = -2, -7 % -3 = -1, 7.5 % 2 = 1.5, x % 0 = nan.
  const std::vector<double> x = {7, -7, 7, -7, 7.5, 7};
  const std::vector<double> m = {3, 3, -3, -3, 2, 0};
  std::vector<ColumnValues> values = Block("height_m", x);
  values[static_cast<std::size_t>(*catalog_.Find("speed_mps"))].numbers = m;
  EXPECT_EQ(Rows("height_m % speed_mps == 1", values, 6), (std::vector<int>{0}));
  EXPECT_EQ(Rows("height_m % speed_mps == 2", values, 6), (std::vector<int>{1}));
  EXPECT_EQ(Rows("height_m % speed_mps == -2", values, 6), (std::vector<int>{2}));
  EXPECT_EQ(Rows("height_m % speed_mps == -1", values, 6), (std::vector<int>{3}));
  EXPECT_EQ(Rows("height_m % speed_mps == 1.5", values, 6), (std::vector<int>{4}));
  EXPECT_EQ(Rows("isnan(height_m % speed_mps)", values, 6), (std::vector<int>{5}));
  // Same precedence as * and /: 2 + 7 % 3 * 2 = 2 + ((7 % 3) * 2) = 4.
  EXPECT_EQ(Rows("2 + height_m % 3 * 2 == 4", Block("height_m", {7}), 1), (std::vector<int>{0}));
}

TEST_F(ExpressionTest, InListsNumbersLevelsAndTexts) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<ColumnValues> speeds = Block("speed_mps", {28, 32.0208, 45, nan, -1, 60});
  EXPECT_EQ(Rows("speed_mps in (32.0208, 60, -1)", speeds, 6), (std::vector<int>{1, 4, 5}));
  EXPECT_EQ(Rows("speed_mps in (28)", speeds, 6), (std::vector<int>{0}));
  // A missing value is in no list (as == fails for it), so "not in" every one (as != holds).
  EXPECT_EQ(Rows("speed_mps in (nan, 45)", speeds, 6), (std::vector<int>{2}));
  EXPECT_EQ(Rows("speed_mps not in (28, 45)", speeds, 6), (std::vector<int>{1, 3, 4, 5}));
  EXPECT_EQ(Rows("speed_mps % 2 in (0, 1)", speeds, 6), (std::vector<int>{0, 2, 4, 5}));
  // Levels by name or code; texts by string.
  const std::vector<ColumnValues> status = Block("status", {0, 1, 2, 1});
  EXPECT_EQ(Rows("status in (\"ok\", \"failed\")", status, 4), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(Rows("status not in ('ok')", status, 4), (std::vector<int>{0, 2}));
  EXPECT_EQ(Rows("status in (2)", status, 4), (std::vector<int>{2}));
  const std::vector<ColumnValues> texts = Block("message", {}, {"", "a", "b", "a b"});
  EXPECT_EQ(Rows("message in (\"a\", \"\")", texts, 4), (std::vector<int>{0, 1}));
  // Refusals name the place.
  EXPECT_NE(Error("status in (\"okay\")").find("at column 12: \"okay\" is not a level of status"),
            std::string::npos);
  EXPECT_NE(Error("speed_mps in (\"a\")").find("is a string but speed_mps is a number"), std::string::npos);
  EXPECT_NE(Error("message in (1)").find("message is text"), std::string::npos);
  EXPECT_NE(Error("speed_mps in (height_m)").find("holds numbers or \"strings\""), std::string::npos);
  EXPECT_NE(Error("speed_mps in 28").find("expected '(' after in"), std::string::npos);
  EXPECT_NE(Error("speed_mps in (28").find("expected ',' or ')'"), std::string::npos);
  EXPECT_NE(Error("in (1)").find("'in' needs a column before it"), std::string::npos);
}

TEST_F(ExpressionTest, ContainsAndMatchesOnMessagesAndLevels) {
  const std::vector<std::string> messages = {"", "boundary: none (stable at every height)",
                                             "LQR: the Riccati equation has no stabilising solution",
                                             "boundary: found", "lqr lower case"};
  const std::vector<ColumnValues> values = Block("message", {}, messages);
  EXPECT_EQ(Rows("message contains \"LQR\"", values, 5), (std::vector<int>{2}));
  EXPECT_EQ(Rows("message not contains 'boundary'", values, 5), (std::vector<int>{0, 2, 4}));
  EXPECT_EQ(Rows("message contains \"\"", values, 5), (std::vector<int>{0, 1, 2, 3, 4}));
  EXPECT_EQ(Rows("message matches \"^boundary: (none|found)\"", values, 5), (std::vector<int>{1, 3}));
  EXPECT_EQ(Rows("message matches \"(?i)^lqr\"", values, 5), (std::vector<int>{2, 4}));
  EXPECT_EQ(Rows("message matches \"^$\"", values, 5), (std::vector<int>{0}));
  EXPECT_EQ(Rows("message not matches \"Riccati|found\"", values, 5), (std::vector<int>{0, 1, 4}));
  // On a level column: the levels whose names match (time_limit, touchdown, diverged).
  const std::vector<ColumnValues> events = Block("end_event", {0, 1, 2, 1});
  EXPECT_EQ(Rows("end_event contains \"d\"", events, 4), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(Rows("end_event matches \"^t\"", events, 4), (std::vector<int>{0, 1, 3}));
  EXPECT_EQ(Rows("end_event not matches \"n$\"", events, 4), (std::vector<int>{0, 2}));
  // Refusals.
  EXPECT_NE(Error("message matches \"(\"").find("at column 17: not a regular expression (RE2 syntax)"),
            std::string::npos)
      << Error("message matches \"(\"");
  EXPECT_NE(Error("height_m contains \"1\"").find("height_m is a number"), std::string::npos);
  EXPECT_NE(Error("message contains 3").find("expected a \"string\" after contains"), std::string::npos);
}

TEST_F(ExpressionTest, ColumnWildcardsExpandInNaturalOrder) {
  auto names = [&](const std::string& pattern) {
    std::string text;
    for (int c : catalog_.Expand(pattern, "command line", "--columns"))
      text += (text.empty() ? "" : ",") + catalog_.column(c).path;
    return text;
  };
  EXPECT_EQ(names("phugoid/*"), "results/modes/phugoid/damping_ratio");
  EXPECT_EQ(names("*/damping_ratio"),
            "results/modes/phugoid/damping_ratio,results/modes/short_period/damping_ratio");
  EXPECT_EQ(names("/design/*"), "design/cdh,design/h_derivatives,design/height_m,design/speed_mps");
  EXPECT_EQ(names("*height_over_span"), "results/boundary/height_over_span,results/modes/height_over_span");
  // "*": index, the design in design order, status, the results, then the other runs/ columns.
  const std::vector<int> all = catalog_.Expand("*", "command line", "--columns");
  ASSERT_EQ(all.size(), catalog_.columns().size());
  EXPECT_EQ(catalog_.column(all[0]).path, "runs/index");
  EXPECT_EQ(catalog_.column(all[5]).path, "runs/status");
  EXPECT_EQ(catalog_.column(all.back()).path, "runs/message");
  // A plain name is one column; a pattern that matches nothing is refused.
  EXPECT_EQ(names("height_m"), "design/height_m");
  try {
    catalog_.Expand("phugiod/*", "command line", "--columns");
    ADD_FAILURE() << "no refusal";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--columns = phugiod/*: the pattern matches no column"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(ExpressionTest, EveryKeptFuzzInputKeepsTheContract) {
  std::int64_t rows = 0;
  const std::vector<ColumnValues> values = testing::WhereFuzzValues(catalog_, &rows);
  const std::filesystem::path folder =
      std::filesystem::path(GESWEEP_SOURCE_DIR) / "tests/query/where_regressions";
  int cases = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.path().extension() != ".txt") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    ++cases;
    testing::CheckWhereContract(
        text.str(), catalog_, values, rows, [&](const char* what, const std::string& detail) {
          ADD_FAILURE() << entry.path().filename() << ": " << what << ": " << detail.substr(0, 300);
          throw std::runtime_error(what);
        });
  }
  EXPECT_GT(cases, 0) << "no regression inputs in " << folder;
  // And the seeds of the fuzz corpus, which must all parse.
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(GESWEEP_SOURCE_DIR) /
                                                               "tests/fuzz/where_corpus")) {
    std::ifstream in(entry.path(), std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    EXPECT_TRUE(testing::CheckWhereContract(text.str(), catalog_, values, rows,
                                            [&](const char* what, const std::string& detail) {
                                              ADD_FAILURE() << entry.path().filename() << ": " << what << ": "
                                                            << detail.substr(0, 300);
                                              throw std::runtime_error(what);
                                            }))
        << entry.path().filename() << ": " << Error(text.str());
  }
}

}  // namespace
}  // namespace gesweep
