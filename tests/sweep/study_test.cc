// Study files: a valid study parses into the design and analyses it describes; a bad one is
// refused before anything runs, with the file, key, value, expectation and line.
#include "engine/sweep/study.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "engine/common/errors.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep {
namespace {

const std::string kAircraft = std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml";

class StudyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("gesweep_study_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                  "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  std::filesystem::path Write(const std::string& name, const std::string& text) {
    const auto path = directory_ / name;
    std::ofstream(path) << text;
    return path;
  }
  std::string Header(const std::string& analyses = "[analyses.modes]\n") {
    return "format_version = 1\nname = \"t\"\naircraft = \"" + kAircraft + "\"\n" + analyses;
  }
  // The InputError of loading `text`, or fails the test.
  InputError ErrorOf(const std::string& text) {
    const auto path = Write("study.toml", text);
    try {
      Study study = LoadStudy(path);
      SweepPlan plan(std::move(study), ShardSpec{});
    } catch (const InputError& e) {
      return e;
    }
    ADD_FAILURE() << "expected an InputError for:\n" << text;
    return InputError("", "", "", "");
  }

  std::filesystem::path directory_;
};

TEST_F(StudyTest, ParsesAGridStudy) {
  const auto path = Write("grid.toml", Header() + R"(
[parameters]
speed_mps = 32.0208
scale.CLh = 1.1
[output]
compression_level = 6
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
linspace = [1.0, 3.0, 5]
[[design.parameter]]
name = "h_derivatives"
values = [true, false]
)");
  Study study = LoadStudy(path);
  EXPECT_EQ(study.name, "t");
  ASSERT_EQ(study.analyses.size(), 1u);
  EXPECT_EQ(study.analyses[0]->name(), "modes");
  ASSERT_TRUE(study.aircraft.has_value());
  EXPECT_EQ(study.compression_level, 6);
  ASSERT_EQ(study.fixed.size(), 2u);
  EXPECT_EQ(study.design.kind, DesignKind::kGrid);
  ASSERT_EQ(study.design.parameters.size(), 2u);
  EXPECT_EQ(study.design.parameters[0].values, (std::vector<double>{1.0, 1.5, 2.0, 2.5, 3.0}));
  EXPECT_EQ(study.design.parameters[1].values, (std::vector<double>{1.0, 0.0}));
  SweepPlan plan(std::move(study), ShardSpec{});
  EXPECT_EQ(plan.design_runs(), 10);
  EXPECT_EQ(plan.base_parameters()[static_cast<std::size_t>(RequireParameter("scale.CLh"))], 1.1);
  EXPECT_EQ(plan.base_parameters()[static_cast<std::size_t>(RequireParameter("mass_kg"))], 182.055);
}

TEST_F(StudyTest, ParsesAMonteCarloStudyAndChecksEachDistributionsReach) {
  const auto path = Write("mc.toml", Header() + R"(
[design]
kind = "monte_carlo"
samples = 500
seed = 9
[[design.parameter]]
name = "speed_mps"
normal = [40.0, 2.0]
[[design.parameter]]
name = "height_m"
truncated_normal = [2.0, 1.0, 1.0, 5.0]
[[design.parameter]]
name = "mass_kg"
lognormal = [3.4, 0.1]
[[design.parameter]]
name = "scale.CLh"
uniform = [0.9, 1.1]
[[design.parameter]]
name = "cdh"
values = ["polar", "zero"]
weights = [3, 1]
[[design.parameter]]
name = "h_derivatives"
values = [true]
)");
  const Study study = LoadStudy(path);
  const DesignSpec& spec = study.design;
  ASSERT_EQ(spec.kind, DesignKind::kMonteCarlo);
  EXPECT_EQ(spec.samples, 500);
  EXPECT_EQ(spec.seed, 9u);
  ASSERT_EQ(spec.parameters.size(), 6u);
  // The reach of a normal: mean ± sigma·Φ⁻¹(2⁻⁵³), Φ⁻¹(2⁻⁵³) = −8.209536151601387 (scipy.stats.norm.ppf).
  constexpr double kZReach = 8.209536151601387;
  constexpr double kQuantileRelative = 1e-13;  // Boost's and SciPy's normal quantiles agree to a few ulps
  EXPECT_EQ(spec.parameters[0].distribution, Distribution::kNormal);
  EXPECT_NEAR(spec.parameters[0].lower, 40 - 2 * kZReach, 40 * kQuantileRelative);
  EXPECT_NEAR(spec.parameters[0].upper, 40 + 2 * kZReach, 40 * kQuantileRelative);
  // A truncated normal reaches its bounds (to within the 2⁻⁵³ of probability left out at each end).
  constexpr double kTruncationReach = 1e-9;  // 2⁻⁵³ of the interval's mass over the density at an end
  EXPECT_NEAR(spec.parameters[1].lower, 1.0, kTruncationReach);
  EXPECT_NEAR(spec.parameters[1].upper, 5.0, kTruncationReach);
  EXPECT_NEAR(spec.parameters[2].upper, std::exp(3.4 + 0.1 * kZReach), 50 * kQuantileRelative);
  EXPECT_EQ(spec.parameters[3].lower, 0.9);  // uniform: its bounds
  EXPECT_EQ(spec.parameters[4].distribution, Distribution::kDiscrete);
  EXPECT_EQ(spec.parameters[4].values, (std::vector<double>{0, 1}));  // level indices
  EXPECT_EQ(spec.parameters[4].weights, (std::vector<double>{3, 1}));
  EXPECT_EQ(spec.parameters[5].weights, (std::vector<double>{1}));  // default: equal weights
  EXPECT_EQ(DescribeDistribution(spec.parameters[4]), "discrete(polar:3, zero:1)");
  EXPECT_EQ(DescribeDistribution(spec.parameters[0]), "normal(mean=40, sigma=2)");
}

TEST_F(StudyTest, MonteCarloRefusesADistributionThatReachesOutsideTheParameter) {
  // height_m ~ N(1.5, 0.3) reaches 1.5 − 8.21·0.3 = −0.96 m, under the wheels.
  const InputError e = ErrorOf(Header() + R"(
[design]
kind = "monte_carlo"
samples = 10
seed = 1
[[design.parameter]]
name = "height_m"
normal = [1.5, 0.3]
)");
  EXPECT_EQ(e.key(), "design.parameter[0].normal");
  EXPECT_NE(e.expected().find("the distribution reaches"), std::string::npos) << e.expected();
  EXPECT_NE(e.expected().find("truncated_normal"), std::string::npos) << e.expected();
}

TEST_F(StudyTest, FingerprintIgnoresCommentsButNotValues) {
  const std::string body = R"(
[parameters]
speed_mps = 32.0
height_m = 2.0
)";
  const auto a = LoadStudy(Write("a.toml", Header() + body)).fingerprint;
  const auto b = LoadStudy(Write("b.toml", "# a comment\n" + Header() + body + "\n# another\n")).fingerprint;
  const auto c = LoadStudy(Write("c.toml", Header() + R"(
[parameters]
speed_mps = 32.5
height_m = 2.0
)"))
                     .fingerprint;
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST_F(StudyTest, ListDesignFromCsv) {
  Write("runs.csv", "# heights and speeds\nheight_m, speed_mps, cdh\n1.0, 30, polar\n2.5, 40, zero\n");
  Study study = LoadStudy(Write("list.toml", Header() + R"(
[design]
kind = "list"
csv = "runs.csv"
)"));
  ASSERT_EQ(study.design.list_rows, 2);
  EXPECT_EQ(study.design.list_values, (std::vector<double>{1.0, 30, 0, 2.5, 40, 1}));
}

TEST_F(StudyTest, CsvErrorsNameTheCsvLine) {
  Write("runs.csv", "height_m,speed_mps\n1.0,30\n0.5,30\n");
  const InputError e = ErrorOf(Header() + "[design]\nkind = \"list\"\ncsv = \"runs.csv\"\n");
  EXPECT_NE(e.source().find("runs.csv"), std::string::npos);
  EXPECT_EQ(e.line(), 3);
  EXPECT_NE(e.expected().find("wheel-contact"), std::string::npos);
}

TEST_F(StudyTest, UnknownKeySuggestsTheNearOne) {
  const InputError e = ErrorOf(Header() + "[output]\ntime_serie = true\n");
  EXPECT_EQ(e.key(), "output.time_serie");
  EXPECT_NE(e.expected().find("did you mean 'time_series'"), std::string::npos);
  EXPECT_EQ(e.line(), 6);
}

TEST_F(StudyTest, UnknownParameterSuggestsTheNearOne) {
  const InputError e = ErrorOf(Header() + "[parameters]\nspeed_mps = 30\nheigth_m = 2\n");
  EXPECT_NE(e.expected().find("did you mean 'height_m'"), std::string::npos);
  EXPECT_EQ(e.line(), 7);
}

TEST_F(StudyTest, UnknownAnalysisSuggestsTheNearOne) {
  const InputError e = ErrorOf(Header("[analyses.mode]\n") + "[parameters]\nspeed_mps = 30\nheight_m = 2\n");
  EXPECT_NE(e.expected().find("did you mean 'modes'"), std::string::npos);
}

TEST_F(StudyTest, WrongTypeNamesKeyValueAndLine) {
  const InputError e = ErrorOf(Header() + "[parameters]\nspeed_mps = \"fast\"\nheight_m = 2\n");
  EXPECT_EQ(e.key(), "parameters.speed_mps");
  EXPECT_EQ(e.value(), "\"fast\"");
  EXPECT_EQ(e.line(), 6);
  EXPECT_NE(std::string(e.what()).find("study.toml:6"), std::string::npos);
}

TEST_F(StudyTest, StartHeightUnderWheelContactIsRefused) {
  const InputError e = ErrorOf(Header() + "[parameters]\nspeed_mps = 30\nheight_m = 0.5\n");
  EXPECT_NE(e.expected().find("wheel-contact height 0.788"), std::string::npos);
}

TEST_F(StudyTest, NegativeAndZeroValuesAreRefused) {
  // The ranges of the limits table (engine/common/input_limits.h), the same as the CLI flags'.
  EXPECT_NE(
      ErrorOf(Header() + "[parameters]\nspeed_mps = 0\nheight_m = 2\n").expected().find("in [1, 300] m/s"),
      std::string::npos);
  EXPECT_NE(ErrorOf(Header() + "[parameters]\nspeed_mps = 30\nheight_m = 2\nmass_kg = -1\n")
                .expected()
                .find("in (0, 1000000] kg"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Header() + "[parameters]\nspeed_mps = nan\nheight_m = 2\n").expected().find("expected"),
            std::string::npos);
}

TEST_F(StudyTest, DuplicateAxisIsRefused) {
  const InputError e = ErrorOf(Header() + R"([parameters]
speed_mps = 30
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
values = [1, 2]
[[design.parameter]]
name = "height_m"
values = [3, 4]
)");
  EXPECT_NE(e.expected().find("duplicate"), std::string::npos);
  EXPECT_EQ(e.line(), 13);
}

TEST_F(StudyTest, FixedAndSweptAtOnceIsRefused) {
  const InputError e = ErrorOf(Header() + R"([parameters]
speed_mps = 30
height_m = 2
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
values = [1, 2]
)");
  EXPECT_NE(e.expected().find("both fixed"), std::string::npos);
}

TEST_F(StudyTest, ParameterNoAnalysisReadsIsRefused) {
  const InputError e =
      ErrorOf(Header() + "[parameters]\nspeed_mps = 30\nheight_m = 2\npulse_amplitude_deg = 5\n");
  EXPECT_NE(e.expected().find("no analysis of this study"), std::string::npos);
}

TEST_F(StudyTest, MissingRequiredParameterIsNamed) {
  const InputError e = ErrorOf(Header() + "[parameters]\nspeed_mps = 30\n");
  EXPECT_NE(e.expected().find("needs height_m"), std::string::npos);
}

TEST_F(StudyTest, ChoiceParametersCannotBeSampled) {
  const InputError e = ErrorOf(Header() + R"([parameters]
speed_mps = 30
height_m = 2
[design]
kind = "lhs"
samples = 10
seed = 1
[[design.parameter]]
name = "cdh"
uniform = [0, 1]
)");
  EXPECT_NE(e.expected().find("real-valued"), std::string::npos);
}

TEST_F(StudyTest, AbsurdGridIsRefusedQuotingTheStorageEstimate) {
  // 10^4 × 10^4 × 10^4 = 10^12 runs of modes: hundreds of terabytes.
  const InputError e = ErrorOf(Header() + R"([parameters]
speed_mps = 30
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
linspace = [1, 10, 10000]
[[design.parameter]]
name = "scale.CLh"
linspace = [0.5, 1.5, 10000]
[[design.parameter]]
name = "scale.CMh"
linspace = [0.5, 1.5, 10000]
)");
  EXPECT_NE(e.expected().find("refusing it: the archive would need about"), std::string::npos);
  EXPECT_NE(e.expected().find(" TB before compression"), std::string::npos) << e.what();
  EXPECT_EQ(e.line(), 7);
}

TEST_F(StudyTest, EmptyGridAxisIsRefused) {
  const InputError e = ErrorOf(Header() + R"([parameters]
speed_mps = 30
[design]
kind = "grid"
[[design.parameter]]
name = "height_m"
values = []
)");
  EXPECT_NE(e.expected().find("non-empty"), std::string::npos);
}

TEST_F(StudyTest, StudyNamingItselfAsAircraftIsRefused) {
  const auto path = Write("self.toml", "format_version = 1\naircraft = \"self.toml\"\n[analyses.modes]\n");
  try {
    LoadStudy(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(e.expected().find("not this study file itself"), std::string::npos);
  }
}

TEST_F(StudyTest, MissingAircraftFileIsNamed) {
  const auto path = Write("s.toml", "format_version = 1\naircraft = \"nowhere.toml\"\n[analyses.modes]\n");
  try {
    LoadStudy(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "aircraft");
    EXPECT_NE(std::string(e.what()).find("nowhere.toml"), std::string::npos);
  }
}

TEST_F(StudyTest, VerificationStudyNeedsNoAircraft) {
  Study study = LoadStudy(Write("ishigami.toml", R"(format_version = 1
[analyses.ishigami]
[design]
kind = "sobol"
base_samples = 8
second_order = true
[[design.parameter]]
name = "x1"
uniform = [-3.141592653589793, 3.141592653589793]
[[design.parameter]]
name = "x2"
uniform = [-3.141592653589793, 3.141592653589793]
[[design.parameter]]
name = "x3"
uniform = [-3.141592653589793, 3.141592653589793]
)"));
  EXPECT_FALSE(study.aircraft.has_value());
  SweepPlan plan(std::move(study), ShardSpec{});
  EXPECT_EQ(plan.design_runs(), 8 * (2 * 3 + 2));
}

TEST_F(StudyTest, OpenLoopRefusesADesignThatStartsAtStall) {
  const InputError e = ErrorOf(Header("[analyses.open_loop]\n") + R"([parameters]
height_m = 3.0
[design]
kind = "grid"
[[design.parameter]]
name = "speed_mps"
linspace = [24.6314, 40.0, 5]
)");
  EXPECT_NE(
      e.expected().find("analysis 'open_loop' cannot run it: expected speed_mps > the stall speed 24.6314"),
      std::string::npos)
      << e.what();
  EXPECT_NE(e.value().find("speed_mps = 24.6314"), std::string::npos) << e.what();
}

TEST(ShardSpec, ParsesAndSplitsContiguously) {
  EXPECT_THROW(ParseShard("3/3", "--shard"), InputError);
  EXPECT_THROW(ParseShard("1", "--shard"), InputError);
  EXPECT_THROW(ParseShard("-1/3", "--shard"), InputError);
  const ShardSpec shard = ParseShard("1/3", "--shard");
  EXPECT_EQ(shard.index, 1);
  EXPECT_EQ(shard.count, 3);
  // Every run in exactly one shard, in order; every shard starts at a batch boundary (so its chunks
  // coincide with the merged archive's) and shards differ by at most one batch.
  for (std::int64_t runs : {1, 2, 10, 1000, 1001, 10000}) {
    for (int batch : {1, 7, 64, 4096}) {
      for (int count : {1, 2, 3, 7}) {
        if (count > runs) continue;
        const std::int64_t b = ShardBatchRuns(runs, batch, count);
        EXPECT_GE(b, 1);
        EXPECT_LE(b, batch);
        EXPECT_LE(b * count, runs);  // at least one batch per shard
        std::int64_t next = 0, smallest = runs, largest = 0;
        for (int i = 0; i < count; ++i) {
          std::int64_t first = 0, n = 0;
          ShardRange(runs, batch, ShardSpec{i, count}, &first, &n);
          EXPECT_EQ(first, next);
          EXPECT_EQ(first % b, 0) << runs << " runs, batch " << batch << ", shard " << i << "/" << count;
          EXPECT_GE(n, 1);
          if (first + n < runs) {
            smallest = std::min(smallest, n);
            largest = std::max(largest, n);
          }
          next = first + n;
        }
        EXPECT_EQ(next, runs);
        if (largest > 0) {
          EXPECT_LE(largest - smallest, b);
        }
      }
    }
  }
}

}  // namespace
}  // namespace gesweep
