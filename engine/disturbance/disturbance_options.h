#pragma once
/// The options of the moving atmosphere (docs/model.md §9; names as the study keys). The
/// defaults are still air: no wind, no turbulence, no gust.

#include <cstdint>
#include <limits>
#include <string>

#include "engine/common/describe.h"
#include "engine/common/series.h"
#include "engine/disturbance/mean_wind.h"

namespace gesweep {

/// Continuous turbulence model.
enum class TurbulenceModel {
  kNone,    ///< no continuous turbulence
  kDryden,  ///< the Dryden form, low altitude (dryden.h)
};
GESWEEP_ENUM_NAMES(TurbulenceModel, {kNone, "none"}, {kDryden, "dryden"});

/// Body axis of the discrete gust.
enum class GustAxis {
  kU,  ///< along x, adds to u_g (positive forward: a tail gust)
  kW,  ///< along z, adds to w_g (positive down: a down gust)
};
GESWEEP_ENUM_NAMES(GustAxis, {kU, "u"}, {kW, "w"});

// Their names (the study keys' values): ToString, ParseEnum, EnumChoices of engine/common/enum_names.h.

/// Options of one run's disturbances.
struct DisturbanceOptions {
  /// Mean wind at 20 ft, m/s, as u_g: a headwind is negative. Finite.
  double wind_20ft_mps = 0.0;
  /// The shear profile; kLogarithmic is the specification's.
  WindShear wind_shear = WindShear::kLogarithmic;
  TurbulenceModel turbulence = TurbulenceModel::kNone;
  /// σ_w, m/s (≥ 0, finite); NaN (the default): 0.1·|W20| as the specification's low-altitude model.
  double turbulence_sigma_w_mps = std::numeric_limits<double>::quiet_NaN();
  /// Interval Δt_n at which the white noise is sampled and held, s. In [1e-4, 1]. The w filter
  /// loses variance above ω ≈ 1/Δt_n (docs/disturbance.md gives the loss and the cost).
  double turbulence_sample_interval_s = 0.01;
  /// Adds the Dryden pitch-rate gust q_g = −(s/V)/(1 + 4b s/(πV))·w_g (needs wing_span_m > 0).
  bool pitch_rate_gust = false;
  /// Wing span b for the pitch-rate gust, m (> 0 when pitch_rate_gust).
  double wing_span_m = 0.0;
  GustAxis gust_axis = GustAxis::kW;
  /// 1 − cos gust amplitude v_m, m/s (finite; 0: no gust).
  double gust_amplitude_mps = 0.0;
  /// Half-length d_m, m (> 0).
  double gust_half_length_m = 30.0;
  /// Time at which the airplane enters the gust, s (≥ 0, finite).
  double gust_start_s = 0.0;

  /// The settings a person gives (describe.h): the flags of `gesweep simulate` and `gesweep land`,
  /// and in a sweep the run parameters of the same names (RunParameter: engine/analyses/
  /// parameter_catalog.cc makes their catalogue entries from these fields), so they can be fixed, swept or
  /// drawn per run. The sample interval and the pitch-rate gust are settings of the analysis
  /// ([analyses.open_loop], [analyses.landing]). The span of the pitch-rate gust is the aircraft's.
  template <class V>
  void Describe(V& v) {
    v(Field("wind_20ft_mps", &wind_20ft_mps)
          .Unit("m/s")
          .Limit("wind_20ft_mps")
          .RunParameter()
          .Doc("Mean wind at 20 ft as u_g, m/s: a headwind is negative (docs/model.md section 9)"));
    v(Field("wind_shear", &wind_shear)
          .RunParameter()
          .Doc("Mean-wind profile in height: logarithmic (MIL-F-8785C) or none (W20 at every height)"));
    v(Field("turbulence", &turbulence)
          .RunParameter()
          .Doc("Continuous turbulence: none or dryden (low-altitude Dryden, docs/model.md section 9)"));
    v(Field("turbulence_sigma_w_mps", &turbulence_sigma_w_mps)
          .Unit("m/s")
          .Limit("turbulence_sigma_w_mps")
          .Automatic()
          .RunParameter()
          .Doc("Vertical turbulence intensity sigma_w, m/s; default (left out): 0.1 |wind_20ft_mps| "
               "as the specification's low-altitude model"));
    v(Field("gust_axis", &gust_axis)
          .RunParameter()
          .Doc("Axis of the 1 - cos gust: u (positive: a tail gust) or w (positive: a down gust)"));
    v(Field("gust_amplitude_mps", &gust_amplitude_mps)
          .Unit("m/s")
          .Limit("gust_amplitude_mps")
          .RunParameter()
          .Doc("Amplitude v_m of the 1 - cos gust, m/s; 0: no gust"));
    v(Field("gust_half_length_m", &gust_half_length_m)
          .Unit("m")
          .Limit("gust_half_length_m")
          .RunParameter()
          .Doc("Half-length d_m of the 1 - cos gust, m"));
    v(Field("gust_start_s", &gust_start_s)
          .Unit("s")
          .Limit("gust_start_s")
          .RunParameter()
          .Doc("Time at which the airplane enters the gust, s"));
    v(Field("turbulence_sample_interval_s", &turbulence_sample_interval_s)
          .Unit("s")
          .Limit("turbulence_sample_interval_s")
          .Doc("Interval at which the turbulence's white noise is sampled and held, s "
               "(docs/disturbance.md)"));
    v(Field("pitch_rate_gust", &pitch_rate_gust)
          .Doc("Add the Dryden pitch-rate gust q_g (span: the aircraft's)"));
  }
};

/// σ_w in force: the override, else 0.1·|W20|; 0 without turbulence.
double EffectiveSigmaW(const DisturbanceOptions& options);

/// Throws InputError(source, key, value, expectation) for the first option out of range.
void ValidateDisturbanceOptions(const DisturbanceOptions& options, const std::string& source);

/// The air motion a time response met (docs/model.md §9), as quantities of its series
/// (engine/common/series.h): u_g and w_g with a moving atmosphere, q_g with the pitch-rate gust. S is
/// the series struct (the open loop's columns, a landing's sample) with members of these names.
template <class S, class V>
void DescribeAirMotion(V& v) {
  v(SeriesField("u_g_mps", &S::u_g_mps)
        .Unit("m/s")
        .Only(SeriesPresence::kDisturbance)
        .Doc("Air velocity along x at the airplane: mean wind + turbulence + a u gust (a headwind is "
             "negative)"));
  v(SeriesField("w_g_mps", &S::w_g_mps)
        .Unit("m/s")
        .Only(SeriesPresence::kDisturbance)
        .Doc("Air velocity along z at the airplane (positive down): turbulence + a w gust"));
  v(SeriesField("q_g_radps", &S::q_g_radps)
        .Unit("rad/s")
        .Only(SeriesPresence::kPitchRateGust)
        .Doc("Pitch-rate gust q_g (Dryden)"));
}

}  // namespace gesweep
