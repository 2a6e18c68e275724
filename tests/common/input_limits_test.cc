// The one table of limits (engine/common/input_limits.h): every entry well formed, and the checks.
#include "engine/common/input_limits.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

TEST(InputLimits, EveryEntryHasAUniqueNameUnitsAnIntervalAndAReason) {
  std::set<std::string_view> names;
  for (const InputLimit& limit : InputLimits()) {
    EXPECT_TRUE(names.insert(limit.name).second) << limit.name << " twice";
    EXPECT_FALSE(limit.units.empty()) << limit.name;
    EXPECT_FALSE(limit.reason.empty()) << limit.name;
    EXPECT_EQ(limit.reason.find('\n'), std::string_view::npos) << limit.name << ": the reason is one line";
    EXPECT_TRUE(std::isfinite(limit.minimum) && std::isfinite(limit.maximum)) << limit.name;
    EXPECT_LT(limit.minimum, limit.maximum) << limit.name;
    // Every bound is far inside a double's range, so no value near it overflows in arithmetic.
    EXPECT_LT(std::abs(limit.maximum), 1e100) << limit.name;
  }
}

TEST(InputLimits, BoundsAreInclusiveOrExclusiveAsWritten) {
  const InputLimit& speed = RequireInputLimit("speed_mps");  // [1, 300]
  EXPECT_TRUE(WithinLimit(speed, 1.0));
  EXPECT_TRUE(WithinLimit(speed, 300.0));
  EXPECT_FALSE(WithinLimit(speed, std::nextafter(1.0, 0.0)));
  EXPECT_FALSE(WithinLimit(speed, std::nextafter(300.0, 1e9)));
  const InputLimit& height = RequireInputLimit("height_m");  // (0, 11000]
  EXPECT_FALSE(WithinLimit(height, 0.0));
  EXPECT_TRUE(WithinLimit(height, 1e-300));  // positive: the wheel-contact height is a further bound
  EXPECT_TRUE(WithinLimit(height, 11000.0));
}

TEST(InputLimits, RefusesTheValuesOfTheIssue) {
  // modes --speed-mps 1e308 and 1e-300 printed sigma = nan and -inf; simulate --height-m 1e308.
  for (double bad : {1e308, 1e-300, 0.0, -5.0}) {
    EXPECT_FALSE(WithinLimit(RequireInputLimit("speed_mps"), bad)) << bad;
  }
  EXPECT_FALSE(WithinLimit(RequireInputLimit("height_m"), 1e308));
  EXPECT_FALSE(WithinLimit(RequireInputLimit("pulse_amplitude_deg"), 1e308));
}

TEST(InputLimits, NonFiniteValuesAreRefusedUnlessInfinityIsAllowed) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(WithinLimit(RequireInputLimit("height_m"), inf));
  EXPECT_FALSE(WithinLimit(RequireInputLimit("height_m"), std::nan("")));
  EXPECT_TRUE(WithinLimit(RequireInputLimit("landing.design_height_m"), inf));
  EXPECT_FALSE(WithinLimit(RequireInputLimit("landing.design_height_m"), -inf));
  EXPECT_FALSE(WithinLimit(RequireInputLimit("landing.design_height_m"), std::nan("")));
}

TEST(InputLimits, ProblemNamesTheRangeTheUnitsAndTheReason) {
  const InputLimit& speed = RequireInputLimit("speed_mps");
  EXPECT_EQ(LimitProblem(speed, 32.0), "");
  const std::string problem = LimitProblem(speed, 1e308);
  EXPECT_NE(problem.find("expected a number in [1, 300] m/s ("), std::string::npos) << problem;
  EXPECT_NE(problem.find(speed.reason), std::string::npos) << problem;
  EXPECT_EQ(DescribeLimit(RequireInputLimit("landing.design_height_m")), "a number in (0, 11000] m, or inf");
}

TEST(InputLimits, CheckThrowsOneLineNamingKeyAndValue) {
  try {
    CheckInputLimit("speed_mps", 1e-300, "command line", "--speed-mps");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    const std::string text = e.what();
    EXPECT_EQ(text.rfind("command line: --speed-mps = 1e-300: expected a number in [1, 300] m/s", 0), 0u)
        << text;
  }
  EXPECT_NO_THROW(CheckInputLimit("speed_mps", 32.0, "command line", "--speed-mps"));
}

TEST(StepCount, RefusesMoreThanTheLimitNamingBothValues) {
  EXPECT_NO_THROW(CheckStepCount(300.0, 0.015, "s.toml", "duration_s", "step_s"));  // 20,000 steps
  EXPECT_NO_THROW(CheckStepCount(1e5, 1e-3, "s.toml", "duration_s", "step_s"));     // exactly 1e8
  try {
    CheckStepCount(30.0, 1e-9, "s.toml", "duration_s", "step_s");  // the issue's step_s = 1e-9
    FAIL() << "no exception";
  } catch (const InputError& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("step_s = 1e-09"), std::string::npos) << text;
    EXPECT_NE(text.find("duration_s = 30 s"), std::string::npos) << text;
    EXPECT_NE(text.find("3e+10 steps"), std::string::npos) << text;
    EXPECT_NE(text.find("at most 100000000 integration steps"), std::string::npos) << text;
  }
  // Nothing to bound: an adaptive method without a largest step.
  EXPECT_NO_THROW(CheckStepCount(1e5, 0.0, "s.toml", "duration_s", "max_step_s"));
}

// Whole numbers (issue 26, item 3): digits only, compared as integers, never through a double.
TEST(ExactInteger, TakesDigitsWithinTheRangeExactly) {
  EXPECT_EQ(ParseExactInteger("0", "seed", "command line", "--seed"), 0u);
  EXPECT_EQ(ParseExactInteger("9007199254740992", "seed", "command line", "--seed"), 9007199254740992u);
  EXPECT_EQ(ParseExactInteger("9007199254740991", "seed", "command line", "--seed"), 9007199254740991u);
  EXPECT_EQ(ParseExactInteger("000000000000000000000042", "seed", "command line", "--seed"), 42u);
  EXPECT_EQ(ParseExactInteger("4096", "threads", "command line", "--threads"), 4096u);
}

TEST(ExactInteger, RefusesEverythingElseNamingTheRange) {
  const std::string range = "expected a whole number in [0, 9007199254740992]";
  // 2^53 + 1 rounds to 2^53 as a double; 2^64 and 2^64 + 1 wrap or clamp in a uint64.
  for (const char* text :
       {"9007199254740993", "18446744073709551616", "18446744073709551617", "99999999999999999999999999999",
        "-1", "+5", "1.5", "1e3", "5.0", "0x10", " 7", "7 ", "", "-0"}) {
    try {
      ParseExactInteger(text, "seed", "command line", "--seed");
      ADD_FAILURE() << "took '" << text << "'";
    } catch (const InputError& e) {
      const std::string line = e.what();
      EXPECT_EQ(line.rfind("command line: --seed", 0), 0u) << line;
      EXPECT_NE(line.find(range), std::string::npos) << line;
    }
  }
  EXPECT_THROW(ParseExactInteger("0", "threads", "command line", "--threads"), InputError);  // [1, 4096]
  EXPECT_THROW(ParseExactInteger("4097", "threads", "command line", "--threads"), InputError);
}

TEST(ExactInteger, WholeEntriesRefuseFractionsAndSayWhole) {
  const InputLimit& seed = RequireInputLimit("seed");
  EXPECT_TRUE(seed.whole);
  EXPECT_TRUE(WithinLimit(seed, 9007199254740992.0));
  EXPECT_FALSE(WithinLimit(seed, 1.5));
  EXPECT_FALSE(WithinLimit(seed, -1.0));
  EXPECT_EQ(DescribeLimit(seed), "a whole number in [0, 9007199254740992]");
  EXPECT_EQ(DescribeLimit(RequireInputLimit("run_index")), "a whole number in [0, 9007199254740992]");
}

// Issue 26, item 5: a turbulent run's noise table bounded before it is built.
TEST(NoiseSamples, RefusesMoreThanTheLimitNamingTheNumbersAndTheMemory) {
  EXPECT_EQ(NoiseSampleCount(1e5, 0.01), 1e7);
  EXPECT_EQ(NoiseSampleCount(0.0, 0.01), 0.0);
  EXPECT_EQ(NoiseSampleCount(1e5, 0.0), 0.0);
  EXPECT_NO_THROW(CheckNoiseSamples(1e5, 0.01, "s.toml", "duration_s", "turbulence_sample_interval_s"));
  EXPECT_NO_THROW(CheckNoiseSamples(1000.0, 1e-4, "s.toml", "duration_s", "turbulence_sample_interval_s"));
  EXPECT_THROW(CheckNoiseSamples(1000.5, 1e-4, "s.toml", "duration_s", "turbulence_sample_interval_s"),
               InputError);
  try {
    CheckNoiseSamples(1e5, 1e-4, "s.toml", "duration_s", "turbulence_sample_interval_s");  // the issue's 1e9
    FAIL() << "no exception";
  } catch (const InputError& e) {
    const std::string text = e.what();
    EXPECT_EQ(e.key(), "turbulence_sample_interval_s");
    EXPECT_NE(text.find("duration_s = 100000 s"), std::string::npos) << text;
    EXPECT_NE(text.find("1000000000 samples"), std::string::npos) << text;
    EXPECT_NE(text.find("about 32 GB"), std::string::npos) << text;  // 1e9 x 32 bytes
  }
}

TEST(RunMemory, RefusesMoreThanAGibibyteNamingTheBreakdown) {
  EXPECT_NO_THROW(CheckRunMemory(1073741824.0, "x", "s.toml", "output_dt_s", "1"));
  try {
    CheckRunMemory(9.6e9, "1e+08 series samples x 96 bytes", "s.toml", "output_dt_s", "1e-05");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("at most 1.07 GB of memory per run"), std::string::npos) << text;
    EXPECT_NE(text.find("1e+08 series samples x 96 bytes = about 9.6 GB"), std::string::npos) << text;
  }
  EXPECT_EQ(ApproximateBytes(3.2e10), "32 GB");
  EXPECT_EQ(ApproximateBytes(512), "512 bytes");
}

}  // namespace
}  // namespace gesweep
