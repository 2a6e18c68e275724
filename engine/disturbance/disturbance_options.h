#pragma once
/// The options of the moving atmosphere (docs/model.md §9; names as the study keys). The
/// defaults are still air: no wind, no turbulence, no gust.

#include <cstdint>
#include <optional>
#include <string>

#include "engine/disturbance/mean_wind.h"

namespace gesweep {

/// Continuous turbulence model.
enum class TurbulenceModel {
  kNone,    ///< no continuous turbulence
  kDryden,  ///< the Dryden form, low altitude (dryden.h)
};
template <>
struct EnumNames<TurbulenceModel> {
  static constexpr EnumName<TurbulenceModel> kTable[] = {{TurbulenceModel::kNone, "none"},
                                                         {TurbulenceModel::kDryden, "dryden"}};
};

/// Body axis of the discrete gust.
enum class GustAxis {
  kU,  ///< along x, adds to u_g (positive forward: a tail gust)
  kW,  ///< along z, adds to w_g (positive down: a down gust)
};
template <>
struct EnumNames<GustAxis> {
  static constexpr EnumName<GustAxis> kTable[] = {{GustAxis::kU, "u"}, {GustAxis::kW, "w"}};
};

// Their names (the study keys' values): ToString, ParseEnum, EnumChoices of engine/common/enum_names.h.

/// Options of one run's disturbances.
struct DisturbanceOptions {
  /// Mean wind at 20 ft, m/s, as u_g: a headwind is negative. Finite.
  double wind_20ft_mps = 0.0;
  /// The shear profile; kLogarithmic is the specification's.
  WindShear wind_shear = WindShear::kLogarithmic;
  TurbulenceModel turbulence = TurbulenceModel::kNone;
  /// σ_w, m/s (≥ 0, finite); unset: 0.1·|W20| as the specification's low-altitude model.
  std::optional<double> turbulence_sigma_w_mps;
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
};

/// σ_w in force: the override, else 0.1·|W20|; 0 without turbulence.
double EffectiveSigmaW(const DisturbanceOptions& options);

/// Throws InputError(source, key, value, expectation) for the first option out of range.
void ValidateDisturbanceOptions(const DisturbanceOptions& options, const std::string& source);

}  // namespace gesweep
