#include "engine/estimators/sobol_indices.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "engine/common/errors.h"
#include "engine/estimators/ishigami.h"
#include "tests/estimators/production_designs.h"

namespace gesweep {
namespace {

using production_designs::DesignRows;
using production_designs::LayoutOf;

constexpr int kIshigamiBaseSamples = 1 << 13;  // N = 2^13, as studies/verification/ishigami_sobol.toml
// Slack on the interval test for the indices whose true value is 0 (S3, S12, S23): their bootstrap
// interval may be a few 1e-3 wide and centred slightly off 0; 0.005 is ~2 % of the smallest non-zero index.
constexpr double kZeroIndexSlack = 5e-3;
// The bootstrap intervals at N = 2^13 must be narrow enough to separate the indices (0.24 to 0.56
// apart from the zeros): the Saltelli and Jansen estimators' standard errors there are 0.005 to 0.015,
// so a 95 % interval is 0.02 to 0.06 wide; one of 0.1 or more would no longer separate S2 from S_T3.
constexpr double kMaximumIntervalWidth = 0.1;
// Closed-form values of magnitude ≤ 10 from sin and a fourth power: a few ulps.
constexpr double kClosedFormTolerance = 1e-12;

/// Closed-form Sobol' indices of the Ishigami function on [−π, π]³ (Ishigami & Homma 1990; Sobol' &
/// Levitan 1999), written out here so the test does not depend on the code under test.
struct IshigamiTruth {
  double first[3], total[3], s13;
};
IshigamiTruth IshigamiAnalytic(double a, double b) {
  const double pi4 = std::pow(std::numbers::pi, 4), pi8 = pi4 * pi4;
  const double V1 = 0.5 * (1.0 + b * pi4 / 5.0) * (1.0 + b * pi4 / 5.0);
  const double V2 = a * a / 8.0;
  const double V13 = b * b * pi8 * (1.0 / 18.0 - 1.0 / 50.0);
  const double V = V1 + V2 + V13;
  return {{V1 / V, V2 / V, 0.0}, {(V1 + V13) / V, V2 / V, V13 / V}, V13 / V};
}

/// The sweep's sobol design on the Ishigami inputs x1, x2, x3 (catalogue parameters, each uniform on
/// [−π, π]), as studies/verification/ishigami_sobol.toml declares it.
DesignSpec IshigamiSpec(int base_samples, bool second_order) {
  std::vector<DesignParameter> parameters;
  for (const auto& range : IshigamiRanges()) {
    parameters.push_back(production_designs::Sampled(range.name, range.lower, range.upper));
  }
  return production_designs::SobolSpec(std::move(parameters), base_samples, second_order);
}

std::vector<double> EvaluateIshigami(const Eigen::MatrixXd& design) {
  std::vector<double> y(design.rows());
  for (Eigen::Index r = 0; r < design.rows(); ++r)
    y[r] = Ishigami({design(r, 0), design(r, 1), design(r, 2)});
  return y;
}

void ExpectInsideInterval(double truth, const ConfidenceInterval& ci, double slack, const std::string& what) {
  EXPECT_LE(ci.lower - slack, truth) << what << ": [" << ci.lower << ", " << ci.upper << "]";
  EXPECT_GE(ci.upper + slack, truth) << what << ": [" << ci.lower << ", " << ci.upper << "]";
}

TEST(IshigamiTruth, MatchesThePublishedValues) {
  // The values (and SALib's documentation): S = (0.3139, 0.4424, 0), ST = (0.5576, 0.4424, 0.2437).
  const IshigamiTruth t = IshigamiAnalytic(7.0, 0.1);
  constexpr double kFourDigits = 5e-5;  // the published values are rounded to four decimals
  EXPECT_NEAR(t.first[0], 0.3139, kFourDigits);
  EXPECT_NEAR(t.first[1], 0.4424, kFourDigits);
  EXPECT_NEAR(t.total[0], 0.5576, kFourDigits);
  EXPECT_NEAR(t.total[2], 0.2437, kFourDigits);
}

TEST(Ishigami, IsTheClosedForm) {
  // sin(π/2) + 7 sin²(π/2) + 0.1·2⁴·sin(π/2) = 1 + 7 + 1.6.
  EXPECT_NEAR(Ishigami({std::numbers::pi / 2, std::numbers::pi / 2, 2.0}), 9.6, kClosedFormTolerance);
  EXPECT_NEAR(Ishigami({0.0, 0.0, 3.0}), 0.0, kClosedFormTolerance);
  EXPECT_EQ(kIshigamiOutputName, "ishigami");
  for (const auto& range : IshigamiRanges()) {
    EXPECT_DOUBLE_EQ(range.lower, -std::numbers::pi);
    EXPECT_DOUBLE_EQ(range.upper, std::numbers::pi);
  }
}

class IshigamiSobol : public ::testing::TestWithParam<bool> {};

TEST_P(IshigamiSobol, AnalyticIndicesLieInsideTheBootstrapIntervals) {
  const bool second_order = GetParam();
  const DesignSpec spec = IshigamiSpec(kIshigamiBaseSamples, second_order);
  const std::vector<double> y = EvaluateIshigami(DesignRows(spec));
  const SaltelliLayout layout = LayoutOf(spec);
  const SobolIndices s = AnalyzeSobol(y, {}, layout);
  ASSERT_EQ(s.status, SensitivityStatus::kOk) << s.message;
  EXPECT_EQ(s.blocks_used, kIshigamiBaseSamples);
  EXPECT_EQ(s.blocks_dropped, 0);
  EXPECT_EQ(s.bootstrap.resamples, 1000);
  EXPECT_DOUBLE_EQ(s.bootstrap.confidence_level, 0.95);

  const IshigamiTruth truth = IshigamiAnalytic(kIshigamiA, kIshigamiB);
  for (int i = 0; i < 3; ++i) {
    const double first_slack = truth.first[i] == 0.0 ? kZeroIndexSlack : 0.0;
    ExpectInsideInterval(truth.first[i], s.first_order_ci[i], first_slack, "S" + std::to_string(i + 1));
    ExpectInsideInterval(truth.total[i], s.total_ci[i], 0.0, "ST" + std::to_string(i + 1));
    // The interval is about the estimate, and narrow enough to mean something at N = 2^13.
    EXPECT_TRUE(s.first_order_ci[i].Contains(s.first_order[i]));
    EXPECT_TRUE(s.total_ci[i].Contains(s.total[i]));
    EXPECT_LT(s.first_order_ci[i].upper - s.first_order_ci[i].lower, kMaximumIntervalWidth);
    EXPECT_LT(s.total_ci[i].upper - s.total_ci[i].lower, kMaximumIntervalWidth);
  }
  if (!second_order) {
    EXPECT_TRUE(std::isnan(s.second_order(0, 2)));
    return;
  }
  const double s2_truth[3][3] = {{0, 0.0, truth.s13}, {0, 0, 0.0}, {0, 0, 0}};
  for (int i = 0; i < 3; ++i) {
    for (int j = i + 1; j < 3; ++j) {
      const ConfidenceInterval ci{s.second_order_ci_lower(i, j), s.second_order_ci_upper(i, j)};
      ExpectInsideInterval(s2_truth[i][j], ci, s2_truth[i][j] == 0.0 ? kZeroIndexSlack : 0.0,
                           "S" + std::to_string(i + 1) + std::to_string(j + 1));
    }
    EXPECT_TRUE(std::isnan(s.second_order(i, i)));
  }
}

INSTANTIATE_TEST_SUITE_P(WithAndWithoutSecondOrder, IshigamiSobol, ::testing::Bool());

TEST(SobolBootstrap, IsReproducibleForASeedAndChangesWithIt) {
  const int N = 256;
  const DesignSpec spec = IshigamiSpec(N, false);
  const SaltelliLayout layout = LayoutOf(spec);
  const std::vector<double> y = EvaluateIshigami(DesignRows(spec));
  SobolOptions options;
  const SobolIndices a = AnalyzeSobol(y, {}, layout, options);
  const SobolIndices b = AnalyzeSobol(y, {}, layout, options);
  options.bootstrap.seed += 1;
  const SobolIndices c = AnalyzeSobol(y, {}, layout, options);
  EXPECT_EQ(a.first_order_ci[0].lower, b.first_order_ci[0].lower);
  EXPECT_EQ(a.total_ci[2].upper, b.total_ci[2].upper);
  EXPECT_NE(a.first_order_ci[0].lower, c.first_order_ci[0].lower);
  EXPECT_EQ(a.first_order[0], c.first_order[0]);  // the estimate itself does not depend on the seed
}

/// Outputs of the Ishigami design with some rows marked failed, and the reduced design that keeps
/// only the blocks without a failed row: analysing the latter is what dropping must amount to.
struct FailedRowsCase {
  SaltelliLayout layout;
  std::vector<double> outputs;
  std::vector<bool> succeeded;
  std::set<int> failed_blocks;
  std::vector<double> reduced_outputs;
};

FailedRowsCase MakeFailedRowsCase(bool second_order) {
  FailedRowsCase c;
  const DesignSpec spec = IshigamiSpec(512, second_order);
  c.layout = LayoutOf(spec);
  c.outputs = EvaluateIshigami(DesignRows(spec));
  c.succeeded.assign(c.outputs.size(), true);
  // Failures in different row kinds: an A row, an AB row, a B row, two rows of one block, and a
  // non-finite output flagged as a success.
  const std::size_t rows[] = {c.layout.RowA(3), c.layout.RowAB(40, 1), c.layout.RowB(41),
                              c.layout.RowAB(100, 0), c.layout.RowAB(100, 2)};
  for (std::size_t r : rows) {
    c.succeeded[r] = false;
    c.outputs[r] = 1e30;  // a failed run's garbage: it must never be averaged in
    c.failed_blocks.insert(c.layout.BlockOfRow(r));
  }
  c.outputs[c.layout.RowB(200)] = std::numeric_limits<double>::quiet_NaN();
  c.failed_blocks.insert(200);
  for (int j = 0; j < c.layout.base_samples; ++j) {
    if (c.failed_blocks.count(j)) continue;
    for (std::size_t r = c.layout.RowA(j); r <= c.layout.RowB(j); ++r)
      c.reduced_outputs.push_back(c.outputs[r]);
  }
  return c;
}

class SobolFailedRows : public ::testing::TestWithParam<bool> {};

TEST_P(SobolFailedRows, DropBlocksDropsWholeBlocksAndReportsThem) {
  const FailedRowsCase c = MakeFailedRowsCase(GetParam());
  const SobolIndices s = AnalyzeSobol(c.outputs, c.succeeded, c.layout);
  ASSERT_EQ(s.status, SensitivityStatus::kOk) << s.message;
  EXPECT_EQ(s.failed_rows, 6);
  EXPECT_EQ(s.blocks_dropped, static_cast<int>(c.failed_blocks.size()));
  EXPECT_EQ(s.blocks_dropped, 5);
  EXPECT_EQ(s.blocks_used, c.layout.base_samples - 5);

  SaltelliLayout reduced = c.layout;
  reduced.base_samples = c.layout.base_samples - 5;
  const SobolIndices r = AnalyzeSobol(c.reduced_outputs, {}, reduced);
  for (int i = 0; i < 3; ++i) {
    EXPECT_DOUBLE_EQ(s.first_order[i], r.first_order[i]);
    EXPECT_DOUBLE_EQ(s.total[i], r.total[i]);
  }
  EXPECT_DOUBLE_EQ(s.output_variance, r.output_variance);
}

TEST_P(SobolFailedRows, ErrorPolicyStopsAndNamesTheFirstFailure) {
  const FailedRowsCase c = MakeFailedRowsCase(GetParam());
  SobolOptions options;
  options.failed_runs = FailedRunPolicy::kError;
  const SobolIndices s = AnalyzeSobol(c.outputs, c.succeeded, c.layout, options);
  EXPECT_EQ(s.status, SensitivityStatus::kStoppedOnFailedRuns);
  EXPECT_TRUE(std::isnan(s.first_order[0]));
  EXPECT_TRUE(std::isnan(s.total[2]));
  EXPECT_NE(s.message.find("6 of " + std::to_string(c.outputs.size()) + " runs failed"), std::string::npos)
      << s.message;
  EXPECT_NE(s.message.find("row " + std::to_string(c.layout.RowA(3)) + ", base sample 3"), std::string::npos)
      << s.message;
  EXPECT_NE(s.message.find("drop_blocks"), std::string::npos) << s.message;
}

INSTANTIATE_TEST_SUITE_P(WithAndWithoutSecondOrder, SobolFailedRows, ::testing::Bool());

TEST(SobolDegenerate, AllBlocksFailedOrConstantOutput) {
  const SaltelliLayout layout{2, 4, false};
  std::vector<double> y(layout.RowCount(), 1.0);
  const SobolIndices constant = AnalyzeSobol(y, {}, layout);
  EXPECT_EQ(constant.status, SensitivityStatus::kZeroVariance);
  EXPECT_TRUE(std::isnan(constant.first_order[0]));

  std::vector<bool> succeeded(y.size(), true);
  for (int j = 0; j < 3; ++j) succeeded[layout.RowB(j)] = false;
  const SobolIndices few = AnalyzeSobol(y, succeeded, layout);
  EXPECT_EQ(few.status, SensitivityStatus::kTooFewBlocks);
  EXPECT_EQ(few.blocks_dropped, 3);
}

TEST(SobolInput, WrongRowCountOrFlagsThrowInputError) {
  const SaltelliLayout layout{3, 8, true};
  std::vector<double> y(layout.RowCount() - 1, 0.0);
  SobolOptions options;
  options.source = "runs.h5";
  try {
    AnalyzeSobol(y, {}, layout, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), "runs.h5");
    EXPECT_NE(std::string(e.what()).find("N·(2D+2) = 64"), std::string::npos) << e.what();
  }
  y.push_back(0.0);
  EXPECT_THROW(AnalyzeSobol(y, std::vector<bool>(3, true), layout), InputError);
  options.bootstrap.confidence_level = 1.0;
  EXPECT_THROW(AnalyzeSobol(y, {}, layout, options), InputError);
  options.bootstrap.confidence_level = 0.9;
  options.bootstrap.resamples = -1;
  EXPECT_THROW(AnalyzeSobol(y, {}, layout, options), InputError);
}

TEST(PercentileInterval, IsTheType7QuantilePair) {
  // 1..101: the q-quantile of type 7 is 1 + 100 q, so the 95 % interval is [3.5, 98.5].
  std::vector<double> values;
  for (int v = 101; v >= 1; --v) values.push_back(v);
  values.push_back(std::numeric_limits<double>::quiet_NaN());  // left out
  const ConfidenceInterval ci = PercentileInterval(values, 0.95);
  // q·(n−1) = 0.025·100 rounds to 2.5 ± 1 ulp: an error of ~1e-15 on values below 100.
  constexpr double kQuantileTolerance = 1e-12;
  EXPECT_NEAR(ci.lower, 3.5, kQuantileTolerance);
  EXPECT_NEAR(ci.upper, 98.5, kQuantileTolerance);
  EXPECT_TRUE(std::isnan(PercentileInterval({1.0}, 0.95).lower));
}

TEST(FailedRunPolicy, ParsesItsNames) {
  EXPECT_EQ(ParseEnum<FailedRunPolicy>("drop_blocks"), FailedRunPolicy::kDropBlocks);
  EXPECT_EQ(ParseEnum<FailedRunPolicy>("error"), FailedRunPolicy::kError);
  EXPECT_FALSE(ParseEnum<FailedRunPolicy>("drop").has_value());
  EXPECT_EQ(ToString(FailedRunPolicy::kDropBlocks), "drop_blocks");
}

}  // namespace
}  // namespace gesweep
