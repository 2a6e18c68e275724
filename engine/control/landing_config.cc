#include "engine/control/landing_config.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

std::string Text(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

}  // namespace

const std::array<std::string_view, kLandingStateCount>& LandingStateNames() {
  static const std::array<std::string_view, kLandingStateCount> kNames = {
      "delta_u", "delta_w", "pitch_rate", "delta_theta", "delta_h",
      "elevator", "deviation", "compensator", "error_integral"};
  return kNames;
}

std::string_view ToString(PlantHeightReference reference) {
  return reference == PlantHeightReference::kReferencePath ? "path" : "fixed";
}

std::optional<PlantHeightReference> ParsePlantHeightReference(std::string_view text) {
  if (text == "path") return PlantHeightReference::kReferencePath;
  if (text == "fixed") return PlantHeightReference::kFixedHeight;
  return std::nullopt;
}

double FlareTimeConstant(const LandingConfig& config) {
  if (config.flare_time_constant_s) return *config.flare_time_constant_s;
  const double gamma_rad = config.glide_slope_deg * std::numbers::pi / 180.0;
  return config.flare_height_m / (config.start_speed_mps * std::sin(gamma_rad));
}

double NominalLandingTime(const LandingConfig& config, double wheel_contact_height_m) {
  const double gamma_rad = config.glide_slope_deg * std::numbers::pi / 180.0;
  const double glide_s = (config.start_height_m - config.start_glide_path_offset_m - config.flare_height_m) /
                         (config.start_speed_mps * gamma_rad);
  const double flare_s = FlareTimeConstant(config) * std::log(config.flare_height_m / wheel_contact_height_m);
  return std::max(glide_s, 0.0) + flare_s;
}

double LandingTimeLimit(const LandingConfig& config, double wheel_contact_height_m) {
  return config.time_limit_s ? *config.time_limit_s : 2.0 * NominalLandingTime(config, wheel_contact_height_m);
}

void ValidateLandingConfig(const LandingConfig& c, const Aircraft& aircraft, const std::string& source) {
  const double wheel_contact_height_m = aircraft.wheel_contact_height_m;
  auto require = [&source](bool ok, const char* key, double value, const std::string& expected) {
    if (!ok) throw InputError(source, key, Text(value), expected);
  };
  auto finite = [](double v) { return std::isfinite(v); };
  const std::string contact = Text(wheel_contact_height_m);
  require(finite(c.flare_height_m) && c.flare_height_m > wheel_contact_height_m, "flare_height_m",
          c.flare_height_m, "expected a flare height above the wheel-contact height " + contact + " m");
  require(finite(c.start_height_m) && c.start_height_m > c.flare_height_m, "start_height_m", c.start_height_m,
          "expected a start height above the flare height " + Text(c.flare_height_m) + " m");
  require(finite(c.start_speed_mps) && c.start_speed_mps > aircraft.stall_speed_mps, "start_speed_mps",
          c.start_speed_mps, "expected a speed above the stall speed " + Text(aircraft.stall_speed_mps) + " m/s of " +
                                 aircraft.source_path);
  require(finite(c.start_pitch_deg) && std::abs(c.start_pitch_deg) < c.divergence_pitch_deg, "start_pitch_deg",
          c.start_pitch_deg, "expected |pitch| below divergence_pitch_deg " + Text(c.divergence_pitch_deg));
  require(finite(c.start_glide_path_offset_m), "start_glide_path_offset_m", c.start_glide_path_offset_m,
          "expected a finite offset, m");
  require(finite(c.glide_slope_deg) && c.glide_slope_deg > 0.0 && c.glide_slope_deg < 30.0, "glide_slope_deg",
          c.glide_slope_deg, "expected a glide-slope angle in (0, 30) deg (a descent)");
  if (c.design_height_m) {
    // +∞ (free flight) is allowed: the table's free-flight row at sea-level density.
    require(*c.design_height_m >= wheel_contact_height_m, "design_height_m", *c.design_height_m,
            "expected a height >= the wheel-contact height " + contact + " m, or inf");
  }
  if (c.design_speed_mps) {
    require(finite(*c.design_speed_mps) && *c.design_speed_mps > 0.0, "design_speed_mps", *c.design_speed_mps,
            "expected a speed > 0 m/s");
  }
  for (int i = 0; i < kLandingStateCount; ++i) {
    const std::string key = "q_weights." + std::string(LandingStateNames()[i]);
    if (!(finite(c.q_weights[i]) && c.q_weights[i] >= 0.0)) {
      throw InputError(source, key, Text(c.q_weights[i]), "expected a weight >= 0");
    }
  }
  require(finite(c.r_weight) && c.r_weight > 0.0, "r_weight", c.r_weight, "expected a weight > 0");
  require(finite(c.actuator_pole_per_s) && c.actuator_pole_per_s > 0.0, "actuator_pole_per_s",
          c.actuator_pole_per_s, "expected a pole > 0 1/s");
  require(finite(c.compensator_pole_per_s) && c.compensator_pole_per_s > 0.0, "compensator_pole_per_s",
          c.compensator_pole_per_s, "expected a pole > 0 1/s");
  if (c.flare_time_constant_s) {
    require(finite(*c.flare_time_constant_s) && *c.flare_time_constant_s > 0.0, "flare_time_constant_s",
            *c.flare_time_constant_s, "expected a time constant > 0 s");
  }
  require(finite(c.elevator_min_deg) && c.elevator_min_deg < 0.0 && c.elevator_min_deg >= -90.0,
          "elevator_min_deg", c.elevator_min_deg, "expected a lower limit in [-90, 0) deg");
  require(finite(c.elevator_max_deg) && c.elevator_max_deg > 0.0 && c.elevator_max_deg <= 90.0,
          "elevator_max_deg", c.elevator_max_deg, "expected an upper limit in (0, 90] deg");
  if (c.plant_fixed_reference_height_m) {
    require(finite(*c.plant_fixed_reference_height_m), "plant_fixed_reference_height_m",
            *c.plant_fixed_reference_height_m, "expected a finite height, m");
  }
  require(c.relative_tolerance > 0.0 && c.relative_tolerance < 1.0, "relative_tolerance", c.relative_tolerance,
          "expected a relative tolerance in (0, 1)");
  require(finite(c.absolute_tolerance) && c.absolute_tolerance > 0.0, "absolute_tolerance", c.absolute_tolerance,
          "expected an absolute tolerance > 0");
  require(finite(c.max_step_s) && c.max_step_s > 0.0, "max_step_s", c.max_step_s, "expected a step > 0 s");
  if (c.time_limit_s) {
    require(finite(*c.time_limit_s) && *c.time_limit_s > 0.0, "time_limit_s", *c.time_limit_s,
            "expected a time limit > 0 s");
  }
  require(finite(c.output_interval_s) && c.output_interval_s >= 0.0, "output_interval_s", c.output_interval_s,
          "expected an interval >= 0 s (0: no series)");
  require(finite(c.divergence_pitch_deg) && c.divergence_pitch_deg > 0.0 && c.divergence_pitch_deg <= 90.0,
          "divergence_pitch_deg", c.divergence_pitch_deg, "expected an angle in (0, 90] deg");
}

}  // namespace gesweep
