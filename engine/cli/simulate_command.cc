// gesweep simulate: one open-loop time response of Eq. (1) with the derivatives re-evaluated at the
// current height and speed (docs/model.md §7, docs/simulation.md): the paper's Fig. 4 runs.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <numbers>
#include <string>

#include "engine/analyses/records.h"
#include "engine/cli/command.h"
#include "engine/cli/described_flags.h"
#include "engine/cli/described_output.h"
#include "engine/cli/json_util.h"
#include "engine/cli/model_flags.h"
#include "engine/cli/record_json.h"
#include "engine/cli/series_output.h"
#include "engine/cli/signals.h"
#include "engine/common/errors.h"
#include "engine/simulation/open_loop.h"

namespace gesweep::cli {
namespace {

// Today's names of flags whose key-derived name differs (docs/simulation.md): kept as aliases.
std::vector<FlagAlias> SimulateAliases() {
  return {{"step_s", "--dt-s"},
          {"relative_tolerance", "--rtol"},
          {"absolute_tolerance", "--atol"},
          {"pulse_amplitude_deg", "--elevator-deg"},
          {"pulse_duration_s", "--pulse-s"},
          {"honour_breakpoints", "--no-breakpoints"},
          {"freeze_derivatives", "--frozen"}};
}

struct SimulateFlags {
  ModelFlags model;
  OpenLoopConfig config;  // its fields are flags (OpenLoopConfig::Describe); defaults as the struct's
  DescribedFlags described{SimulateAliases()};
  double output_dt_s = std::nan("");  // default: the step
  bool summary_only = false;
  std::string format = "csv";
  // The run's turbulence is RunNoise(seed, run_index): a sweep's run i replays with its seed and i.
  std::uint64_t seed = 0;
  std::uint64_t run_index = 0;
};

// Each flag's own range is checked as it is parsed (AddLimitedOption); here what depends on the
// aircraft or on several flags (ValidateOpenLoopConfig), in the flags' names.
OpenLoopConfig BuildConfig(const SimulateFlags& flags, const LongitudinalModel& model) {
  OpenLoopConfig config = flags.config;
  config.seed = flags.seed;
  config.run_index = flags.run_index;
  if (!flags.summary_only) {
    const double output_dt = std::isnan(flags.output_dt_s) ? config.integrator.step_s : flags.output_dt_s;
    if (config.duration_s / output_dt > 1e7) {
      throw InputError("command line", "--output-dt-s", FormatNumber(output_dt),
                       "expected at most 1e7 samples");
    }
    config.series_interval_s = output_dt;
  }
  try {
    ValidateOpenLoopConfig(model, config, "command line");  // the step count among others
  } catch (const InputError& e) {
    if (e.key() == "series_interval_s")
      throw InputError("command line", "--output-dt-s", e.value(), e.expected());
    flags.described.Rethrow(e);
  }
  return config;
}

std::string Number(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.10g", value);
  return buffer;
}

int RunSimulate(const SimulateFlags& flags) {
  flags.described.Apply();
  RequireFormat(flags.format, {"csv", "json"});
  const LongitudinalModel model = flags.model.BuildModel();
  const OpenLoopConfig config = BuildConfig(flags, model);
  const SignalCancellation signals;
  const OpenLoopResult result = SimulateOpenLoop(model, config, signals.flag());
  if (result.summary.cancelled) {
    std::cerr << "gesweep: simulate stopped by signal " << signals.signal()
              << " at t = " << ShortNumber(result.summary.end_time_s) << " s of "
              << ShortNumber(config.duration_s) << " s; nothing written\n";
    return signals.exit_code();
  }

  if (flags.format == "json") {
    nlohmann::json series = nullptr;
    if (!flags.summary_only) series = SeriesJson<nlohmann::json>(result.series, result.series.contents());
    // The settings under their keys (OpenLoopConfig::Describe), in the keys' units, and the model.
    const auto run = RecordJson<nlohmann::json>([&](auto& sink) { OpenLoopRunRecord(config, model, sink); });
    std::cout
        << nlohmann::json{{"run", run}, {"summary", FieldsJson(result.summary)}, {"series", series}}.dump(1)
        << "\n";
    return 0;
  }

  std::string out;
  if (flags.summary_only) {
    out += CsvHeader(result.summary) + "\n" + CsvRow(result.summary, Number) + "\n";
  } else {
    out += SeriesCsv(result.series, result.series.contents(), Number);
  }
  std::cout << out;
  return 0;
}

void AddSimulateFlags(CLI::App& app, SimulateFlags& flags) {
  flags.model.AddTo(app);
  flags.described.Add(app, flags.config, {"height_m", "speed_mps"});
  auto* output_dt =
      AddLimitedOption(app, "--output-dt-s", flags.output_dt_s, "output_dt_s",
                       "Series sampling interval, s (interpolated inside steps); default --step-s");
  auto* summary = app.add_flag("--summary-only", flags.summary_only, "Write the summary only, no series");
  output_dt->excludes(summary);
  AddExactIntegerOption(app, "--seed", flags.seed, "seed",
                        "Seed of the turbulence (a sweep's seed parameter); default 0 (docs/disturbance.md)");
  AddExactIntegerOption(
      app, "--run-index", flags.run_index, "run_index",
      "Run index i of the turbulence RunNoise(seed, i): replays run i of a sweep; default 0");
  app.add_option("--format", flags.format,
                 "csv (default: the time series; with --summary-only one summary row) or json "
                 "({\"run\", \"summary\", \"series\"})");
}

const CommandRegistrar kRegistrar{CommandWith<SimulateFlags>(
    "simulate",
    "Open-loop time response of Eq. (1) after an elevator input, derivatives re-evaluated at the current "
    "height and speed (docs/model.md section 7; the paper's Fig. 4)",
    AddSimulateFlags, RunSimulate)};

}  // namespace
}  // namespace gesweep::cli
