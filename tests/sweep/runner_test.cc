// The runner: every run's results equal a direct call of the engine for its parameters; a failing
// run is data and the sweep goes on; the results do not depend on the thread count; memory is a
// fixed pool of batches; runs grouped in lanes (ExecuteRuns) equal runs alone (ExecuteRun).
#include "engine/sweep/runner.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>

#include "engine/analyses/analysis.h"
#include "engine/control/landing_simulation.h"
#include "engine/modal/modal_analysis.h"
#include "engine/simulation/open_loop.h"

namespace gesweep {
namespace {

const std::string kAircraft = std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml";

// Keeps every batch, as the archive would, keyed by its number.
class MemorySink : public ResultSink {
 public:
  void Write(const ResultBlock& block) override {
    std::lock_guard<std::mutex> lock(mutex_);
    ++writes_;
    blocks_[block.block_index] = block;
  }
  std::map<std::int64_t, ResultBlock> blocks_;
  int writes_ = 0;
  std::mutex mutex_;
};

DesignParameter Axis(const char* name, std::vector<double> values) {
  DesignParameter p;
  p.id = RequireParameter(name);
  p.values = std::move(values);
  return p;
}

// A study of `analyses` over a grid, built in memory (no file).
Study GridStudy(std::vector<std::unique_ptr<Analysis>> analyses, std::vector<DesignParameter> axes,
                int chunk_runs) {
  Study study;
  study.path = "<test>";
  study.name = "test";
  study.aircraft = LoadAircraftFile(kAircraft);
  study.analyses = std::move(analyses);
  study.chunk_runs = chunk_runs;
  study.design.kind = DesignKind::kGrid;
  study.design.parameters = std::move(axes);
  return study;
}

std::unique_ptr<Analysis> Modes() {
  toml::table empty;
  static const Aircraft aircraft = LoadAircraftFile(kAircraft);
  return MakeAnalysis("modes", TomlSection(empty, "<test>", "analyses.modes"), &aircraft);
}

int ColumnIndex(const SweepPlan& plan, const std::string& path) {
  for (std::size_t c = 0; c < plan.schema().columns.size(); ++c) {
    if (plan.schema().columns[c].path == path) return static_cast<int>(c);
  }
  ADD_FAILURE() << "no column " << path;
  return 0;
}

TEST(Runner, ModesResultsEqualDirectAnalysisOfEachRun) {
  std::vector<std::unique_ptr<Analysis>> analyses;
  analyses.push_back(Modes());
  SweepPlan plan(
      GridStudy(std::move(analyses),
                {Axis("speed_mps", {25, 32.0208, 45}), Axis("height_m", {0.8, 1.5, 2.5935, 2.7, 6, 13})}, 4),
      ShardSpec{});
  std::vector<std::int64_t> blocks;
  for (std::int64_t b = 0; b < plan.block_count(); ++b) blocks.push_back(b);
  MemorySink sink;
  SweepProgress progress;
  const SweepOutcome outcome = RunSweep(plan, blocks, sink, RunnerOptions{2, nullptr, 2}, &progress);
  EXPECT_EQ(outcome.runs_ok, 18);
  EXPECT_EQ(outcome.runs_failed, 0);
  EXPECT_EQ(sink.writes_, 5);  // 18 runs in batches of 4
  EXPECT_EQ(progress.runs_written.load(), 18);
  const LongitudinalModel model(LoadAircraftFile(kAircraft), ModelOptions{});
  const int margin = ColumnIndex(plan, "results/modes/stability_margin_per_s");
  const int eigenvalues = ColumnIndex(plan, "results/modes/eigenvalues");
  for (const auto& [index, block] : sink.blocks_) {
    for (int r = 0; r < block.rows; ++r) {
      const double u = block.design[0][static_cast<std::size_t>(r)];
      const double h = block.design[1][static_cast<std::size_t>(r)];
      EXPECT_EQ(block.design_index[static_cast<std::size_t>(r)], index * 4 + r);
      const ModalAnalysis direct = AnalyzeModes(model.StateMatrix(h, u));
      EXPECT_EQ(block.results[static_cast<std::size_t>(margin)][static_cast<std::size_t>(r)],
                direct.stability_margin_per_s);
      for (int k = 0; k < 5; ++k) {
        EXPECT_EQ(
            block.results[static_cast<std::size_t>(eigenvalues)][static_cast<std::size_t>(r * 10 + 2 * k)],
            direct.eigenvalues[static_cast<std::size_t>(k)].real());
      }
      EXPECT_EQ(block.status[static_cast<std::size_t>(r)], static_cast<std::int8_t>(RunStatus::kOk));
    }
  }
}

// Fails (by throwing, or by reporting) on chosen x1 values.
class FlakyAnalysis final : public Analysis {
 public:
  std::string_view name() const override { return "flaky"; }
  bool needs_model() const override { return false; }
  std::vector<ParameterId> parameters_used() const override { return {x1_}; }
  double nominal_run_cost_us() const override { return 1; }
  void DeclareOutputs(OutputSchema& schema, const StorageOptions&) override {
    column_ = schema.Add(OutputColumn::Real("results/flaky/y", "1", "x1 squared"));
  }
  AnalysisOutcome Run(const RunContext& context, OutputRow& row) const override {
    const double x = context.value(x1_);
    if (x == 3) throw std::runtime_error("boom at 3");
    if (x == 5) return AnalysisOutcome::Failed("diverged at 5");
    row.Set(column_, x * x);
    return AnalysisOutcome::Ok();
  }

 private:
  ParameterId x1_ = RequireParameter("x1");
  int column_ = 0;
};

TEST(Runner, FailedRunsAreDataAndTheSweepGoesOn) {
  Study study;
  study.path = "<test>";
  study.analyses.push_back(std::make_unique<FlakyAnalysis>());
  study.chunk_runs = 3;
  study.design.kind = DesignKind::kGrid;
  study.design.parameters = {Axis("x1", {1, 2, 3, 4, 5, 6, 7})};
  SweepPlan plan(std::move(study), ShardSpec{});
  MemorySink sink;
  const SweepOutcome outcome = RunSweep(plan, {0, 1, 2}, sink, RunnerOptions{2, nullptr, 1}, nullptr);
  EXPECT_EQ(outcome.runs_ok, 5);
  EXPECT_EQ(outcome.runs_failed, 2);
  const ResultBlock& middle = sink.blocks_.at(0);  // x1 = 1, 2, 3
  EXPECT_EQ(middle.status[2], static_cast<std::int8_t>(RunStatus::kFailed));
  EXPECT_EQ(middle.message[2], "flaky: exception: boom at 3");
  EXPECT_TRUE(std::isnan(middle.results[0][2]));
  EXPECT_EQ(middle.results[0][1], 4.0);
  const ResultBlock& second = sink.blocks_.at(1);  // x1 = 4, 5, 6
  EXPECT_EQ(second.status[1], static_cast<std::int8_t>(RunStatus::kFailed));
  EXPECT_EQ(second.message[1], "flaky: diverged at 5");
  EXPECT_EQ(second.results[0][2], 36.0);
  EXPECT_EQ(sink.blocks_.at(2).rows, 1);
}

TEST(Runner, ResultsDoNotDependOnTheThreadCount) {
  auto run = [](int threads) {
    std::vector<std::unique_ptr<Analysis>> analyses;
    analyses.push_back(Modes());
    SweepPlan plan(
        GridStudy(std::move(analyses),
                  {Axis("scale.CMalphadot", {0.8, 1.0, 1.2}), Axis("height_m", {0.9, 1.7, 2.6, 3.1, 8.0}),
                   Axis("speed_mps", {28, 32, 40, 52})},
                  8),
        ShardSpec{});
    plan.set_chunk_runs(8);
    MemorySink sink;
    std::vector<std::int64_t> blocks;
    for (std::int64_t b = 0; b < plan.block_count(); ++b) blocks.push_back(b);
    RunSweep(plan, blocks, sink, RunnerOptions{threads, nullptr, 2}, nullptr);
    std::vector<double> all;
    for (const auto& [index, block] : sink.blocks_) {
      for (const auto& column : block.results)
        all.insert(all.end(), column.begin(),
                   column.begin() + block.rows * (static_cast<int>(column.size()) / 8));
    }
    return all;
  };
  const auto one = run(1);
  const auto four = run(4);
  ASSERT_EQ(one.size(), four.size());
  EXPECT_EQ(0,
            std::memcmp(one.data(), four.data(), one.size() * sizeof(double)));  // bit for bit (NaN included)
}

TEST(Runner, CancelStopsTakingBatchesAndWritesThoseInFlight) {
  Study study;
  study.path = "<test>";
  study.analyses.push_back(std::make_unique<FlakyAnalysis>());
  study.chunk_runs = 1;
  study.design.kind = DesignKind::kGrid;
  std::vector<double> xs;
  for (int i = 10; i < 1010; ++i) xs.push_back(i);
  study.design.parameters = {Axis("x1", xs)};
  SweepPlan plan(std::move(study), ShardSpec{});
  std::vector<std::int64_t> blocks;
  for (std::int64_t b = 0; b < plan.block_count(); ++b) blocks.push_back(b);
  // Cancels from inside the sink after the fifth batch.
  struct CancellingSink : MemorySink {
    std::atomic<bool>* cancel = nullptr;
    void Write(const ResultBlock& block) override {
      MemorySink::Write(block);
      if (writes_ == 5) cancel->store(true);
    }
  } sink;
  std::atomic<bool> cancel{false};
  sink.cancel = &cancel;
  const SweepOutcome outcome = RunSweep(plan, blocks, sink, RunnerOptions{2, &cancel, 1}, nullptr);
  EXPECT_TRUE(outcome.cancelled);
  EXPECT_LT(sink.writes_, 100);
  EXPECT_EQ(outcome.runs_ok, sink.writes_) << "every computed batch was written";
}

TEST(Runner, IshigamiRunsGiveTheFunctionValues) {
  toml::table empty;
  Study study;
  study.path = "<test>";
  study.analyses.push_back(
      MakeAnalysis("ishigami", TomlSection(empty, "<test>", "analyses.ishigami"), nullptr));
  study.design.kind = DesignKind::kGrid;
  study.design.parameters = {Axis("x1", {-1, 0.5}), Axis("x2", {2}), Axis("x3", {-3, 1})};
  SweepPlan plan(std::move(study), ShardSpec{});
  MemorySink sink;
  RunSweep(plan, {0}, sink, RunnerOptions{1, nullptr, 1}, nullptr);
  const ResultBlock& block = sink.blocks_.at(0);
  // pow() and repeated products round differently in the last bits.
  constexpr double kRounding = 1e-13;
  // Oracle: the formula, Ishigami & Homma (1990) with a = 7, b = 0.1.
  auto f = [](double x1, double x2, double x3) {
    return std::sin(x1) + 7 * std::pow(std::sin(x2), 2) + 0.1 * std::pow(x3, 4) * std::sin(x1);
  };
  EXPECT_NEAR(block.results[0][0], f(-1, 2, -3), kRounding);
  EXPECT_NEAR(block.results[0][1], f(-1, 2, 1), kRounding);
  EXPECT_NEAR(block.results[0][2], f(0.5, 2, -3), kRounding);
  EXPECT_NEAR(block.results[0][3], f(0.5, 2, 1), kRounding);
}

}  // namespace
}  // namespace gesweep

namespace gesweep {
namespace {

TEST(Runner, OpenLoopRunsEqualDirectSimulationSummaryAndSeries) {
  static const Aircraft aircraft = LoadAircraftFile(kAircraft);
  toml::table settings;
  settings.insert("duration_s", 20.0);
  std::vector<std::unique_ptr<Analysis>> analyses;
  analyses.push_back(
      MakeAnalysis("open_loop", TomlSection(settings, "<test>", "analyses.open_loop"), &aircraft));
  Study study = GridStudy(std::move(analyses), {Axis("height_m", {1.5561, 5.5922})}, 2);
  study.storage.time_series = true;
  study.storage.output_dt_s = 0.03;
  study.fixed = {{RequireParameter("speed_mps"), 32.0208}};
  SweepPlan plan(std::move(study), ShardSpec{});
  MemorySink sink;
  RunSweep(plan, {0}, sink, RunnerOptions{2, nullptr, 1}, nullptr);
  const ResultBlock& block = sink.blocks_.at(0);
  const LongitudinalModel model(aircraft, ModelOptions{});
  const int min_height = ColumnIndex(plan, "results/open_loop/min_height_m");
  const int series_height = ColumnIndex(plan, "series/open_loop/height_m");
  const int samples = plan.schema().columns[static_cast<std::size_t>(series_height)].width;
  EXPECT_EQ(samples, 667);  // 0, 0.03, ..., 19.98 s
  for (int r = 0; r < 2; ++r) {
    // Oracle: the engine's own open-loop run with the same settings (the paper's pulse).
    OpenLoopConfig config;
    config.start_height_m = block.design[0][static_cast<std::size_t>(r)];
    config.reference_speed_mps = 32.0208;
    config.duration_s = 20.0;
    config.series_interval_s = 0.03;
    const OpenLoopResult direct = SimulateOpenLoop(model, config);
    EXPECT_EQ(block.results[static_cast<std::size_t>(min_height)][static_cast<std::size_t>(r)],
              direct.summary.min_height_m);
    const double* series = block.results[static_cast<std::size_t>(series_height)].data() + r * samples;
    for (std::size_t i = 0; i + 1 < direct.series.time_s.size(); ++i) {
      const auto k = static_cast<int>(std::lround(direct.series.time_s[i] / 0.03));
      ASSERT_LT(k, samples);
      EXPECT_EQ(series[k], direct.series.height_m[i]) << "row " << r << " t " << direct.series.time_s[i];
    }
    if (direct.summary.end_event == OpenLoopEndEvent::kTouchdown) {
      EXPECT_TRUE(std::isnan(series[samples - 1])) << "samples after touchdown are NaN";
    }
  }
}

// A study of open-loop runs of 1e8 RK4 steps each (1e5 s at 1 ms, seconds of work per run): steps at
// trim with no input, so that nothing ends a run early.
SweepPlan LongOpenLoopPlan(int chunk_runs) {
  static const Aircraft aircraft = LoadAircraftFile(kAircraft);
  toml::table settings;
  settings.insert("duration_s", 1e5);
  settings.insert("step_s", 1e-3);
  settings.insert("input", "none");
  std::vector<std::unique_ptr<Analysis>> analyses;
  analyses.push_back(
      MakeAnalysis("open_loop", TomlSection(settings, "<test>", "analyses.open_loop"), &aircraft));
  Study study = GridStudy(std::move(analyses), {Axis("height_m", {100.0, 200.0, 300.0, 400.0})}, chunk_runs);
  study.fixed = {{RequireParameter("speed_mps"), 32.0208}};
  return SweepPlan(std::move(study), ShardSpec{});
}

TEST(Runner, CancelReachesInsideALongRunAndItsBatchIsNotWritten) {
  const SweepPlan plan = LongOpenLoopPlan(2);
  for (int lanes : {1, 2}) {  // one at a time, and the two runs of a batch flown in lanes
    std::atomic<bool> cancel{false};
    // Cancels once the runs are under way (as SIGINT would); each needs seconds, so none can finish.
    std::thread canceller([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      cancel.store(true);
    });
    MemorySink sink;
    SweepProgress progress;
    RunnerOptions options{2, &cancel, 1};
    options.lanes = lanes;
    const SweepOutcome outcome = RunSweep(plan, {0, 1}, sink, options, &progress);
    canceller.join();
    EXPECT_TRUE(outcome.cancelled) << lanes;
    EXPECT_EQ(sink.writes_, 0) << "a batch whose runs were stopped half-way must not be written";
    EXPECT_EQ(progress.runs_done.load(), 0) << "a stopped run is not a completed one";
  }
}

TEST(Runner, ExecuteRunLeavesACancelledRunPending) {
  const SweepPlan plan = LongOpenLoopPlan(1);
  ResultBlock block;
  block.Allocate(plan);
  block.Reset(plan, 0);
  RunWorkspace workspace(plan);
  const std::atomic<bool> cancel{true};
  ExecuteRun(plan, 0, workspace, block, 0, &cancel);
  EXPECT_EQ(block.status[0], static_cast<std::int8_t>(RunStatus::kPending));
  EXPECT_EQ(block.message[0], "cancelled");
}

}  // namespace
}  // namespace gesweep

namespace gesweep {
namespace {

TEST(Runner, LandingRunsEqualDirectSimulationWithAndWithoutHDerivatives) {
  static const Aircraft aircraft = LoadAircraftFile(kAircraft);
  toml::table settings;
  std::vector<std::unique_ptr<Analysis>> analyses;
  analyses.push_back(MakeAnalysis("landing", TomlSection(settings, "<test>", "analyses.landing"), &aircraft));
  Study study = GridStudy(std::move(analyses), {Axis("h_derivatives", {1.0, 0.0})}, 2);
  study.fixed = {{RequireParameter("height_m"), 500.0}, {RequireParameter("speed_mps"), 52.21}};
  SweepPlan plan(std::move(study), ShardSpec{});
  MemorySink sink;
  RunSweep(plan, {0}, sink, RunnerOptions{2, nullptr, 1}, nullptr);
  const ResultBlock& block = sink.blocks_.at(0);
  const int touchdown = ColumnIndex(plan, "results/landing/touchdown_time_s");
  const int outcome = ColumnIndex(plan, "results/landing/outcome");
  const int gain = ColumnIndex(plan, "results/landing/gain");
  for (int r = 0; r < 2; ++r) {
    ModelOptions options;
    options.h_derivatives = r == 0;
    LandingConfig config;  // the paper's case: 500 m, 52.21 m/s (landing_config.h defaults)
    config.output_interval_s = 0.0;
    const LandingResult direct = SimulateLanding(LongitudinalModel(aircraft, options), config);
    EXPECT_EQ(block.results[static_cast<std::size_t>(outcome)][static_cast<std::size_t>(r)],
              static_cast<double>(static_cast<int>(direct.outcome)));
    const double expected = direct.touchdown_time_s;
    const double got = block.results[static_cast<std::size_t>(touchdown)][static_cast<std::size_t>(r)];
    EXPECT_TRUE(got == expected || (std::isnan(got) && std::isnan(expected))) << got << " vs " << expected;
    EXPECT_EQ(block.results[static_cast<std::size_t>(gain)][static_cast<std::size_t>(r * 9 + 3)],
              direct.design.gain[3]);
  }
}

}  // namespace
}  // namespace gesweep

// Runs in groups, flown in SIMD lanes (ExecuteRuns, Analysis::RunLanes): every run's row equals the
// row ExecuteRun gives it alone -- design values, id, status, message and results, bit for bit --
// for every lane width and however the runs are grouped, with open-loop runs that touch down, stall
// and reach the time limit, several models in a group, and a second analysis that fails or throws
// on some runs. The oracle is ExecuteRun, the one-at-a-time path the runner takes without lanes.
namespace gesweep {
namespace {

const Aircraft& Ance() {
  static const Aircraft aircraft = LoadAircraftFile(kAircraft);
  return aircraft;
}

std::unique_ptr<Analysis> OpenLoop() {
  toml::table settings;
  settings.insert("input", "step");
  settings.insert("duration_s", 12.0);
  settings.insert("integrator", "rk4");
  settings.insert("step_s", 0.015);
  return MakeAnalysis("open_loop", TomlSection(settings, "<test>", "analyses.open_loop"), &Ance());
}

// Open-loop steps from near the ground to 13 m, from just above the stall, nose up and nose down,
// on two models (scale.CMh), beside the flaky analysis (fails at x1 = 3 and 5): 3 x 3 x 3 x 2 x 3 = 162 runs.
SweepPlan MixedPlan() {
  Study study;
  study.path = "<test>";
  study.name = "lanes";
  study.aircraft = Ance();
  study.analyses.push_back(std::make_unique<FlakyAnalysis>());
  study.analyses.push_back(OpenLoop());
  study.chunk_runs = 256;
  study.design.kind = DesignKind::kGrid;
  study.design.parameters = {Axis("speed_mps", {25.2, 27.0, 34.0}), Axis("height_m", {1.3, 4.0, 13.0}),
                             Axis("pulse_amplitude_deg", {-6.0, 0.5, 4.0}), Axis("scale.CMh", {1.0, 1.3}),
                             Axis("x1", {1.0, 3.0, 5.0})};
  return SweepPlan(std::move(study), ShardSpec{});
}

bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// Every field of the two blocks' rows.
void ExpectSameRows(const ResultBlock& lanes, const ResultBlock& alone, const std::string& what) {
  ASSERT_EQ(lanes.rows, alone.rows);
  const auto rows = static_cast<std::size_t>(alone.rows);
  for (std::size_t r = 0; r < rows; ++r) {
    EXPECT_EQ(lanes.design_index[r], alone.design_index[r]) << what << " row " << r;
    EXPECT_EQ(lanes.run_id[r], alone.run_id[r]) << what << " row " << r;
    EXPECT_EQ(lanes.status[r], alone.status[r]) << what << " row " << r;
    EXPECT_EQ(lanes.message[r], alone.message[r]) << what << " row " << r;
  }
  for (std::size_t c = 0; c < alone.design.size(); ++c)
    EXPECT_TRUE(SameBits(lanes.design[c], alone.design[c])) << what << " design column " << c;
  for (std::size_t c = 0; c < alone.results.size(); ++c)
    EXPECT_TRUE(SameBits(lanes.results[c], alone.results[c])) << what << " result column " << c;
}

ResultBlock OneAtATime(const SweepPlan& plan) {
  ResultBlock block;
  block.Allocate(plan);
  block.Reset(plan, 0);
  RunWorkspace workspace(plan);
  for (int r = 0; r < block.rows; ++r)
    ExecuteRun(plan, block.design_index[static_cast<std::size_t>(r)], workspace, block, r);
  return block;
}

TEST(Lanes, GroupedRunsEqualEachRunAloneAtEveryWidthAndGrouping) {
  const SweepPlan plan = MixedPlan();
  ASSERT_TRUE(RunsInLanes(plan, 8));
  EXPECT_FALSE(RunsInLanes(plan, 1));
  const ResultBlock alone = OneAtATime(plan);
  // The runs exercise what lanes do differently: ends before the others (touchdown, stall), at the
  // time limit, and failed runs with their messages.
  std::set<int> events;
  const int end_event = ColumnIndex(plan, "results/open_loop/end_event");
  for (int r = 0; r < alone.rows; ++r) {
    events.insert(
        static_cast<int>(alone.results[static_cast<std::size_t>(end_event)][static_cast<std::size_t>(r)]));
  }
  EXPECT_EQ(events, (std::set<int>{static_cast<int>(OpenLoopEndEvent::kTouchdown),
                                   static_cast<int>(OpenLoopEndEvent::kStall),
                                   static_cast<int>(OpenLoopEndEvent::kTimeLimit)}));
  EXPECT_EQ(std::count(alone.status.begin(), alone.status.begin() + alone.rows,
                       static_cast<std::int8_t>(RunStatus::kFailed)),
            alone.rows * 2 / 3);
  EXPECT_EQ(alone.message[1], "flaky: exception: boom at 3");
  for (int width : kLaneWidths) {
    for (int group : {alone.rows, 7, 1}) {
      ResultBlock block;
      block.Allocate(plan);
      block.Reset(plan, 0);
      RunWorkspace workspace(plan);
      for (int first = 0; first < block.rows; first += group)
        ExecuteRuns(plan, workspace, block, first, std::min(group, block.rows - first), width);
      ExpectSameRows(block, alone, "width " + std::to_string(width) + ", groups of " + std::to_string(group));
    }
  }
}

TEST(Lanes, ACancelledGroupLeavesEveryRunPending) {
  const SweepPlan plan = MixedPlan();
  ResultBlock block;
  block.Allocate(plan);
  block.Reset(plan, 0);
  RunWorkspace workspace(plan);
  const std::atomic<bool> cancel{true};
  ExecuteRuns(plan, workspace, block, 0, 24, 4, &cancel);
  for (std::size_t r = 0; r < 24; ++r) {
    EXPECT_EQ(block.status[r], static_cast<std::int8_t>(RunStatus::kPending)) << r;
    EXPECT_EQ(block.message[r], "cancelled") << r;
  }
  EXPECT_EQ(block.status[24], static_cast<std::int8_t>(RunStatus::kPending))
      << "outside the group: untouched";
  EXPECT_EQ(block.message[24], "");
}

// A run SimulateOpenLoopBatch refuses (a start below the wheels, which a study's checks would refuse
// before the sweep) makes the batch throw before any run flies: every run then gets what Run gives
// it, the refused one its exception, the others their results.
TEST(Lanes, ARefusedRunGetsItsOwnExceptionAndTheOthersTheirResults) {
  const SweepPlan plan = MixedPlan();
  const Analysis& open_loop = *plan.study().analyses[1];
  ASSERT_EQ(open_loop.name(), "open_loop");
  const LongitudinalModel model(Ance(), ModelOptions{});
  const double heights[] = {5.0, 0.1, 2.0};  // the second below the wheel-contact height
  std::vector<RunParameters> parameters(3, plan.base_parameters());
  std::vector<RunContext> contexts;
  for (std::size_t i = 0; i < 3; ++i) {
    parameters[i][static_cast<std::size_t>(RequireParameter("height_m"))] = heights[i];
    parameters[i][static_cast<std::size_t>(RequireParameter("speed_mps"))] = 32.0;
    contexts.push_back(RunContext{parameters[i], &model, nullptr, i});
  }
  std::vector<std::vector<double>> lanes_columns;
  for (const OutputColumn& column : plan.schema().columns)
    lanes_columns.emplace_back(static_cast<std::size_t>(3 * column.doubles_per_run()));
  std::vector<std::vector<double>> alone_columns = lanes_columns;
  std::vector<OutputRow> lanes_rows, alone_rows;
  std::vector<LaneRun> runs;
  for (int i = 0; i < 3; ++i) {
    lanes_rows.emplace_back(&lanes_columns, &plan.schema(), i);
    alone_rows.emplace_back(&alone_columns, &plan.schema(), i);
  }
  for (std::size_t i = 0; i < 3; ++i) runs.push_back({&contexts[i], &lanes_rows[i], {}, {}});
  open_loop.RunLanes(runs, 2);
  for (std::size_t i = 0; i < 3; ++i) {
    std::string thrown;
    AnalysisOutcome outcome;
    try {
      outcome = open_loop.Run(contexts[i], alone_rows[i]);
    } catch (const std::exception& e) {
      thrown = e.what();
    }
    if (i == 1) {
      ASSERT_FALSE(thrown.empty());
      ASSERT_TRUE(runs[i].error);
      try {
        std::rethrow_exception(runs[i].error);
      } catch (const std::exception& e) {
        EXPECT_EQ(std::string(e.what()), thrown);
      }
      continue;
    }
    EXPECT_FALSE(runs[i].error) << i;
    EXPECT_EQ(runs[i].outcome.ok, outcome.ok) << i;
    EXPECT_EQ(runs[i].outcome.message, outcome.message) << i;
  }
  for (std::size_t c = 0; c < lanes_columns.size(); ++c)
    EXPECT_TRUE(SameBits(lanes_columns[c], alone_columns[c])) << plan.schema().columns[c].path;
}

}  // namespace
}  // namespace gesweep
