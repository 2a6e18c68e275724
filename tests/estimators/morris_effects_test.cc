#include "engine/estimators/morris_effects.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/common/errors.h"
#include "tests/estimators/production_designs.h"

namespace gesweep {
namespace {

using production_designs::DesignRows;
using production_designs::MorrisSpec;
using production_designs::RangesOf;
using production_designs::Sampled;

// Elementary effects of a linear function are exact but for rounding. The design values (|x| ≤ 14) and
// the outputs (|y| ≤ 20 after four products and sums) each carry a few ulps, ≤ 2e-14 on y; an effect
// divides a difference of two outputs by the unit step Δ = 2/3 (p = 4), so it is off by ≤ 6e-14, and
// so are μ, μ*, their bootstrap percentiles and σ (a spread of values all that close). 1e-12 leaves
// a factor > 10 for the log-uniform case's exp/log round trip.
constexpr double kLinearTolerance = 1e-12;
// The hand-computed trajectories hold values like 2/3 and 1/9: a few ulps of numbers below 2.
constexpr double kHandTolerance = 1e-12;

TEST(Morris, LinearFunctionRecoversAbsoluteCoefficientsAsMuStar) {
  // y = 3 a − 2 b + 0.5 c + 0·d + 7. An elementary effect is per full range of the parameter, so the
  // oracle is |coefficient| × (upper − lower): on the unit interval, |coefficient| itself.
  const DesignSpec spec = MorrisSpec(
      {Sampled("x1", 0.0, 1.0), Sampled("x2", 0.0, 1.0), Sampled("x3", 10.0, 14.0), Sampled("x4", -1.0, 1.0)},
      12, 4, 11);
  const std::vector<ParameterRange> ranges = RangesOf(spec);
  const double coefficients[] = {3.0, -2.0, 0.5, 0.0};
  const Eigen::MatrixXd X = DesignRows(spec);
  std::vector<double> y(X.rows());
  for (Eigen::Index r = 0; r < X.rows(); ++r) {
    y[r] = 7.0;
    for (int i = 0; i < 4; ++i) y[r] += coefficients[i] * X(r, i);
  }
  const MorrisIndices m = AnalyzeMorris(X, y, {}, ranges);
  ASSERT_EQ(m.status, SensitivityStatus::kOk) << m.message;
  EXPECT_EQ(m.trajectories, 12);
  EXPECT_EQ(m.trajectories_used, 12);
  for (int i = 0; i < 4; ++i) {
    const double width = ranges[i].upper - ranges[i].lower;
    EXPECT_NEAR(m.mu_star[i], std::abs(coefficients[i]) * width, kLinearTolerance) << ranges[i].name;
    EXPECT_NEAR(m.mu[i], coefficients[i] * width, kLinearTolerance) << ranges[i].name;
    EXPECT_NEAR(m.sigma[i], 0.0, kLinearTolerance) << ranges[i].name;
    EXPECT_EQ(m.effects[i], 12);
    EXPECT_NEAR(m.mu_star_ci[i].lower, m.mu_star[i], kLinearTolerance);
    EXPECT_NEAR(m.mu_star_ci[i].upper, m.mu_star[i], kLinearTolerance);
  }
}

TEST(Morris, LogUniformParameterStepsInLogSpace) {
  // y = 2 ln x + b with x log-uniform on [1, e³]: linear in the unit coordinate u = ln(x)/3, so every
  // elementary effect is 2 × 3 = 6 per full (log-)range; b on [0, 1] contributes 1.
  const DesignSpec spec = MorrisSpec(
      {Sampled("x1", 1.0, std::exp(3.0), Distribution::kLogUniform), Sampled("x2", 0.0, 1.0)}, 6, 4, 5);
  const std::vector<ParameterRange> ranges = RangesOf(spec);
  const Eigen::MatrixXd X = DesignRows(spec);
  std::vector<double> y(X.rows());
  for (Eigen::Index r = 0; r < X.rows(); ++r) y[r] = 2.0 * std::log(X(r, 0)) + X(r, 1);
  const MorrisIndices m = AnalyzeMorris(X, y, {}, ranges);
  ASSERT_EQ(m.status, SensitivityStatus::kOk) << m.message;
  EXPECT_NEAR(m.mu_star[0], 6.0, kLinearTolerance);
  EXPECT_NEAR(m.sigma[0], 0.0, kLinearTolerance);
  EXPECT_NEAR(m.mu_star[1], 1.0, kLinearTolerance);
  // A log-uniform range must have 0 < lower: the estimator refuses ranges (e.g. read from a damaged
  // archive) that no design could have sampled.
  std::vector<ParameterRange> bad = ranges;
  bad[0].lower = 0.0;
  EXPECT_THROW(AnalyzeMorris(X, y, {}, bad), InputError);
}

TEST(Morris, HandComputedTrajectories) {
  // y = x1² + x2 on [0, 1]², two trajectories with Δ = 2/3 written out by hand:
  //   (0, 0) → (2/3, 0) → (2/3, 2/3):   EE1 = (4/9)/(2/3) = 2/3,   EE2 = (2/3)/(2/3) = 1
  //   (1, 1) → (1, 1/3) → (1/3, 1/3):   EE2 = (−2/3)/(−2/3) = 1,   EE1 = (1/9 − 1)/(−2/3) = 4/3
  // μ1 = μ1* = 1, σ1 = sd(2/3, 4/3) = √2/3; μ2 = μ2* = 1, σ2 = 0.
  Eigen::MatrixXd X(6, 2);
  X << 0, 0, 2.0 / 3, 0, 2.0 / 3, 2.0 / 3, 1, 1, 1, 1.0 / 3, 1.0 / 3, 1.0 / 3;
  std::vector<double> y(6);
  for (int r = 0; r < 6; ++r) y[r] = X(r, 0) * X(r, 0) + X(r, 1);
  MorrisOptions options;
  options.bootstrap.resamples = 0;
  const MorrisIndices m = AnalyzeMorris(X, y, {}, {{"x1", 0, 1}, {"x2", 0, 1}}, options);
  ASSERT_EQ(m.status, SensitivityStatus::kOk);
  EXPECT_NEAR(m.mu[0], 1.0, kHandTolerance);
  EXPECT_NEAR(m.mu_star[0], 1.0, kHandTolerance);
  EXPECT_NEAR(m.sigma[0], std::sqrt(2.0) / 3.0, kHandTolerance);
  EXPECT_NEAR(m.mu[1], 1.0, kHandTolerance);
  EXPECT_NEAR(m.sigma[1], 0.0, kHandTolerance);
  EXPECT_TRUE(std::isnan(m.mu_star_ci[0].lower));  // no bootstrap asked for
}

TEST(Morris, FailedRowsDropTheirTrajectoryOrStop) {
  const DesignSpec spec = MorrisSpec({Sampled("x1", 0.0, 1.0), Sampled("x2", 0.0, 2.0)}, 5, 4, 3);
  const std::vector<ParameterRange> ranges = RangesOf(spec);
  const Eigen::MatrixXd X = DesignRows(spec);
  std::vector<double> y(X.rows());
  for (Eigen::Index r = 0; r < X.rows(); ++r) y[r] = 4.0 * X(r, 0) - X(r, 1);
  std::vector<bool> succeeded(y.size(), true);
  succeeded[4] = false;  // trajectory 1 (rows 3–5)
  y[4] = 1e30;
  y[14] = std::numeric_limits<double>::infinity();  // trajectory 4, flagged as a success
  const MorrisIndices m = AnalyzeMorris(X, y, succeeded, ranges);
  ASSERT_EQ(m.status, SensitivityStatus::kOk) << m.message;
  EXPECT_EQ(m.failed_rows, 2);
  EXPECT_EQ(m.trajectories_dropped, 2);
  EXPECT_EQ(m.trajectories_used, 3);
  EXPECT_EQ(m.effects[0], 3);
  EXPECT_NEAR(m.mu_star[0], 4.0, kLinearTolerance);
  EXPECT_NEAR(m.mu_star[1], 2.0, kLinearTolerance);

  MorrisOptions stop;
  stop.failed_runs = FailedRunPolicy::kError;
  const MorrisIndices s = AnalyzeMorris(X, y, succeeded, ranges, stop);
  EXPECT_EQ(s.status, SensitivityStatus::kStoppedOnFailedRuns);
  EXPECT_TRUE(std::isnan(s.mu_star[0]));
  EXPECT_NE(s.message.find("row 4, trajectory 1"), std::string::npos) << s.message;
}

TEST(Morris, RejectsADesignThatIsNotOneAtATime) {
  Eigen::MatrixXd X(3, 2);
  X << 0, 0, 1, 1, 1, 0;  // the first step moves both parameters
  const std::vector<double> y = {0, 1, 2};
  try {
    AnalyzeMorris(X, y, {}, {{"a", 0, 1}, {"b", 0, 1}});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("design rows 0 to 1"), std::string::npos) << e.what();
  }
  Eigen::MatrixXd short_design(4, 2);
  short_design.setZero();
  EXPECT_THROW(AnalyzeMorris(short_design, std::vector<double>(4, 0.0), {}, {{"a", 0, 1}, {"b", 0, 1}}),
               InputError);
}

}  // namespace
}  // namespace gesweep
