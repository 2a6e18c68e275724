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

#include "engine/cli/command.h"
#include "engine/cli/described_flags.h"
#include "engine/cli/model_flags.h"
#include "engine/cli/signals.h"
#include "engine/common/errors.h"
#include "engine/control/landing_simulation.h"
#include "engine/disturbance/disturbance_field.h"

namespace gesweep::cli {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

// Ordered JSON keeps the summary's fields in the order written here (also the CSV column order).
using Json = nlohmann::ordered_json;

/// A number, or null when it is not finite (JSON has no NaN), as json_util.h's JsonNumber.
Json JsonNumber(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

struct LandFlags {
  ModelFlags model;
  LandingConfig config;  // defaults documented in landing_config.h
  double flare_time_constant_s = std::nan("");
  double design_height_m = std::nan("");
  double design_speed_mps = std::nan("");
  double plant_reference_height_m = std::nan("");
  double time_limit_s = std::nan("");
  std::string plant_height_reference = "path";
  std::string q_weights;
  bool no_design_h_derivatives = false;
  bool summary_only = false;
  std::string format = "csv";
  // The moving atmosphere's flags (DisturbanceOptions::Describe) and the turbulence's RunNoise(seed, i).
  DescribedFlags described;
  std::string turbulent_integrator = "rk4";
};

std::string Number(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  if (value == 0.0) value = 0.0;  // no "-0"
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.10g", value);
  return buffer;
}

// Maps the config's field names (ValidateLandingConfig's keys) to the flags a person typed.
std::string FlagOf(const std::string& key) {
  static const std::vector<std::pair<std::string, std::string>> kFlags = {
      {"start_height_m", "--start-height-m"},
      {"start_speed_mps", "--speed-mps"},
      {"start_pitch_deg", "--start-pitch-deg"},
      {"start_glide_path_offset_m", "--start-offset-m"},
      {"glide_slope_deg", "--glide-slope-deg"},
      {"design_height_m", "--design-height-m"},
      {"design_speed_mps", "--design-speed-mps"},
      {"r_weight", "--r-weight"},
      {"actuator_pole_per_s", "--actuator-pole-per-s"},
      {"compensator_pole_per_s", "--compensator-pole-per-s"},
      {"flare_height_m", "--flare-height-m"},
      {"flare_time_constant_s", "--tau-s"},
      {"elevator_min_deg", "--elevator-min-deg"},
      {"elevator_max_deg", "--elevator-max-deg"},
      {"plant_fixed_reference_height_m", "--plant-reference-height-m"},
      {"relative_tolerance", "--rtol"},
      {"absolute_tolerance", "--atol"},
      {"max_step_s", "--max-step-s"},
      {"time_limit_s", "--time-limit-s"},
      {"output_interval_s", "--output-dt-s"},
      {"divergence_pitch_deg", "--divergence-pitch-deg"},
      {"flare_asymptote_m", "--flare-asymptote-m"},
  };
  for (const auto& [field, flag] : kFlags) {
    if (key == field) return flag;
  }
  if (key.rfind("q_weights.", 0) == 0) return "--q-weights (" + key.substr(10) + ")";
  if (key == "time_limit_s (automatic)") return "--time-limit-s (automatic)";
  return key;
}

LandingConfig BuildConfig(const LandFlags& flags, const LongitudinalModel& model) {
  LandingConfig config = flags.config;
  if (!std::isnan(flags.flare_time_constant_s)) config.flare_time_constant_s = flags.flare_time_constant_s;
  if (!std::isnan(flags.design_height_m)) config.design_height_m = flags.design_height_m;
  if (!std::isnan(flags.design_speed_mps)) config.design_speed_mps = flags.design_speed_mps;
  if (!std::isnan(flags.time_limit_s)) config.time_limit_s = flags.time_limit_s;
  if (!std::isnan(flags.plant_reference_height_m)) {
    config.plant_fixed_reference_height_m = flags.plant_reference_height_m;
  }
  config.design_h_derivatives = !flags.no_design_h_derivatives;
  const auto reference = ParsePlantHeightReference(flags.plant_height_reference);
  if (!reference) {
    throw InputError("command line", "--plant-height-reference", "'" + flags.plant_height_reference + "'",
                     "expected path or fixed");
  }
  config.plant_height_reference = *reference;
  const auto integrator = ParseEnum<IntegratorKind>(flags.turbulent_integrator);
  if (!integrator) {
    throw InputError("command line", "--turbulent-integrator", "'" + flags.turbulent_integrator + "'",
                     "expected " + EnumChoices<IntegratorKind>());
  }
  config.turbulent_integrator = *integrator;
  if (!flags.q_weights.empty()) {
    const std::vector<double> weights = ParseNumberList(flags.q_weights, "--q-weights", false);
    if (weights.size() != static_cast<std::size_t>(kLandingStateCount)) {
      std::string names;
      for (auto name : LandingStateNames()) names += (names.empty() ? "" : ",") + std::string(name);
      throw InputError("command line", "--q-weights", "'" + flags.q_weights + "'",
                       "expected 9 comma-separated weights >= 0 in the order " + names);
    }
    for (int i = 0; i < kLandingStateCount; ++i) config.q_weights[i] = weights[i];
  }
  if (flags.summary_only) config.output_interval_s = 0.0;
  try {
    ValidateLandingConfig(config, model.aircraft(), "command line");
  } catch (const InputError& error) {
    std::string expected = error.expected();
    for (const char* field : {"time_limit_s", "max_step_s"}) {  // inside the step-count sentence
      const std::string from = std::string(field) + " ";
      const auto at = expected.find(from);
      if (at != std::string::npos) expected.replace(at, std::string(field).size(), FlagOf(field));
    }
    const std::string flag = FlagOf(error.key());
    throw InputError("command line", flag == error.key() ? flags.described.FlagOf(flag) : flag, error.value(),
                     expected);
  }
  const double time_limit_s = LandingTimeLimit(config, model.aircraft().wheel_contact_height_m);
  if (config.output_interval_s > 0.0 && time_limit_s / config.output_interval_s > 1e7) {
    throw InputError("command line", "--output-dt-s", Number(config.output_interval_s),
                     "expected at most 1e7 samples");
  }
  return config;
}

Json DesignJson(const LandingDesign& design) {
  Json gain = Json::object();
  for (int i = 0; i < kLandingStateCount; ++i)
    gain[std::string(LandingStateNames()[i])] = JsonNumber(design.gain[i]);
  Json eigenvalues = Json::array();
  for (Eigen::Index i = 0; i < design.closed_loop_eigenvalues.size(); ++i) {
    eigenvalues.push_back(
        {design.closed_loop_eigenvalues(i).real(), design.closed_loop_eigenvalues(i).imag()});
  }
  return {{"status", std::string(ToString(design.status))}, {"message", design.message},
          {"design_height_m", design.design_height_m},      {"design_speed_mps", design.design_speed_mps},
          {"h_derivatives", design.design_h_derivatives},   {"gain", design.ok() ? gain : Json(nullptr)},
          {"closed_loop_eigenvalues_per_s", eigenvalues}};
}

Json SummaryJson(const LandingResult& r) {
  return {{"outcome", std::string(ToString(r.outcome))},
          {"message", r.message},
          {"touchdown_time_s", JsonNumber(r.touchdown_time_s)},
          {"touchdown_distance_past_transmitter_m", JsonNumber(r.touchdown_distance_past_transmitter_m)},
          {"touchdown_sink_rate_mps", JsonNumber(r.touchdown_sink_rate_mps)},
          {"touchdown_pitch_deg", JsonNumber(r.touchdown_pitch_deg)},
          {"touchdown_speed_mps", JsonNumber(r.touchdown_speed_mps)},
          {"flare_start_time_s", JsonNumber(r.flare_start_time_s)},
          {"glide_path_error_at_flare_m", JsonNumber(r.glide_path_error_at_flare_m)},
          {"max_abs_elevator_deg", JsonNumber(r.max_abs_elevator_deg)},
          {"max_abs_elevator_command_deg", JsonNumber(r.max_abs_elevator_command_deg)},
          {"max_abs_pitch_rate_degps", JsonNumber(r.max_abs_pitch_rate_degps)},
          {"saturated_time_s", JsonNumber(r.saturated_time_s)},
          {"longest_saturation_s", JsonNumber(r.longest_saturation_s)},
          {"min_speed_mps", JsonNumber(r.min_speed_mps)},
          {"max_speed_mps", JsonNumber(r.max_speed_mps)},
          {"final_time_s", JsonNumber(r.final_time_s)},
          {"final_height_m", JsonNumber(r.final_height_m)},
          {"touchdown_airspeed_mps", JsonNumber(r.touchdown_airspeed_mps)},
          {"flare_max_abs_elevator_deg", JsonNumber(r.flare_max_abs_elevator_deg)},
          {"flare_max_abs_pitch_rate_degps", JsonNumber(r.flare_max_abs_pitch_rate_degps)},
          {"steps", r.accepted_steps},
          {"rejected_steps", r.rejected_steps},
          {"rhs_calls", r.rhs_calls},
          {"design", DesignJson(r.design)}};
}

// Series columns: name and value of one sample, in CSV and JSON order (angles in degrees at this edge).
struct Column {
  const char* name;
  double (*value)(const LandingSample&);
};
constexpr Column kColumns[] = {
    {"time_s", [](const LandingSample& s) { return s.time_s; }},
    {"height_m", [](const LandingSample& s) { return s.height_m; }},
    {"reference_height_m", [](const LandingSample& s) { return s.reference_height_m; }},
    {"tracking_error_m", [](const LandingSample& s) { return s.tracking_error_m; }},
    {"speed_mps", [](const LandingSample& s) { return s.speed_mps; }},
    {"delta_w_mps", [](const LandingSample& s) { return s.delta_w_mps; }},
    {"pitch_rate_degps", [](const LandingSample& s) { return s.pitch_rate_radps * kDegPerRad; }},
    {"pitch_deg", [](const LandingSample& s) { return s.pitch_rad * kDegPerRad; }},
    {"sink_rate_mps", [](const LandingSample& s) { return s.sink_rate_mps; }},
    {"elevator_deg", [](const LandingSample& s) { return s.elevator_rad * kDegPerRad; }},
    {"elevator_command_deg", [](const LandingSample& s) { return s.elevator_command_rad * kDegPerRad; }},
    {"compensator_m_s", [](const LandingSample& s) { return s.compensator; }},
    {"error_integral_m_s", [](const LandingSample& s) { return s.error_integral; }},
};
// The air motion the airplane met (docs/model.md §9), after the columns above when the run had a
// disturbance; q_g only with the pitch-rate gust.
constexpr Column kAirColumns[] = {
    {"u_g_mps", [](const LandingSample& s) { return s.u_g_mps; }},
    {"w_g_mps", [](const LandingSample& s) { return s.w_g_mps; }},
    {"q_g_radps", [](const LandingSample& s) { return s.q_g_radps; }},
};

std::vector<Column> SeriesColumns(const LandingConfig& config) {
  std::vector<Column> columns(std::begin(kColumns), std::end(kColumns));
  DisturbanceOptions d = config.disturbance;
  d.pitch_rate_gust = false;  // needs the aircraft's span; it makes no air motion of its own
  if (DisturbanceField(d, config.seed, config.run_index).active()) {
    columns.push_back(kAirColumns[0]);
    columns.push_back(kAirColumns[1]);
    if (config.disturbance.pitch_rate_gust) columns.push_back(kAirColumns[2]);
  }
  return columns;
}

Json RunJson(const LandingConfig& c, const LandingResult& r, const LongitudinalModel& model) {
  Json weights = Json::object();
  for (int i = 0; i < kLandingStateCount; ++i) weights[std::string(LandingStateNames()[i])] = c.q_weights[i];
  Json run = {{"aircraft", model.aircraft().name},
              {"start_height_m", c.start_height_m},
              {"start_speed_mps", c.start_speed_mps},
              {"start_pitch_deg", c.start_pitch_deg},
              {"start_glide_path_offset_m", c.start_glide_path_offset_m},
              {"glide_slope_deg", r.glide_slope_deg},
              {"flare_height_m", r.flare_height_m},
              {"flare_time_constant_s", r.flare_time_constant_s},
              {"q_weights", weights},
              {"r_weight", c.r_weight},
              {"actuator_pole_per_s", c.actuator_pole_per_s},
              {"compensator_pole_per_s", c.compensator_pole_per_s},
              {"elevator_min_deg", c.elevator_min_deg},
              {"elevator_max_deg", c.elevator_max_deg},
              {"plant_height_reference", std::string(ToString(c.plant_height_reference))},
              {"h_derivatives", model.options().h_derivatives},
              {"cdh", std::string(ToString(model.options().cdh))},
              {"interpolation", std::string(ToString(model.options().interpolation))},
              {"integrator", "dopri5"},
              {"flare_asymptote_m", c.flare_asymptote_m},
              {"reset_compensator_at_flare", c.reset_compensator_at_flare},
              {"rtol", c.relative_tolerance},
              {"atol", c.absolute_tolerance},
              {"max_step_s", c.max_step_s},
              {"time_limit_s", r.time_limit_s}};
  if (c.plant_height_reference == PlantHeightReference::kFixedHeight) {
    run["plant_reference_height_m"] = r.plant_fixed_reference_height_m;
  }
  const DisturbanceOptions& d = c.disturbance;
  run["wind_20ft_mps"] = d.wind_20ft_mps;
  run["wind_shear"] = std::string(ToString(d.wind_shear));
  run["turbulence"] = std::string(ToString(d.turbulence));
  run["turbulence_sigma_w_mps"] = EffectiveSigmaW(d);
  run["turbulence_sample_interval_s"] = d.turbulence_sample_interval_s;
  run["pitch_rate_gust"] = d.pitch_rate_gust;
  run["gust_axis"] = std::string(ToString(d.gust_axis));
  run["gust_amplitude_mps"] = d.gust_amplitude_mps;
  run["gust_half_length_m"] = d.gust_half_length_m;
  run["gust_start_s"] = d.gust_start_s;
  run["seed"] = c.seed;
  run["run_index"] = c.run_index;
  run["turbulent_integrator"] = std::string(ToString(c.turbulent_integrator));
  return run;
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
    if (!flags.summary_only) {
      series = Json::object();
      Json phase = Json::array();
      for (const LandingSample& s : result.series) phase.push_back(std::string(ToString(s.phase)));
      for (const Column& column : SeriesColumns(config)) {
        Json values = Json::array();
        for (const LandingSample& s : result.series) values.push_back(JsonNumber(column.value(s)));
        series[column.name] = std::move(values);
      }
      series["phase"] = std::move(phase);
    }
    std::cout << Json{{"run", RunJson(config, result, model)},
                      {"summary", SummaryJson(result)},
                      {"series", series}}
                     .dump(1)
              << "\n";
    return exit_code;
  }

  std::string out;
  if (flags.summary_only) {
    const Json summary = SummaryJson(result);
    std::string header, row;
    for (const auto& [key, value] : summary.items()) {
      if (key == "design" || key == "message") continue;
      header += (header.empty() ? "" : ",") + key;
      row += row.empty() ? "" : ",";
      if (value.is_string()) {
        row += value.get<std::string>();
      } else if (value.is_null()) {
        row += "nan";
      } else if (value.is_number_integer()) {
        row += std::to_string(value.get<long>());
      } else {
        row += Number(value.get<double>());
      }
    }
    out += header + "\n" + row + "\n";
  } else {
    const std::vector<Column> columns = SeriesColumns(config);
    const std::size_t air_columns = columns.size() - std::size(kColumns);  // after phase: still air unchanged
    for (std::size_t c = 0; c < std::size(kColumns); ++c) out += std::string(columns[c].name) + ",";
    out += "phase";
    for (std::size_t c = std::size(kColumns); c < columns.size(); ++c)
      out += "," + std::string(columns[c].name);
    out += "\n";
    for (const LandingSample& s : result.series) {
      for (std::size_t c = 0; c < std::size(kColumns); ++c) out += Number(columns[c].value(s)) + ",";
      out += std::string(ToString(s.phase));
      for (std::size_t c = std::size(kColumns); c < columns.size(); ++c)
        out += "," + Number(columns[c].value(s));
      out += "\n";
    }
    (void)air_columns;
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
      LandingConfig& c = flags->config;
      flags->model.AddTo(app);
      AddLimitedOption(app, "--start-height-m", c.start_height_m, "height_m",
                       "Start height of the mean chord, m; default 500");
      AddLimitedOption(app, "--speed-mps", c.start_speed_mps, "speed_mps",
                       "Start speed, also the reference speed u0 of the plant, m/s; default 52.21");
      AddLimitedOption(app, "--start-pitch-deg", c.start_pitch_deg, "landing.start_pitch_deg",
                       "Start pitch angle (reference: level), deg; default 0");
      AddLimitedOption(app, "--start-offset-m", c.start_glide_path_offset_m,
                       "landing.start_glide_path_offset_m",
                       "Start deviation d from the glide path, m, positive above; default 0");
      AddLimitedOption(app, "--glide-slope-deg", c.glide_slope_deg, "glide_slope_deg",
                       "Glide-slope angle, deg, positive down; default 2.5");
      AddLimitedOption(app, "--flare-height-m", c.flare_height_m, "flare_height_m",
                       "Flare height Ho, m; default 10");
      AddLimitedOption(
          app, "--tau-s", flags->flare_time_constant_s, "flare_tau_s",
          "Flare time constant, s; default Ho/(u0 sin(glide slope)), continuous sink rate at Ho");
      app.add_option("--q-weights", flags->q_weights,
                     "9 comma-separated LQR output weights on delta_u,delta_w,pitch_rate,delta_theta,delta_h,"
                     "elevator,deviation,compensator,error_integral (SI units, rad); default all 1");
      AddLimitedOption(app, "--r-weight", c.r_weight, "lqr.r",
                       "LQR weight on the elevator command (rad^2); default 1");
      AddLimitedOption(app, "--design-height-m", flags->design_height_m, "landing.design_height_m",
                       "Height of the linear model used for the gain, m; default the wheel-contact height");
      AddLimitedOption(app, "--design-speed-mps", flags->design_speed_mps, "speed_mps",
                       "Speed of the linear model used for the gain, m/s; default --speed-mps");
      app.add_flag("--no-design-h-derivatives", flags->no_design_h_derivatives,
                   "Leave Xh, Zh, Mh out of the design model (the plant follows --no-h-derivatives)");
      AddLimitedOption(app, "--actuator-pole-per-s", c.actuator_pole_per_s, "landing.actuator_pole_per_s",
                       "Elevator actuator pole, 1/s; default 10");
      AddLimitedOption(app, "--compensator-pole-per-s", c.compensator_pole_per_s,
                       "landing.compensator_pole_per_s", "Compensator pole S_d, 1/s; default 10");
      AddLimitedOption(app, "--elevator-min-deg", c.elevator_min_deg, "landing.elevator_min_deg",
                       "Lower elevator limit, deg; default -25");
      AddLimitedOption(app, "--elevator-max-deg", c.elevator_max_deg, "landing.elevator_max_deg",
                       "Upper elevator limit, deg; default 25");
      app.add_option("--plant-height-reference", flags->plant_height_reference,
                     "What the plant's h-derivative terms measure dH from: path (default, the reference "
                     "trajectory) or fixed (--plant-reference-height-m)");
      AddLimitedOption(
          app, "--plant-reference-height-m", flags->plant_reference_height_m,
          "landing.plant_fixed_reference_height_m",
          "Fixed reference height for --plant-height-reference fixed, m; default the top table height");
      AddLimitedOption(app, "--rtol", c.relative_tolerance, "relative_tolerance",
                       "Dormand-Prince relative tolerance; default 1e-3 (ode45)");
      AddLimitedOption(app, "--atol", c.absolute_tolerance, "absolute_tolerance",
                       "Dormand-Prince absolute tolerance; default 1e-6");
      AddLimitedOption(app, "--max-step-s", c.max_step_s, "landing.max_step_s", "Largest step, s; default 1");
      AddLimitedOption(
          app, "--time-limit-s", flags->time_limit_s, "landing.time_limit_s",
          "Time limit, s (outcome no_touchdown); default twice the reference trajectory's time to the "
          "wheels");
      AddLimitedOption(app, "--divergence-pitch-deg", c.divergence_pitch_deg, "landing.divergence_pitch_deg",
                       "|pitch| that ends the run as diverged, deg; default 60");
      auto* output_dt = AddLimitedOption(app, "--output-dt-s", c.output_interval_s, "output_dt_s",
                                         "Series sampling interval, s; default 0.1");
      auto* summary =
          app.add_flag("--summary-only", flags->summary_only, "Write the summary only, no series");
      output_dt->excludes(summary);
      app.add_option("--format", flags->format,
                     "csv (default: the series; with --summary-only one summary row) or json "
                     "({\"run\", \"summary\", \"series\"})");
      app.add_option("--flare-asymptote-m", c.flare_asymptote_m,
                     "Height the flare's exponential tends to, m, in [0, Ho); default 0 (the ground, the "
                     "paper's); the wheel-contact height makes touchdown a long float (docs/landing.md)");
      app.add_flag("--reset-compensator-at-flare", c.reset_compensator_at_flare,
                   "Restart the compensator and the error integral from zero at the flare switch (default: "
                   "they carry over)");
      // The moving atmosphere (docs/model.md section 9): one flag per field of DisturbanceOptions.
      flags->described.Add(app, c.disturbance);
      app.add_option("--turbulent-integrator", flags->turbulent_integrator,
                     "Integrator of a landing in turbulence: rk4 (default; step = "
                     "--turbulence-sample-interval-s) or dopri5 (--rtol, --atol)");
      app.add_option("--seed", c.seed,
                     "Seed of the turbulence (a sweep's seed parameter); default 0 (docs/disturbance.md)");
      app.add_option("--run-index", c.run_index,
                     "Run index i of the turbulence RunNoise(seed, i): replays run i of a sweep; default 0");
      return [flags] {
        flags->described.Apply();
        return RunLand(*flags);
      };
    }}};

}  // namespace
}  // namespace gesweep::cli
