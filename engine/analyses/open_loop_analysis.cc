// Adapter: the `open_loop` analysis. The time response of docs/model.md §7 (the paper's Fig. 4):
// SimulateOpenLoop from the run's height and speed after an elevator input of the run's amplitude
// and duration; summary scalars always, time series when the study stores them.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "engine/analyses/analysis.h"
#include "engine/analyses/described_columns.h"
#include "engine/analyses/described_series.h"
#include "engine/common/describe_toml.h"
#include "engine/common/errors.h"
#include "engine/common/input_limits.h"
#include "engine/common/units.h"
#include "engine/simulation/open_loop.h"

namespace gesweep {
namespace {

// Measured (docs/sweep.md): RK4 at 0.015 s for 30 s, derivatives re-evaluated per stage, about 300 µs.
constexpr double kOpenLoopCost_us = 300.0;
constexpr double kDefaultDuration_s = 30.0;
// The runner's lane widths are the open loop's (a width it hands RunLanes is one SimulateOpenLoopBatch
// takes).
static_assert(std::ranges::equal(kLaneWidths, kOpenLoopBatchWidths));

class OpenLoopAnalysis final : public Analysis {
 public:
  explicit OpenLoopAnalysis(const OpenLoopConfig& config) : config_(config) {}

  std::string_view name() const override { return "open_loop"; }
  std::vector<ParameterId> parameters_used() const override {
    std::vector<ParameterId> used = {height_, speed_, amplitude_, duration_};
    const std::vector<ParameterId>& disturbance = DisturbanceParameterIds();
    used.insert(used.end(), disturbance.begin(), disturbance.end());
    return used;
  }
  double nominal_run_cost_us() const override {
    return kOpenLoopCost_us * config_.duration_s / kDefaultDuration_s;
  }

  void DeclareOutputs(OutputSchema& schema, const StorageOptions& storage) override {
    summary_.Declare(schema, "results/open_loop/");
    if (!storage.time_series) return;
    config_.series_interval_s = storage.output_dt_s;
    samples_ = series_.Declare(
        schema, "open_loop", "Time since the start of each open-loop run; samples after a run ended are NaN",
        config_.duration_s, storage.output_dt_s, config_.disturbance.pitch_rate_gust);
  }

  std::vector<FieldRecord> SettingsFields() const override { return ListFields(config_); }

  std::string CheckRun(const RunParameters& p, const Aircraft* aircraft) const override {
    const double touchdown = config_.touchdown_height_m.value_or(aircraft->wheel_contact_height_m);
    const double stall = config_.stall_speed_mps.value_or(aircraft->stall_speed_mps);
    std::ostringstream out;
    if (!(p[static_cast<std::size_t>(height_)] > touchdown)) {
      out << "expected height_m > the touchdown height " << touchdown << " m";
    } else if (!(p[static_cast<std::size_t>(speed_)] > stall)) {
      out << "expected speed_mps > the stall speed " << stall << " m/s";
    } else if (!(p[static_cast<std::size_t>(duration_)] > 0) &&
               config_.elevator.kind != ElevatorInputKind::kNone &&
               config_.elevator.kind != ElevatorInputKind::kStep) {
      out << "expected pulse_duration_s > 0 for a " << ToString(config_.elevator.kind);
    } else {
      // Bounded work (docs/limits.md): the noise table and the series of this run, before any run.
      OpenLoopConfig config = config_;
      ApplyDisturbanceParameters(p, config.disturbance);
      try {
        CheckOpenLoopWork(config, "open_loop");
      } catch (const InputError& e) {
        out << e.key() << " = " << e.value() << ": " << e.expected();
      }
    }
    return out.str();
  }

  AnalysisOutcome Run(const RunContext& context, OutputRow& row) const override {
    return Record(SimulateOpenLoop(*context.model, ConfigOf(context), context.cancel), row);
  }

  bool takes_lanes() const override { return true; }

  // The runs flown together by SimulateOpenLoopBatch, each result bit for bit its SimulateOpenLoop
  // run's (those the lanes do not take are flown one at a time inside it). A run it refuses (it
  // validates every run before flying any) makes it throw: every run of the group is then given to
  // Run, one at a time, so that each gets its own outcome or exception, as without lanes.
  void RunLanes(std::span<LaneRun> runs, int lanes) const override {
    FlyInLanes(
        runs, lanes,
        [&](const RunContext& c) {
          return OpenLoopBatchRun{c.model, ConfigOf(c)};
        },
        [](const auto& batch, int width, const auto* cancel) {
          return SimulateOpenLoopBatch(batch, width, cancel);
        },
        [&](const OpenLoopResult& r, OutputRow& row) { return Record(r, row); },
        [&] { Analysis::RunLanes(runs, lanes); });
  }

 private:
  // The run's settings: the study's, with the run's start condition, input and disturbance.
  OpenLoopConfig ConfigOf(const RunContext& context) const {
    OpenLoopConfig config = config_;
    config.start_height_m = context.value(height_);
    config.reference_speed_mps = context.value(speed_);
    // As OpenLoopConfig::Describe scales pulse_amplitude_deg (simulate's flag): a row replays bit for bit.
    config.elevator.amplitude_rad = context.value(amplitude_) * kRadiansPerDegree;
    config.elevator.duration_s = context.value(duration_);
    config.seed = ApplyDisturbanceParameters(context.parameters, config.disturbance);
    config.run_index = context.run_index;
    return config;
  }

  // Fills the row from a run's result; its outcome.
  AnalysisOutcome Record(const OpenLoopResult& result, OutputRow& row) const {
    const OpenLoopSummary& s = result.summary;
    if (s.cancelled) return AnalysisOutcome::Cancelled();
    summary_.Fill(s, row);
    if (samples_ > 0) series_.Store(result.series, row);
    if (s.end_event == OpenLoopEndEvent::kDiverged) {
      return AnalysisOutcome::Failed(s.message.empty() ? "diverged" : s.message);
    }
    return AnalysisOutcome::Ok(s.message);
  }

  OpenLoopConfig config_;
  ParameterId height_ = RequireParameter("height_m");
  ParameterId speed_ = RequireParameter("speed_mps");
  ParameterId amplitude_ = RequireParameter("pulse_amplitude_deg");
  ParameterId duration_ = RequireParameter("pulse_duration_s");
  DescribedColumns<OpenLoopSummary> summary_;
  DescribedSeries<OpenLoopSeries> series_;
  int samples_ = 0;
};

}  // namespace

std::unique_ptr<Analysis> MakeOpenLoopAnalysis(const TomlSection& settings, const Aircraft*) {
  OpenLoopConfig config;
  config.duration_s = kDefaultDuration_s;
  // Every key of OpenLoopConfig::Describe, each number against the limits table (docs/limits.md).
  ReadFields(settings, config);
  try {
    ValidateIntegratorOptions(config.integrator, settings.source());
    // Bounded work: refused here, before the first run, not as a failed run later.
    const bool rk4 = config.integrator.kind == IntegratorKind::kRk4;
    const double& step_s = rk4 ? config.integrator.step_s : config.integrator.max_step_s;
    CheckStepCount(config.duration_s, step_s, settings.source(),
                   std::string(KeyOf(config, &config.duration_s)), std::string(KeyOf(config, &step_s)));
  } catch (const InputError& e) {
    settings.Fail(e.key(), e.value(), e.expected());
  }
  return std::make_unique<OpenLoopAnalysis>(config);
}

const AnalysisRegistrar kRegistrar{{"open_loop",
                                    "Open-loop time response to an elevator input from height_m at speed_mps "
                                    "(docs/model.md section 7, the paper's Fig. 4).",
                                    true, &MakeOpenLoopAnalysis, 400}};

}  // namespace gesweep
