// Adapter: the `open_loop` analysis. The time response of docs/model.md §7 (the paper's Fig. 4):
// SimulateOpenLoop from the run's height and speed after an elevator input of the run's amplitude
// and duration; summary scalars always, time series when the study stores them.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "engine/analyses/analysis.h"
#include "engine/analyses/described_columns.h"
#include "engine/common/describe_toml.h"
#include "engine/common/errors.h"
#include "engine/common/input_limits.h"
#include "engine/simulation/open_loop.h"

namespace gesweep {
namespace {

// Measured (docs/sweep.md): RK4 at 0.015 s for 30 s, derivatives re-evaluated per stage, about 300 µs.
constexpr double kOpenLoopCost_us = 300.0;
constexpr double kDefaultDuration_s = 30.0;
// A sample lands on the series grid when within this of a grid time (the integrator's output times
// are t0 + j·dt, computed in floating point).
constexpr double kGridTolerance_s = 1e-9;
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
    dt_s_ = storage.output_dt_s;
    config_.series_interval_s = dt_s_;
    TimeAxis axis;
    axis.path = "series/open_loop/time_s";
    axis.description = "Time since the start of each open-loop run; samples after a run ended are NaN";
    const auto samples = static_cast<int>(std::floor(config_.duration_s / dt_s_ + kGridTolerance_s)) + 1;
    for (int k = 0; k < samples; ++k) axis.times_s.push_back(k * dt_s_);
    schema.AddAxis(axis);
    const std::string series = "series/open_loop/";
    series_height_ =
        schema.Add(OutputColumn::Series(series + "height_m", "m", "Height H", axis.path, samples));
    series_speed_ =
        schema.Add(OutputColumn::Series(series + "speed_mps", "m/s", "Speed u", axis.path, samples));
    series_w_ = schema.Add(
        OutputColumn::Series(series + "delta_w_mps", "m/s", "Delta w (positive down)", axis.path, samples));
    series_q_ = schema.Add(
        OutputColumn::Series(series + "pitch_rate_radps", "rad/s", "Pitch rate q", axis.path, samples));
    series_theta_ = schema.Add(
        OutputColumn::Series(series + "delta_theta_rad", "rad", "Delta theta", axis.path, samples));
    series_elevator_ = schema.Add(OutputColumn::Series(series + "elevator_rad", "rad",
                                                       "Elevator deflection (positive trailing edge down)",
                                                       axis.path, samples));
    // The air motion the airplane met (docs/model.md §9): 0 in still air.
    series_u_g_ = schema.Add(OutputColumn::Series(
        series + "u_g_mps", "m/s",
        "Air velocity along x at the airplane: mean wind + turbulence + a u gust (a headwind is negative)",
        axis.path, samples));
    series_w_g_ = schema.Add(OutputColumn::Series(
        series + "w_g_mps", "m/s",
        "Air velocity along z at the airplane (positive down): turbulence + a w gust", axis.path, samples));
    if (config_.disturbance.pitch_rate_gust) {
      series_q_g_ = schema.Add(OutputColumn::Series(series + "q_g_radps", "rad/s",
                                                    "Pitch-rate gust q_g (Dryden)", axis.path, samples));
    }
    samples_ = samples;
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
    if (runs.empty()) return;
    const std::atomic<bool>* cancel = runs.front().context->cancel;
    std::vector<OpenLoopBatchRun> batch;
    batch.reserve(runs.size());
    for (const LaneRun& run : runs) {
      GESWEEP_DEMAND(run.context->cancel == cancel);
      batch.push_back({run.context->model, ConfigOf(*run.context)});
    }
    std::vector<OpenLoopResult> results;
    try {
      results = SimulateOpenLoopBatch(batch, lanes, cancel);
    } catch (...) {
      Analysis::RunLanes(runs, lanes);
      return;
    }
    for (std::size_t i = 0; i < runs.size(); ++i) runs[i].outcome = Record(results[i], *runs[i].row);
  }

 private:
  // The run's settings: the study's, with the run's start condition, input and disturbance.
  OpenLoopConfig ConfigOf(const RunContext& context) const {
    OpenLoopConfig config = config_;
    config.start_height_m = context.value(height_);
    config.reference_speed_mps = context.value(speed_);
    config.elevator.amplitude_rad = context.value(amplitude_) * std::numbers::pi / 180.0;
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
    if (samples_ > 0) StoreSeries(result.series, row);
    if (s.end_event == OpenLoopEndEvent::kDiverged) {
      return AnalysisOutcome::Failed(s.message.empty() ? "diverged" : s.message);
    }
    return AnalysisOutcome::Ok(s.message);
  }

  // The simulation samples every dt and once more at the end; keep the samples on the grid.
  void StoreSeries(const OpenLoopSeries& series, OutputRow& row) const {
    const std::pair<int, const std::vector<double>*> columns[] = {
        {series_height_, &series.height_m},
        {series_speed_, &series.speed_mps},
        {series_w_, &series.delta_normal_velocity_mps},
        {series_q_, &series.pitch_rate_radps},
        {series_theta_, &series.delta_pitch_rad},
        {series_elevator_, &series.elevator_rad}};
    const bool air = !series.u_g_mps.empty();
    const bool pitch_gust = series_q_g_ >= 0;
    for (std::size_t i = 0; i < series.time_s.size(); ++i) {
      const double position = series.time_s[i] / dt_s_;
      const double k = std::round(position);
      if (std::abs(position - k) * dt_s_ > kGridTolerance_s || k < 0 || k >= samples_) continue;
      const int sample = static_cast<int>(k);
      for (const auto& [column, values] : columns) row.Slot(column)[sample] = (*values)[i];
      row.Slot(series_u_g_)[sample] = air ? series.u_g_mps[i] : 0.0;
      row.Slot(series_w_g_)[sample] = air ? series.w_g_mps[i] : 0.0;
      if (pitch_gust) row.Slot(series_q_g_)[sample] = air ? series.q_g_radps[i] : 0.0;
    }
  }

  OpenLoopConfig config_;
  ParameterId height_ = RequireParameter("height_m");
  ParameterId speed_ = RequireParameter("speed_mps");
  ParameterId amplitude_ = RequireParameter("pulse_amplitude_deg");
  ParameterId duration_ = RequireParameter("pulse_duration_s");
  DescribedColumns<OpenLoopSummary> summary_;
  int series_height_ = 0, series_speed_ = 0, series_w_ = 0, series_q_ = 0, series_theta_ = 0,
      series_elevator_ = 0, series_u_g_ = 0, series_w_g_ = 0;
  int series_q_g_ = -1;
  int samples_ = 0;
  double dt_s_ = 0;
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
