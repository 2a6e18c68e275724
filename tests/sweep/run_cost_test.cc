// The dry run's estimate (engine/sweep/run_cost.h): it keeps to its time budget whatever the runs
// cost, and its arithmetic is what it says. (How close it comes to real sweeps is measured on the
// shipped studies in docs/sweep.md, not asserted: no timing assertion in a test.)
#include "engine/sweep/run_cost.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/analyses/analysis.h"

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
  study.analyses.push_back(MakeAnalysis("modes", TomlSection(empty, "<test>", "analyses.modes"), &aircraft));
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
  EXPECT_NEAR(e.estimated_seconds_high, e.seconds_per_run_high * 200 / 2,
              kRounding * e.estimated_seconds_high);
}

// Open-loop runs (RK4 at 1 ms, no input) of `duration_s` from heights of 100 m and up.
SweepPlan OpenLoopPlan(double duration_s, int runs) {
  static const Aircraft aircraft = LoadAircraftFile(kAircraft);
  toml::table settings;
  settings.insert("duration_s", duration_s);
  settings.insert("step_s", 1e-3);
  settings.insert("input", "none");
  Study study;
  study.path = "<test>";
  study.aircraft = aircraft;
  study.analyses.push_back(
      MakeAnalysis("open_loop", TomlSection(settings, "<test>", "analyses.open_loop"), &aircraft));
  std::vector<double> heights;
  for (int i = 0; i < runs; ++i) heights.push_back(100.0 + i);
  study.design.kind = DesignKind::kGrid;
  study.design.parameters = {Axis("height_m", heights)};
  study.fixed = {{RequireParameter("speed_mps"), 32.0208}};
  return SweepPlan(std::move(study), ShardSpec{});
}

TEST(RunCost, ARunLongerThanTheBudgetIsCutAndReportedAsALowerBound) {
  const SweepPlan plan = OpenLoopPlan(1e5, 1);  // 1e8 RK4 steps: seconds per run
  for (int lanes : {1, 8}) {                    // one at a time, and a burst flown in lanes
    RunCostOptions options;
    options.budget_s = 0.2;
    options.lanes = lanes;
    const RunCostEstimate e = EstimateRunCost(plan, options);
    // Had the deadline not reached inside the run, the run would have finished (as a warm-up) and
    // the estimate would not be a bound.
    EXPECT_TRUE(e.lower_bound) << lanes;
    EXPECT_EQ(e.timed_runs, 0) << lanes;
    EXPECT_GT(e.seconds_per_run, 0.0) << lanes;
    EXPECT_TRUE(std::isinf(e.estimated_seconds_high)) << lanes;
  }
}

TEST(RunCost, BurstsFlownInLanesAreTimedAsTheSweepFliesThem) {
  const SweepPlan plan = OpenLoopPlan(1.0, 64);  // 1000 steps a run
  RunCostOptions options;
  options.budget_s = 0.3;
  options.lanes = 4;
  const RunCostEstimate e = EstimateRunCost(plan, options);
  EXPECT_FALSE(e.lower_bound);
  EXPECT_GT(e.timed_runs, 0);
  EXPECT_EQ(e.timed_runs % 8, 0) << "whole bursts of 8 runs, each run finished";
  EXPECT_GT(e.seconds_per_run, 0.0);
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

// SweepSeconds and SteadyWallPerRun against sums done by hand (docs/sweep.md, "Dry run").
// Double rounding of a few products and sums.
constexpr double kArithmetic = 1e-12;

TEST(SweepSeconds, OneBatchPassesThroughThePipelineTheOtherRunsGoAtTheSteadyRate) {
  // 4 ms compute, 1 ms encode, 0.5 ms store per run; 100 ms per sweep; 2 threads on 2 cores.
  const SweepTimeParts parts{4e-3, 1e-3, 0.5e-3, 0.1};
  // max(5/2, 0.5, 5.5/min(3, 2)) ms: the workers and the writer share the two cores.
  EXPECT_NEAR(SteadyWallPerRun(parts, 2, 2), 2.75e-3, kArithmetic);
  // 100 x (4/2 + 1 + 0.5) ms + 900 x 2.75 ms + 100 ms.
  EXPECT_NEAR(SweepSeconds(parts, 1000, 100, 2, 2), 0.35 + 2.475 + 0.1, kArithmetic);
}

TEST(SweepSeconds, ASweepOfOneBatchIsThatBatchThroughThePipelinePlusTheFixedPart) {
  const SweepTimeParts parts{4e-3, 1e-3, 0.5e-3, 0.1};
  // 10 x (2 + 1 + 0.5) ms + 100 ms: nothing overlaps.
  EXPECT_NEAR(SweepSeconds(parts, 10, 100, 2, 2), 0.135, kArithmetic);
  EXPECT_NEAR(SweepSeconds(parts, 0, 100, 2, 2), 0.1, kArithmetic) << "no run: the fixed part alone";
}

TEST(SweepSeconds, TheBindingStageSetsTheSteadyRate) {
  // The writer binds: 10 ms to store a run beside 1 ms of work on 4 threads (8 cores).
  EXPECT_NEAR(SteadyWallPerRun({1e-3, 0, 10e-3, 0}, 4, 8), 10e-3, kArithmetic);
  // The workers bind: (8 + 2) ms / 4 threads; the cores (8) do not.
  EXPECT_NEAR(SteadyWallPerRun({8e-3, 2e-3, 1e-3, 0}, 4, 8), 2.5e-3, kArithmetic);
  // One core: everything shares it, (8 + 2 + 1) ms.
  EXPECT_NEAR(SteadyWallPerRun({8e-3, 2e-3, 1e-3, 0}, 4, 1), 11e-3, kArithmetic);
  // 1000 runs in batches of 10 at the cores' rate, 10 x (2 + 2 + 1) ms for the first batch + 990 x 11 ms.
  EXPECT_NEAR(SweepSeconds({8e-3, 2e-3, 1e-3, 0.25}, 1000, 10, 4, 1), 0.05 + 10.89 + 0.25, kArithmetic);
}

TEST(MeasurePipelineStart, RunsNoBatch) {
  // The sink aborts if called: a pipeline of no batch computes and writes nothing.
  const SweepPlan plan = ModesPlan();
  EXPECT_GT(MeasurePipelineStart(plan, 2), 0.0);
}

}  // namespace
}  // namespace gesweep
