#include "engine/control/landing_config.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "engine/common/errors.h"
#include "engine/common/input_limits.h"
#include "engine/control/landing_simulation.h"

namespace gesweep {
namespace {

std::string Text(double value) { return ShortNumber(value); }

}  // namespace

const std::array<std::string_view, kLandingStateCount>& LandingStateNames() {
  static const std::array<std::string_view, kLandingStateCount> kNames = [] {
    std::array<std::string_view, kLandingStateCount> names;
    for (int i = 0; i < kLandingStateCount; ++i) names[static_cast<std::size_t>(i)] = kLandingStates[i].name;
    return names;
  }();
  return kNames;
}

double FlareTimeConstant(const LandingConfig& config) {
  const double gamma_rad = config.glide_slope_deg * std::numbers::pi / 180.0;
  return SetOr(config.flare_time_constant_s, (config.flare_height_m - config.flare_asymptote_m) /
                                                 (config.start_speed_mps * std::sin(gamma_rad)));
}

double NominalLandingTime(const LandingConfig& config, double wheel_contact_height_m) {
  const double gamma_rad = config.glide_slope_deg * std::numbers::pi / 180.0;
  const double glide_s = (config.start_height_m - config.start_glide_path_offset_m - config.flare_height_m) /
                         (config.start_speed_mps * gamma_rad);
  // H_ref reaches the wheels after τ·ln((Ho − h_a)/(h_wc − h_a)); with the asymptote at or above the
  // wheels it never does, and the float ends by the airplane's lag: count 100 times the drop's fall.
  const double drop_m = config.flare_height_m - config.flare_asymptote_m;
  const double left_m = config.flare_asymptote_m > 0.0
                            ? std::max(wheel_contact_height_m - config.flare_asymptote_m, 0.01 * drop_m)
                            : wheel_contact_height_m;
  const double flare_s = FlareTimeConstant(config) * std::log(drop_m / left_m);
  return std::max(glide_s, 0.0) + flare_s;
}

double LandingTimeLimit(const LandingConfig& config, double wheel_contact_height_m) {
  return SetOr(config.time_limit_s, 2.0 * NominalLandingTime(config, wheel_contact_height_m));
}

namespace {

// The work a landing may take (docs/limits.md): the step count of its time limit over the largest
// step, the noise table built before the first step, and the series kept.
void CheckLandingWork(const LandingConfig& c, double wheel_contact_height_m, const std::string& source) {
  // The fewest steps the run can take: its time limit over the largest step.
  const double time_limit_s = LandingTimeLimit(c, wheel_contact_height_m);
  if (!(std::isfinite(time_limit_s) && time_limit_s > 0.0)) {
    throw InputError(
        source, "time_limit_s", Text(time_limit_s),
        "expected a finite time limit > 0 s (the automatic one: twice the reference trajectory's time)");
  }
  CheckStepCount(time_limit_s, c.integrator.max_step_s, source,
                 std::isnan(c.time_limit_s) ? "time_limit_s (automatic)" : "time_limit_s", "max_step_s");
  // Bounded work (docs/limits.md): the noise table built before the first step, and the series kept.
  const std::string time_limit_key = std::isnan(c.time_limit_s) ? "time_limit_s (automatic)" : "time_limit_s";
  const bool turbulent = c.disturbance.turbulence == TurbulenceModel::kDryden;
  const double noise_samples =
      turbulent ? NoiseSampleCount(time_limit_s, c.disturbance.turbulence_sample_interval_s) : 0.0;
  CheckNoiseSamples(turbulent ? time_limit_s : 0.0, c.disturbance.turbulence_sample_interval_s, source,
                    time_limit_key, "turbulence_sample_interval_s");
  const double series_samples =
      c.output_interval_s > 0.0 ? std::floor(time_limit_s / c.output_interval_s) + 2 : 0.0;
  constexpr double kSampleBytes = sizeof(LandingSample);
  const double bytes = noise_samples * kNoiseBytesPerSample + series_samples * kSampleBytes;
  if (bytes > kMaximumRunMemoryBytes) {
    std::string breakdown = ShortNumber(series_samples) + " series samples (" + time_limit_key + " = " +
                            ShortNumber(time_limit_s) + " s / output_interval_s) x " +
                            ShortNumber(kSampleBytes) + " bytes";
    if (noise_samples > 0)
      breakdown += " + " + ShortNumber(noise_samples) + " noise samples x " +
                   ShortNumber(kNoiseBytesPerSample) + " bytes";
    CheckRunMemory(bytes, breakdown, source, "output_interval_s", ShortNumber(c.output_interval_s));
  }
}

}  // namespace

void ValidateLandingConfig(const LandingConfig& c, const Aircraft& aircraft, const std::string& source) {
  const double wheel_contact_height_m = aircraft.wheel_contact_height_m;
  auto require = [&source](bool ok, const char* key, double value, const std::string& expected) {
    if (!ok) throw InputError(source, key, Text(value), expected);
  };
  // The limits table first (one range per quantity, the same as study files and every flag), then
  // what depends on the aircraft or on other fields.
  auto limit = [&source](const char* name, const char* key, double value) {
    CheckInputLimit(name, value, source, key);
  };
  const std::string contact = Text(wheel_contact_height_m);
  limit("flare_height_m", "flare_height_m", c.flare_height_m);
  require(c.flare_height_m > wheel_contact_height_m, "flare_height_m", c.flare_height_m,
          "expected a flare height above the wheel-contact height " + contact + " m");
  limit("height_m", "start_height_m", c.start_height_m);
  require(c.start_height_m > c.flare_height_m, "start_height_m", c.start_height_m,
          "expected a start height above the flare height " + Text(c.flare_height_m) + " m");
  limit("speed_mps", "start_speed_mps", c.start_speed_mps);
  require(c.start_speed_mps > aircraft.stall_speed_mps, "start_speed_mps", c.start_speed_mps,
          "expected a speed above the stall speed " + Text(aircraft.stall_speed_mps) + " m/s of " +
              aircraft.source_path);
  limit("landing.divergence_pitch_deg", "divergence_pitch_deg", c.divergence_pitch_deg);
  limit("landing.start_pitch_deg", "start_pitch_deg", c.start_pitch_deg);
  require(std::abs(c.start_pitch_deg) < c.divergence_pitch_deg, "start_pitch_deg", c.start_pitch_deg,
          "expected |pitch| below divergence_pitch_deg " + Text(c.divergence_pitch_deg));
  limit("landing.start_glide_path_offset_m", "start_glide_path_offset_m", c.start_glide_path_offset_m);
  limit("glide_slope_deg", "glide_slope_deg", c.glide_slope_deg);
  if (!std::isnan(c.design_height_m)) {
    // +inf (free flight) is allowed: the table's free-flight row at sea-level density.
    limit("landing.design_height_m", "design_height_m", c.design_height_m);
    require(c.design_height_m >= wheel_contact_height_m, "design_height_m", c.design_height_m,
            "expected a height >= the wheel-contact height " + contact + " m, or inf");
  }
  if (!std::isnan(c.design_speed_mps)) limit("speed_mps", "design_speed_mps", c.design_speed_mps);
  for (int i = 0; i < kLandingStateCount; ++i) {
    const std::string key = "q_weights." + std::string(LandingStateNames()[i]);
    CheckInputLimit("q_weights", c.q_weights[i], source, key);
  }
  limit("r_weight", "r_weight", c.r_weight);
  limit("landing.actuator_pole_per_s", "actuator_pole_per_s", c.actuator_pole_per_s);
  limit("landing.compensator_pole_per_s", "compensator_pole_per_s", c.compensator_pole_per_s);
  if (!std::isnan(c.flare_time_constant_s))
    limit("flare_time_constant_s", "flare_time_constant_s", c.flare_time_constant_s);
  require(std::isfinite(c.flare_asymptote_m) && c.flare_asymptote_m >= 0.0 &&
              c.flare_asymptote_m < c.flare_height_m,
          "flare_asymptote_m", c.flare_asymptote_m,
          "expected a height in [0, flare_height_m = " + Text(c.flare_height_m) + " m)");
  {
    DisturbanceOptions disturbance = c.disturbance;
    disturbance.wing_span_m = aircraft.wingspan_m;
    ValidateDisturbanceOptions(disturbance, source);
  }
  limit("landing.elevator_min_deg", "elevator_min_deg", c.elevator_min_deg);
  limit("landing.elevator_max_deg", "elevator_max_deg", c.elevator_max_deg);
  if (!std::isnan(c.plant_fixed_reference_height_m)) {
    limit("landing.plant_fixed_reference_height_m", "plant_fixed_reference_height_m",
          c.plant_fixed_reference_height_m);
  }
  limit("relative_tolerance", "relative_tolerance", c.integrator.relative_tolerance);
  limit("absolute_tolerance", "absolute_tolerance", c.integrator.absolute_tolerance);
  limit("landing.max_step_s", "max_step_s", c.integrator.max_step_s);
  if (!std::isnan(c.time_limit_s)) limit("landing.time_limit_s", "time_limit_s", c.time_limit_s);
  require(std::isfinite(c.output_interval_s) && c.output_interval_s >= 0.0, "output_interval_s",
          c.output_interval_s, "expected an interval >= 0 s (0: no series)");
  if (c.output_interval_s > 0.0) limit("output_dt_s", "output_interval_s", c.output_interval_s);
  CheckLandingWork(c, wheel_contact_height_m, source);
}

}  // namespace gesweep
