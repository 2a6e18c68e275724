// gesweep simulate: one open-loop time response of Eq. (1) with the derivatives re-evaluated at the
// current height and speed (docs/model.md §7, docs/simulation.md): the paper's Fig. 4 runs.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <numbers>
#include <string>

#include "engine/cli/command.h"
#include "engine/cli/json_util.h"
#include "engine/cli/model_flags.h"
#include "engine/cli/signals.h"
#include "engine/common/errors.h"
#include "engine/simulation/open_loop.h"

namespace gesweep::cli {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;

struct SimulateFlags {
  ModelFlags model;
  double height_m = std::nan("");
  double speed_mps = std::nan("");
  std::string input = "pulse";
  double elevator_deg = 5.0;
  double pulse_s = 0.2;
  double input_start_s = 0.0;
  std::string integrator = "rk4";
  double dt_s = 0.015;
  double rtol = 1e-6;
  double atol = 1e-9;
  double max_step_s = 0.0;
  bool no_breakpoints = false;
  double duration_s = 300.0;
  double output_dt_s = std::nan("");  // default: dt_s
  bool summary_only = false;
  bool frozen = false;
  double initial_delta_u_mps = 0, initial_delta_w_mps = 0, initial_pitch_rate_degps = 0;
  double initial_pitch_deg = 0, initial_delta_h_m = 0;
  std::string format = "csv";
};

[[noreturn]] void Refuse(const std::string& flag, double value, const std::string& expected) {
  throw InputError("command line", flag, FormatNumber(value), expected);
}

// Maps ValidateOpenLoopConfig's field names to the flags a person typed.
std::string FlagOf(const std::string& key) {
  static const std::pair<const char*, const char*> kFlags[] = {
      {"start_height_m", "--height-m"},
      {"reference_speed_mps", "--speed-mps"},
      {"duration_s", "--duration-s"},
      {"step_s", "--dt-s"},
      {"max_step_s", "--max-step-s"},
      {"relative_tolerance", "--rtol"},
      {"absolute_tolerance", "--atol"},
      {"series_interval_s", "--output-dt-s"},
      {"elevator.start_s", "--input-start-s"},
      {"elevator.duration_s", "--pulse-s"},
      {"initial_offsets.delta_speed_mps", "--initial-delta-u-mps"},
      {"initial_offsets.delta_normal_velocity_mps", "--initial-delta-w-mps"},
      {"initial_offsets.delta_height_m", "--initial-delta-h-m"},
  };
  for (const auto& [field, flag] : kFlags) {
    if (key == field) return flag;
  }
  return key;
}

// Each flag's own range is checked as it is parsed (AddLimitedOption); here what depends on the
// aircraft or on several flags, then the library's validation as a backstop, in the flags' names.
OpenLoopConfig BuildConfig(const SimulateFlags& flags, const LongitudinalModel& model) {
  const Aircraft& aircraft = model.aircraft();
  OpenLoopConfig config;
  if (!(flags.speed_mps + flags.initial_delta_u_mps > aircraft.stall_speed_mps)) {
    Refuse("--speed-mps", flags.speed_mps + flags.initial_delta_u_mps,
           "expected a start speed above the stall speed " + FormatNumber(aircraft.stall_speed_mps) + " m/s of " +
               aircraft.source_path);
  }
  if (!(flags.height_m + flags.initial_delta_h_m > aircraft.wheel_contact_height_m)) {
    Refuse("--height-m", flags.height_m + flags.initial_delta_h_m,
           "expected a start height above the wheel-contact height " + FormatNumber(aircraft.wheel_contact_height_m) +
               " m of " + aircraft.source_path + " (a run cannot start on the ground)");
  }
  config.start_height_m = flags.height_m;
  config.reference_speed_mps = flags.speed_mps;

  const auto kind = ParseElevatorInputKind(flags.input);
  if (!kind) throw InputError("command line", "--input", "'" + flags.input + "'", "expected pulse, step, doublet or none");
  if ((*kind == ElevatorInputKind::kPulse || *kind == ElevatorInputKind::kDoublet) && !(flags.pulse_s > 0.0)) {
    Refuse("--pulse-s", flags.pulse_s, "expected a pulse length > 0 s for a " + flags.input);
  }
  config.elevator = {*kind, flags.elevator_deg * kRadPerDeg, flags.input_start_s, flags.pulse_s};

  const auto integrator = ParseIntegratorKind(flags.integrator);
  if (!integrator) throw InputError("command line", "--integrator", "'" + flags.integrator + "'", "expected rk4 or dopri5");
  config.integrator.kind = *integrator;
  config.integrator.step_s = flags.dt_s;
  config.integrator.relative_tolerance = flags.rtol;
  config.integrator.absolute_tolerance = flags.atol;
  config.integrator.max_step_s = flags.max_step_s;
  config.integrator.honour_breakpoints = !flags.no_breakpoints;
  config.duration_s = flags.duration_s;
  if (!flags.summary_only) {
    const double output_dt = std::isnan(flags.output_dt_s) ? flags.dt_s : flags.output_dt_s;
    if (flags.duration_s / output_dt > 1e7) Refuse("--output-dt-s", output_dt, "expected at most 1e7 samples");
    config.series_interval_s = output_dt;
  }
  config.freeze_derivatives = flags.frozen;
  config.initial_offsets = {flags.initial_delta_u_mps, flags.initial_delta_w_mps,
                            flags.initial_pitch_rate_degps * kRadPerDeg, flags.initial_pitch_deg * kRadPerDeg,
                            flags.initial_delta_h_m};
  try {
    ValidateOpenLoopConfig(model, config, "command line");  // the step count among others
  } catch (const InputError& e) {
    std::string expected = e.expected();
    for (const char* field : {"duration_s", "max_step_s", "step_s"}) {  // inside the step-count sentence
      const std::string from = std::string(field) + " = ";
      const auto at = expected.find(from);
      if (at != std::string::npos) expected.replace(at, std::string(field).size(), FlagOf(field));
    }
    throw InputError("command line", FlagOf(e.key()), e.value(), expected);
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

nlohmann::json SummaryJson(const OpenLoopSummary& s) {
  nlohmann::json state = nlohmann::json::array();
  for (int i = 0; i < 5; ++i) state.push_back(JsonNumber(s.final_state[i]));
  return {{"end_event", std::string(ToString(s.end_event))},
          {"end_time_s", JsonNumber(s.end_time_s)},
          {"min_height_m", JsonNumber(s.min_height_m)},
          {"min_height_time_s", JsonNumber(s.min_height_time_s)},
          {"max_abs_pitch_rate_radps", JsonNumber(s.max_abs_pitch_rate_radps)},
          {"final_state", state},
          {"final_state_names", {"delta_speed_mps", "delta_normal_velocity_mps", "pitch_rate_radps",
                                 "delta_pitch_rad", "delta_height_m"}},
          {"final_height_m", JsonNumber(s.final_height_m)},
          {"final_speed_mps", JsonNumber(s.final_speed_mps)},
          {"steps", s.steps},
          {"rejected_steps", s.rejected_steps},
          {"rhs_calls", s.rhs_calls},
          {"message", s.message}};
}

// Column names (unit-suffixed) and the series columns, in the CSV and JSON order.
std::vector<std::pair<const char*, const std::vector<double>*>> SeriesColumns(const OpenLoopSeries& s) {
  return {{"time_s", &s.time_s},
          {"delta_speed_mps", &s.delta_speed_mps},
          {"delta_normal_velocity_mps", &s.delta_normal_velocity_mps},
          {"pitch_rate_radps", &s.pitch_rate_radps},
          {"delta_pitch_rad", &s.delta_pitch_rad},
          {"delta_height_m", &s.delta_height_m},
          {"height_m", &s.height_m},
          {"speed_mps", &s.speed_mps},
          {"elevator_rad", &s.elevator_rad}};
}

int RunSimulate(const SimulateFlags& flags) {
  if (flags.format != "csv" && flags.format != "json") {
    throw InputError("command line", "--format", "'" + flags.format + "'", "expected csv or json");
  }
  const LongitudinalModel model = flags.model.BuildModel();
  const OpenLoopConfig config = BuildConfig(flags, model);
  const SignalCancellation signals;
  const OpenLoopResult result = SimulateOpenLoop(model, config, signals.flag());
  if (result.summary.cancelled) {
    std::cerr << "gesweep: simulate stopped by signal " << signals.signal() << " at t = "
              << ShortNumber(result.summary.end_time_s) << " s of " << ShortNumber(config.duration_s)
              << " s; nothing written\n";
    return signals.exit_code();
  }

  if (flags.format == "json") {
    nlohmann::json series = nullptr;
    if (!flags.summary_only) {
      series = nlohmann::json::object();
      for (const auto& [name, column] : SeriesColumns(result.series)) {
        nlohmann::json values = nlohmann::json::array();
        for (double v : *column) values.push_back(JsonNumber(v));
        series[name] = std::move(values);
      }
    }
    nlohmann::json run = {{"aircraft", model.aircraft().name},
                          {"start_height_m", config.start_height_m},
                          {"reference_speed_mps", config.reference_speed_mps},
                          {"input", std::string(ToString(config.elevator.kind))},
                          {"elevator_rad", config.elevator.amplitude_rad},
                          {"input_start_s", config.elevator.start_s},
                          {"pulse_s", config.elevator.duration_s},
                          {"integrator", std::string(ToString(config.integrator.kind))},
                          {"dt_s", config.integrator.step_s},
                          {"breakpoints", config.integrator.honour_breakpoints},
                          {"duration_s", config.duration_s},
                          {"frozen_derivatives", config.freeze_derivatives},
                          {"h_derivatives", model.options().h_derivatives},
                          {"cdh", std::string(ToString(model.options().cdh))},
                          {"interpolation", std::string(ToString(model.options().interpolation))}};
    if (config.integrator.kind == IntegratorKind::kDopri5) {
      run["rtol"] = config.integrator.relative_tolerance;
      run["atol"] = config.integrator.absolute_tolerance;
      run["max_step_s"] = config.integrator.max_step_s;
    }
    std::cout << nlohmann::json{{"run", run}, {"summary", SummaryJson(result.summary)}, {"series", series}}.dump(1)
              << "\n";
    return 0;
  }

  std::string out;
  if (flags.summary_only) {
    const OpenLoopSummary& s = result.summary;
    out += "end_event,end_time_s,min_height_m,min_height_time_s,max_abs_pitch_rate_radps,final_delta_speed_mps,"
           "final_delta_normal_velocity_mps,final_pitch_rate_radps,final_delta_pitch_rad,final_delta_height_m,"
           "final_height_m,final_speed_mps,steps,rejected_steps,rhs_calls\n";
    out += std::string(ToString(s.end_event)) + "," + Number(s.end_time_s) + "," + Number(s.min_height_m) + "," +
           Number(s.min_height_time_s) + "," + Number(s.max_abs_pitch_rate_radps);
    for (int i = 0; i < 5; ++i) out += "," + Number(s.final_state[i]);
    out += "," + Number(s.final_height_m) + "," + Number(s.final_speed_mps) + "," + std::to_string(s.steps) + "," +
           std::to_string(s.rejected_steps) + "," + std::to_string(s.rhs_calls) + "\n";
  } else {
    const auto columns = SeriesColumns(result.series);
    for (std::size_t c = 0; c < columns.size(); ++c) out += (c ? "," : "") + std::string(columns[c].first);
    out += "\n";
    for (std::size_t row = 0; row < result.series.time_s.size(); ++row) {
      for (std::size_t c = 0; c < columns.size(); ++c) out += (c ? "," : "") + Number((*columns[c].second)[row]);
      out += "\n";
    }
  }
  std::cout << out;
  return 0;
}

const CommandRegistrar kRegistrar{Command{
    "simulate",
    "Open-loop time response of Eq. (1) after an elevator input, derivatives re-evaluated at the current "
    "height and speed (docs/model.md section 7; the paper's Fig. 4)",
    [](CLI::App& app) -> std::function<int()> {
      auto flags = std::make_shared<SimulateFlags>();
      flags->model.AddTo(app);
      AddLimitedOption(app, "--height-m", flags->height_m, "height_m",
                       "Start height H0 of the mean chord above ground, m; must be above the aircraft's "
                       "wheel-contact height (0.788 m for ANCE): starts on or below it are refused")
          ->required();
      AddLimitedOption(app, "--speed-mps", flags->speed_mps, "speed_mps",
                       "Reference speed u0, m/s; must be above the stall speed")
          ->required();
      app.add_option("--input", flags->input, "Elevator input: pulse (default), step, doublet or none");
      AddLimitedOption(app, "--elevator-deg", flags->elevator_deg, "pulse_amplitude_deg",
                       "Input amplitude, degrees, positive trailing edge down (nose down); default 5");
      AddLimitedOption(app, "--pulse-s", flags->pulse_s, "pulse_duration_s",
                       "Pulse length (doublet: each half), s; default 0.2");
      AddLimitedOption(app, "--input-start-s", flags->input_start_s, "open_loop.input_start_s",
                       "Time of the input's first jump, s; default 0");
      app.add_option("--integrator", flags->integrator, "rk4 (default, fixed step) or dopri5 (adaptive)");
      AddLimitedOption(app, "--dt-s", flags->dt_s, "open_loop.step_s",
                       "RK4 step (dopri5: first trial step), s; default 0.015");
      AddLimitedOption(app, "--rtol", flags->rtol, "relative_tolerance", "dopri5 relative tolerance; default 1e-6");
      AddLimitedOption(app, "--atol", flags->atol, "absolute_tolerance", "dopri5 absolute tolerance; default 1e-9");
      AddLimitedOption(app, "--max-step-s", flags->max_step_s, "open_loop.max_step_s",
                       "dopri5 largest step, s; default 0 (no limit)");
      app.add_flag("--no-breakpoints", flags->no_breakpoints,
                   "Let steps straddle the input's jumps (the paper's plain fixed-step RK4)");
      AddLimitedOption(app, "--duration-s", flags->duration_s, "open_loop.duration_s", "Time limit, s; default 300");
      auto* output_dt = AddLimitedOption(app, "--output-dt-s", flags->output_dt_s, "output_dt_s",
                                         "Series sampling interval, s (interpolated inside steps); default --dt-s");
      auto* summary = app.add_flag("--summary-only", flags->summary_only, "Write the summary only, no series");
      output_dt->excludes(summary);
      app.add_flag("--frozen", flags->frozen,
                   "Freeze A and B at the start condition (the classical linear response) instead of re-evaluating");
      AddLimitedOption(app, "--initial-delta-u-mps", flags->initial_delta_u_mps, "open_loop.initial_delta_u_mps",
                       "Initial offset of u, m/s");
      AddLimitedOption(app, "--initial-delta-w-mps", flags->initial_delta_w_mps, "open_loop.initial_delta_w_mps",
                       "Initial offset of w (positive down), m/s");
      AddLimitedOption(app, "--initial-pitch-rate-degps", flags->initial_pitch_rate_degps,
                       "open_loop.initial_pitch_rate_degps", "Initial pitch rate, deg/s");
      AddLimitedOption(app, "--initial-pitch-deg", flags->initial_pitch_deg, "open_loop.initial_pitch_deg",
                       "Initial offset of the pitch angle, deg");
      AddLimitedOption(app, "--initial-delta-h-m", flags->initial_delta_h_m, "open_loop.initial_delta_h_m",
                       "Initial offset of H, m (the derivatives see H0 + offset)");
      app.add_option("--format", flags->format,
                     "csv (default: the time series; with --summary-only one summary row) or json "
                     "({\"run\", \"summary\", \"series\"})");
      return [flags] { return RunSimulate(*flags); };
    }}};

}  // namespace
}  // namespace gesweep::cli
