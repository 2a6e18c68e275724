// Adapter: the `landing` analysis. The closed-loop automatic landing of docs/model.md §8 (the
// paper's Fig. 6-9): SimulateLanding from the run's start height and speed, glide slope, flare and
// LQR weights, on the run's plant (h-derivatives on or off as its model says). Summary scalars and
// the gain always; time series when the study stores them.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "engine/analyses/analysis.h"
#include "engine/analyses/described_columns.h"
#include "engine/analyses/described_series.h"
#include "engine/common/describe_toml.h"
#include "engine/control/landing_simulation.h"

namespace gesweep {
namespace {

// Measured (docs/sweep.md): a dopri5 landing from 500 m and one Riccati solution, about 15 ms.
constexpr double kLandingCost_us = 15000.0;
// Stored series cover this long unless the study says otherwise (the paper's landing from 500 m at
// 52.21 m/s down a 2.5° slope lasts about 230 s).
constexpr double kDefaultSeriesDuration_s = 400.0;

// The flight condition a landing starts from (the run parameters height_m and speed_mps, every
// analysis's); its other run parameters are LandingConfig's own (RunParameter, a NaN
// flare_time_constant_s: the automatic time constant), the Q weights and the moving atmosphere's.
constexpr std::pair<const char*, double LandingConfig::*> kStartCondition[] = {
    {"height_m", &LandingConfig::start_height_m}, {"speed_mps", &LandingConfig::start_speed_mps}};

// LandingConfig's own run parameters, less the moving atmosphere's (DisturbanceParameterIds).
std::vector<ParameterId> LandingParameterIds() {
  std::vector<ParameterId> ids;
  const std::vector<ParameterId>& atmosphere = DisturbanceParameterIds();
  for (ParameterId id : RunParameterIds<LandingConfig>()) {
    if (std::find(atmosphere.begin(), atmosphere.end(), id) == atmosphere.end()) ids.push_back(id);
  }
  return ids;
}

// The [analyses.landing] table: the landing's settings, and how long its stored series last.
struct LandingStudySettings {
  LandingConfig config;
  double series_duration_s = kDefaultSeriesDuration_s;

  template <class V>
  void Describe(V& v) {
    config.Describe(v);
    v(Field("series_duration_s", &series_duration_s)
          .Unit("s")
          .Limit("landing.series_duration_s")
          .StudyOnly()
          .Doc("How long the stored series last, s (samples after a run ended are NaN)"));
  }
};

class LandingAnalysis final : public Analysis {
 public:
  explicit LandingAnalysis(const LandingStudySettings& settings)
      : settings_(settings), config_(settings.config), series_duration_s_(settings.series_duration_s) {
    for (const auto& [name, setting] : kStartCondition) start_.emplace_back(RequireParameter(name), setting);
  }

  std::string_view name() const override { return "landing"; }
  std::vector<ParameterId> parameters_used() const override {
    std::vector<ParameterId> ids;
    for (const auto& [id, setting] : start_) ids.push_back(id);
    const std::vector<ParameterId> own = LandingParameterIds();
    ids.insert(ids.end(), own.begin(), own.end());
    const std::vector<ParameterId>& disturbance = DisturbanceParameterIds();
    ids.insert(ids.end(), disturbance.begin(), disturbance.end());
    return ids;
  }
  double nominal_run_cost_us() const override { return kLandingCost_us; }
  std::vector<FieldRecord> SettingsFields() const override { return ListFields(settings_); }

  void DeclareOutputs(OutputSchema& schema, const StorageOptions& storage) override {
    const std::string base = "results/landing/";
    summary_.Declare(schema, base);
    OutputColumn gain = OutputColumn::Real(
        base + "gain", "rad per unit state",
        "LQR gain K on the 9 states of Eq. (14), eta_e = -K z (component_names attribute)");
    gain.width = kLandingStateCount;
    for (std::string_view state : LandingStateNames()) gain.component_names.emplace_back(state);
    gain_ = schema.Add(gain);
    if (!storage.time_series) {
      config_.output_interval_s = 0.0;
      return;
    }
    config_.output_interval_s = storage.output_dt_s;
    samples_ = series_.Declare(schema, "landing",
                               "Time since the start of each landing; samples after a run ended are NaN",
                               series_duration_s_, storage.output_dt_s, config_.disturbance.pitch_rate_gust);
  }

  std::string CheckRun(const RunParameters& p, const Aircraft* aircraft) const override {
    try {
      ValidateLandingConfig(ConfigFor(p), *aircraft, "landing");
    } catch (const InputError& e) {
      return e.key() + (e.value().empty() ? "" : " = " + e.value()) + ": " + e.expected();
    }
    return "";
  }

  AnalysisOutcome Run(const RunContext& context, OutputRow& row) const override {
    const LandingResult r =
        SimulateLanding(*context.model, ConfigOf(context), context.cancel, context.noise_point);
    return Record(r, row);
  }

  bool takes_lanes() const override { return true; }

  // The landings flown together by SimulateLandingBatch, each result bit for bit its SimulateLanding
  // landing's (those the lanes do not take, still air among them, are flown one at a time inside it).
  // A landing it refuses (it validates every one before flying any) makes it throw: every landing of
  // the group is then given to Run, one at a time, so that each gets its own outcome or exception, as
  // without lanes.
  void RunLanes(std::span<LaneRun> runs, int lanes) const override {
    FlyInLanes(
        runs, lanes,
        [&](const RunContext& c) {
          return LandingBatchRun{c.model, ConfigOf(c), c.noise_point};
        },
        [](const auto& batch, int width, const auto* cancel) {
          return SimulateLandingBatch(batch, width, cancel);
        },
        [&](const LandingResult& r, OutputRow& row) { return Record(r, row); },
        [&] { Analysis::RunLanes(runs, lanes); });
  }

  std::uint64_t NoiseDimension(const RunParameters& parameters, const Aircraft& aircraft) const override {
    return LandingNoiseDimension(aircraft, ConfigFor(parameters));
  }

  double NoiseSampleInterval(const RunParameters& parameters) const override {
    return ConfigFor(parameters).disturbance.turbulence_sample_interval_s;
  }

 private:
  // The run's settings: the study's with the run's parameters and index.
  LandingConfig ConfigOf(const RunContext& context) const {
    LandingConfig config = ConfigFor(context.parameters);
    config.run_index = context.run_index;
    return config;
  }

  // The run's columns and outcome from its landing.
  AnalysisOutcome Record(const LandingResult& r, OutputRow& row) const {
    if (r.cancelled) return AnalysisOutcome::Cancelled();
    summary_.Fill(r, row);
    if (r.design.ok()) {
      double* gain = row.Slot(gain_);
      for (int i = 0; i < kLandingStateCount; ++i) gain[i] = r.design.gain[static_cast<std::size_t>(i)];
    }
    bool truncated = false;
    if (samples_ > 0) truncated = series_.Store(r.series, row);
    const std::string note =
        truncated ? r.message + " (series cut at " + ShortNumber(series_duration_s_) + " s)" : r.message;
    if (r.outcome == LandingOutcome::kDiverged || r.outcome == LandingOutcome::kDesignFailed) {
      return AnalysisOutcome::Failed(std::string(ToString(r.outcome)) + ": " + note);
    }
    return AnalysisOutcome::Ok(r.outcome == LandingOutcome::kLanded && !truncated ? "" : note);
  }

  LandingConfig ConfigFor(const RunParameters& p) const {
    auto at = [&](ParameterId id) { return p[static_cast<std::size_t>(id)]; };
    LandingConfig config = config_;
    for (const auto& [id, setting] : start_) config.*setting = at(id);
    ApplyRunParameters(p, config);  // its own (the Q weights too) and the moving atmosphere's
    config.seed = static_cast<std::uint64_t>(at(DisturbanceParameterIds().back()));
    return config;
  }

  LandingStudySettings settings_;  // as the study gave them
  LandingConfig config_;           // with the storage's series interval
  double series_duration_s_;
  std::vector<std::pair<ParameterId, double LandingConfig::*>> start_;  // kStartCondition
  DescribedColumns<LandingResult> summary_;
  int gain_ = 0;
  DescribedSeries<std::vector<LandingSample>> series_;
  int samples_ = 0;
};

}  // namespace

std::unique_ptr<Analysis> MakeLandingAnalysis(const TomlSection& settings, const Aircraft*) {
  LandingStudySettings study;
  // Every key of LandingConfig::Describe and series_duration_s, each number against the limits table
  // (docs/limits.md), with the study's file and line; what depends on the run's parameters is checked
  // on the design's extreme runs (CheckRun).
  ReadFields(settings, study);
  const double asymptote_m = study.config.flare_asymptote_m;
  if (!(std::isfinite(asymptote_m) && asymptote_m >= 0.0)) {
    settings.Fail(KeyOf(study, &study.config.flare_asymptote_m), ShortNumber(asymptote_m),
                  "expected a height >= 0 m below the flare height (0: the ground, the paper's)");
  }
  return std::make_unique<LandingAnalysis>(study);
}

const AnalysisRegistrar kRegistrar{{"landing",
                                    "The closed-loop automatic landing from height_m at speed_mps "
                                    "(docs/model.md section 8, the paper's Fig. 6-9); docs/landing.md.",
                                    true, &MakeLandingAnalysis, 500}};

}  // namespace gesweep
