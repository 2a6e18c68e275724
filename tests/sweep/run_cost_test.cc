// The dry run's estimate (engine/sweep/run_cost.h): it keeps to its time budget whatever the runs
// cost, and its arithmetic is what it says. (How close it comes to real sweeps is measured on the
// shipped studies in docs/sweep.md, not asserted: no timing assertion in a test.)
#include "engine/sweep/run_cost.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/analyses/analysis_adapters.h"

namespace gesweep {
namespace {

const std::string kAircraft = std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml";

DesignParameter Axis(const char* name, std::vector<double> values) {
  DesignParameter p;
  p.id = RequireParameter(name);
  p.values = std::move(values);
  return p;
}

SweepPlan ModesPlan() {
  static const Aircraft aircraft = LoadAircraftFile(kAircraft);
  toml::table empty;
  Study study;
  study.path = "<test>";
  study.aircraft = aircraft;
  study.analyses.push_back(MakeModesAnalysis(TomlSection(empty, "<test>", "analyses.modes"), &aircraft));
  study.design.kind = DesignKind::kGrid;
  std::vector<double> heights;
  for (int i = 0; i < 200; ++i) heights.push_back(1.0 + 0.05 * i);
  study.design.parameters = {Axis("height_m", heights)};
  study.fixed = {{RequireParameter("speed_mps"), 32.0208}};
  return SweepPlan(std::move(study), ShardSpec{});
}

TEST(RunCost, EstimateIsTheMeanCostTimesRunsOverThreadsWithAnIntervalAroundIt) {
  const SweepPlan plan = ModesPlan();
  RunCostOptions options;
  options.threads = 2;
  options.budget_s = 0.3;
  const RunCostEstimate e = EstimateRunCost(plan, options);
  EXPECT_FALSE(e.lower_bound);
  EXPECT_FALSE(e.stopped);
  ASSERT_GT(e.timed_runs, 0);
  EXPECT_GT(e.warmup_runs, 0);
  EXPECT_GT(e.seconds_per_run, 0.0);
  EXPECT_LE(e.seconds_per_run_low, e.seconds_per_run);
  EXPECT_GE(e.seconds_per_run_high, e.seconds_per_run);
  // Double rounding of one product and one division.
  constexpr double kRounding = 1e-12;
  EXPECT_NEAR(e.estimated_seconds, e.seconds_per_run * 200 / 2, kRounding * e.estimated_seconds);
  EXPECT_NEAR(e.estimated_seconds_high, e.seconds_per_run_high * 200 / 2, kRounding * e.estimated_seconds_high);
}

TEST(RunCost, ARunLongerThanTheBudgetIsCutAndReportedAsALowerBound) {
  static const Aircraft aircraft = LoadAircraftFile(kAircraft);
  toml::table settings;
  settings.insert("duration_s", 1e5);  // 1e8 RK4 steps: seconds per run
  settings.insert("step_s", 1e-3);
  settings.insert("input", "none");
  Study study;
  study.path = "<test>";
  study.aircraft = aircraft;
  study.analyses.push_back(MakeOpenLoopAnalysis(TomlSection(settings, "<test>", "analyses.open_loop"), &aircraft));
  study.fixed = {{RequireParameter("speed_mps"), 32.0208}, {RequireParameter("height_m"), 100.0}};
  const SweepPlan plan(std::move(study), ShardSpec{});
  RunCostOptions options;
  options.budget_s = 0.2;
  const RunCostEstimate e = EstimateRunCost(plan, options);
  // Had the deadline not reached inside the run, the run would have finished (as a warm-up) and the
  // estimate would not be a bound.
  EXPECT_TRUE(e.lower_bound);
  EXPECT_EQ(e.timed_runs, 0);
  EXPECT_GT(e.seconds_per_run, 0.0);
  EXPECT_TRUE(std::isinf(e.estimated_seconds_high));
}

TEST(RunCost, AStopFlagEndsTheMeasurement) {
  const SweepPlan plan = ModesPlan();
  const std::atomic<bool> stop{true};
  RunCostOptions options;
  options.budget_s = 5;  // had the flag been ignored: 5 s and stopped == false
  const RunCostEstimate e = EstimateRunCost(plan, options, &stop);
  EXPECT_TRUE(e.stopped);
  EXPECT_EQ(e.timed_runs, 0) << "set before the start, the flag lets no run be measured";
}

}  // namespace
}  // namespace gesweep
