// gesweep land: the closed-loop automatic landing of docs/model.md §8 (glide-slope coupler, flare, one
// LQR gain), flown on the re-evaluated model with or without h-derivatives (docs/landing.md; the paper's
// Fig. 6–9).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "engine/analyses/records.h"
#include "engine/cli/command.h"
#include "engine/cli/described_flags.h"
#include "engine/cli/described_output.h"
#include "engine/cli/model_flags.h"
#include "engine/cli/record_json.h"
#include "engine/cli/series_output.h"
#include "engine/cli/signals.h"
#include "engine/common/errors.h"
#include "engine/control/landing_simulation.h"

namespace gesweep::cli {
namespace {

// Ordered JSON keeps the summary's fields in the order written here (also the CSV column order).
using Json = nlohmann::ordered_json;

// Today's names of flags whose key-derived name differs (docs/landing.md): kept as aliases.
std::vector<FlagAlias> LandAliases() {
  return {
      {"start_speed_mps", "--speed-mps"},    {"start_glide_path_offset_m", "--start-offset-m"},
      {"flare_time_constant_s", "--tau-s"},  {"plant_fixed_reference_height_m", "--plant-reference-height-m"},
      {"relative_tolerance", "--rtol"},      {"absolute_tolerance", "--atol"},
      {"output_interval_s", "--output-dt-s"}};
}

struct LandFlags {
  ModelFlags model;
  LandingConfig config;  // its fields are flags (LandingConfig::Describe); defaults as the struct's
  DescribedFlags described{LandAliases()};
  bool summary_only = false;
  std::string format = "csv";
};

std::string Number(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  if (value == 0.0) value = 0.0;  // no "-0"
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.10g", value);
  return buffer;
}

// The flag of one of ValidateLandingConfig's keys, as the person typed it: a weight of q_weights is
// `--q-weights (<state>)`, the automatic time limit `--time-limit-s (automatic)`.
std::string FlagOf(const DescribedFlags& described, const std::string& key) {
  if (key.rfind("q_weights.", 0) == 0) return "--q-weights (" + key.substr(10) + ")";
  const std::string automatic = " (automatic)";
  if (key.ends_with(automatic))
    return described.FlagOf(key.substr(0, key.size() - automatic.size())) + automatic;
  return described.FlagOf(key);
}

LandingConfig BuildConfig(const LandFlags& flags, const LongitudinalModel& model) {
  LandingConfig config = flags.config;
  if (flags.summary_only) config.output_interval_s = 0.0;
  try {
    ValidateLandingConfig(config, model.aircraft(), "command line");
  } catch (const InputError& error) {
    std::string expected = error.expected();
    for (const char* field : {"time_limit_s", "max_step_s", "turbulence_sample_interval_s",
                              "output_interval_s"}) {  // inside the step-count and work sentences
      const std::string from = std::string(field) + " ";
      const auto at = expected.find(from);
      if (at != std::string::npos)
        expected.replace(at, std::string(field).size(), flags.described.FlagOf(field));
    }
    throw InputError("command line", FlagOf(flags.described, error.key()), error.value(), expected);
  }
  const double time_limit_s = LandingTimeLimit(config, model.aircraft().wheel_contact_height_m);
  if (config.output_interval_s > 0.0 && time_limit_s / config.output_interval_s > 1e7) {
    throw InputError("command line", flags.described.FlagOf("output_interval_s"),
                     Number(config.output_interval_s), "expected at most 1e7 samples");
  }
  return config;
}

// The summary's fields (LandingResult::Describe) in their order, and the design.
Json SummaryJson(const LandingResult& r) {
  Json summary = FieldsJson<LandingResult, Json>(r);
  summary["design"] = RecordJson<Json>([&](auto& sink) { DesignRecord(r.design, sink); });
  return summary;
}

int RunLand(const LandFlags& flags) {
  if (flags.format != "csv" && flags.format != "json") {
    throw InputError("command line", "--format", "'" + flags.format + "'", "expected csv or json");
  }
  const LongitudinalModel model = flags.model.BuildModel();
  const LandingConfig config = BuildConfig(flags, model);
  const SignalCancellation signals;
  const LandingResult result = SimulateLanding(model, config, signals.flag());
  if (result.cancelled) {
    std::cerr << "gesweep: land stopped by signal " << signals.signal()
              << " at t = " << Number(result.final_time_s) << " s; nothing written\n";
    return signals.exit_code();
  }
  const int exit_code = result.outcome == LandingOutcome::kDesignFailed ? 3 : 0;

  if (flags.format == "json") {
    Json series = nullptr;
    if (!flags.summary_only) series = SeriesJson<Json>(result.series, LandingSeriesContents(config));
    std::cout << Json{{"run",
                       RecordJson<Json>([&](auto& sink) { LandingRunRecord(config, result, model, sink); })},
                      {"summary", SummaryJson(result)},
                      {"series", series}}
                     .dump(1)
              << "\n";
    return exit_code;
  }

  std::string out;
  if (flags.summary_only) {
    out += CsvHeader(result) + "\n" + CsvRow(result, Number) + "\n";
  } else {
    out += SeriesCsv(result.series, LandingSeriesContents(config), Number);
  }
  std::cout << out;
  if (result.outcome == LandingOutcome::kDesignFailed)
    std::cerr << "gesweep land: " << result.message << "\n";
  return exit_code;
}

const CommandRegistrar kRegistrar{Command{
    "land",
    "Closed-loop automatic landing: LQR glide-slope coupler and exponential flare with one gain, on the "
    "re-evaluated model (docs/model.md section 8; the paper's Fig. 6-9)",
    [](CLI::App& app) -> std::function<int()> {
      auto flags = std::make_shared<LandFlags>();
      flags->model.AddTo(app);
      flags->described.Add(app, flags->config);
      auto* summary =
          app.add_flag("--summary-only", flags->summary_only, "Write the summary only, no series");
      for (CLI::Option* output_dt : flags->described.OptionsOf("output_interval_s"))
        output_dt->excludes(summary);
      app.add_option("--format", flags->format,
                     "csv (default: the series; with --summary-only one summary row) or json "
                     "({\"run\", \"summary\", \"series\"})");
      return [flags] {
        flags->described.Apply();
        return RunLand(*flags);
      };
    }}};

}  // namespace
}  // namespace gesweep::cli
