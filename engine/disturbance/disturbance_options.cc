#include "engine/disturbance/disturbance_options.h"

#include <cmath>

#include "engine/common/errors.h"
#include "engine/common/input_limits.h"

namespace gesweep {

double EffectiveSigmaW(const DisturbanceOptions& options) {
  if (options.turbulence == TurbulenceModel::kNone) return 0.0;
  if (std::isnan(options.turbulence_sigma_w_mps)) return 0.1 * std::abs(options.wind_20ft_mps);
  return options.turbulence_sigma_w_mps;
}

void ValidateDisturbanceOptions(const DisturbanceOptions& o, const std::string& source) {
  auto fail = [&](const char* key, double value, const char* expected) {
    throw InputError(source, key, ShortNumber(value), std::string("expected ") + expected);
  };
  if (!std::isfinite(o.wind_20ft_mps)) fail("wind_20ft_mps", o.wind_20ft_mps, "a finite speed in m/s");
  // NaN: unset (0.1 |wind_20ft_mps|); else the limits table's range (a flag or a keyword never
  // gives NaN: DisturbanceOptions::Describe marks it Automatic).
  if (!std::isnan(o.turbulence_sigma_w_mps))
    CheckInputLimit("turbulence_sigma_w_mps", o.turbulence_sigma_w_mps, source, "turbulence_sigma_w_mps");
  if (!(o.turbulence_sample_interval_s >= 1e-4 && o.turbulence_sample_interval_s <= 1.0)) {
    fail("turbulence_sample_interval_s", o.turbulence_sample_interval_s, "a number in [0.0001, 1] (s)");
  }
  if (o.pitch_rate_gust && !(std::isfinite(o.wing_span_m) && o.wing_span_m > 0.0)) {
    fail("wing_span_m", o.wing_span_m, "a finite span > 0 (m) for the pitch-rate gust");
  }
  if (!std::isfinite(o.gust_amplitude_mps))
    fail("gust_amplitude_mps", o.gust_amplitude_mps, "a finite speed in m/s");
  if (!(std::isfinite(o.gust_half_length_m) && o.gust_half_length_m > 0.0)) {
    fail("gust_half_length_m", o.gust_half_length_m, "a finite length > 0 (m)");
  }
  if (!(std::isfinite(o.gust_start_s) && o.gust_start_s >= 0.0)) {
    fail("gust_start_s", o.gust_start_s, "a finite time >= 0 (s)");
  }
}

}  // namespace gesweep
