#include "engine/disturbance/disturbance_field.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "engine/common/errors.h"
#include "engine/disturbance/discrete_gust.h"
#include "engine/disturbance/dryden.h"
#include "engine/disturbance/mean_wind.h"

namespace gesweep {

DisturbanceField::DisturbanceField(const DisturbanceOptions& options, std::uint64_t study_seed,
                                   std::uint64_t run_index)
    : DisturbanceField(options, RunNoise(study_seed, run_index)) {}

DisturbanceField::DisturbanceField(const DisturbanceOptions& options, std::span<const double> noise_point)
    : DisturbanceField(options, RunNoise(noise_point)) {}

DisturbanceField::DisturbanceField(const DisturbanceOptions& options, const RunNoise& noise)
    : options_(options),
      noise_(noise),
      cached_height_m_(std::numeric_limits<double>::quiet_NaN()),
      cached_rates_height_m_(std::numeric_limits<double>::quiet_NaN()) {
  ValidateDisturbanceOptions(options_, "disturbance options");
  sigma_w_mps_ = EffectiveSigmaW(options_);
  turbulent_ = options_.turbulence == TurbulenceModel::kDryden;
  has_gust_ = options_.gust_amplitude_mps != 0.0;
  noise_scale_ = 1.0 / std::sqrt(options_.turbulence_sample_interval_s);
  // MeanWindAt holds its value from the ceiling up, LowAltitudeDrydenScales clamps to [floor, ceiling]:
  // at the clamped heights these are the values they return.
  ceiling_mean_wind_mps_ = MeanWindAt(options_.wind_20ft_mps, kLowAltitudeCeiling_m, options_.wind_shear);
  ceiling_scales_ = LowAltitudeDrydenScales(kLowAltitudeCeiling_m, sigma_w_mps_);
  floor_scales_ = LowAltitudeDrydenScales(kDrydenFloorHeight_m, sigma_w_mps_);
}

void DisturbanceField::UpdateHeightTerms(double height_m) const {
  if (height_m == cached_height_m_) return;  // false for NaN: it is computed (and propagates)
  if (height_m >= kLowAltitudeCeiling_m) {
    cached_mean_wind_mps_ = ceiling_mean_wind_mps_;
    cached_scales_ = ceiling_scales_;
  } else {
    cached_mean_wind_mps_ = MeanWindAt(options_.wind_20ft_mps, height_m, options_.wind_shear);
    if (turbulent_) {
      cached_scales_ =
          height_m <= kDrydenFloorHeight_m ? floor_scales_ : LowAltitudeDrydenScales(height_m, sigma_w_mps_);
    }
  }
  cached_height_m_ = height_m;
}

void DisturbanceField::HeightTerms(double height_m, double& mean_wind_mps, double& sigma_u_mps,
                                   double& length_u_m, double& length_w_m) const {
  UpdateHeightTerms(height_m);
  mean_wind_mps = cached_mean_wind_mps_;
  sigma_u_mps = cached_scales_.sigma_u_mps;
  length_u_m = cached_scales_.length_u_m;
  length_w_m = cached_scales_.length_w_m;
}

DisturbanceField::State DisturbanceField::InitialState() const {
  State x{};
  if (turbulent_) {
    // Stationary covariances of the normalised filters (dryden.h): z ~ N(0, 1);
    // (x1, x2) ~ N(0, [[1/2, 1/4], [1/4, 1/4]]) by its Cholesky factor [[√½, 0], [√⅛, √⅛]].
    const double n0 = noise_.StandardNormal(NoiseStream::kInitialState, 0);
    const double n1 = noise_.StandardNormal(NoiseStream::kInitialState, 1);
    const double n2 = noise_.StandardNormal(NoiseStream::kInitialState, 2);
    x[kTurbulenceU] = n0;
    x[kTurbulenceW1] = std::sqrt(0.5) * n1;
    x[kTurbulenceW2] = std::sqrt(0.125) * (n1 + n2);
  }
  // w_g(0): σ_w does not depend on height, and the gust has not begun (distance 0).
  x[kPitchRateLag] = sigma_w_mps_ * DrydenWOutput(x[kTurbulenceW1], x[kTurbulenceW2]);
  return x;
}

std::int64_t DisturbanceField::SampleIndexAt(double t) const {
  const double dt = options_.turbulence_sample_interval_s;
  if (!(t >= dt)) return 0;
  // The instants are the doubles k·Δt_n exactly as Breakpoints writes them; correct the division's rounding.
  auto k = static_cast<std::int64_t>(std::floor(t / dt));
  while (static_cast<double>(k + 1) * dt <= t) ++k;
  while (k > 0 && static_cast<double>(k) * dt > t) --k;
  return k;
}

std::vector<double> DisturbanceField::Breakpoints(double start_s, double end_s,
                                                  const std::atomic<bool>* cancel) const {
  std::vector<double> b;
  if (turbulent_) {
    const double dt = options_.turbulence_sample_interval_s;
    for (std::int64_t k = SampleIndexAt(start_s) + 1;; ++k) {
      if (cancel != nullptr && k % kCancelCheckInterval == 0 && cancel->load(std::memory_order_relaxed)) {
        return {};  // SIGINT/SIGTERM while the table is built: the run stops before its first step
      }
      const double t = static_cast<double>(k) * dt;
      if (!(t < end_s)) break;
      if (t > start_s) b.push_back(t);
    }
  }
  if (has_gust_ && options_.gust_start_s > start_s && options_.gust_start_s < end_s) {
    b.insert(std::upper_bound(b.begin(), b.end(), options_.gust_start_s), options_.gust_start_s);
    b.erase(std::unique(b.begin(), b.end()), b.end());
  }
  return b;
}

std::vector<DisturbanceField::Segment> DisturbanceField::SegmentTable(std::span<const double> breakpoints_s,
                                                                      double start_s,
                                                                      const std::atomic<bool>* cancel) const {
  std::vector<Segment> table(breakpoints_s.size() + 1);
  for (std::size_t s = 0; s < table.size(); ++s) {
    if (cancel != nullptr && s % kCancelCheckInterval == 0 && cancel->load(std::memory_order_relaxed)) break;
    const double t = s == 0 ? start_s : breakpoints_s[s - 1];  // the segment's left end
    table[s].sample_index = SampleIndexAt(t);
    table[s].gust_started = t >= options_.gust_start_s;
  }
  return table;
}

double DisturbanceField::HeldNoise(NoiseStream stream, std::int64_t sample_index) const {
  GESWEEP_DEMAND(sample_index >= 0);
  return noise_.StandardNormal(stream, static_cast<std::uint64_t>(sample_index)) * noise_scale_;
}

AirMotion DisturbanceField::Motion(const Segment& segment, double height_m, double inertial_speed_mps,
                                   const State& x) const {
  (void)segment;
  AirMotion m;
  UpdateHeightTerms(height_m);
  m.mean_wind_mps = cached_mean_wind_mps_;
  if (has_gust_) {
    m.gust_mps =
        OneMinusCosineGust(x[kGustDistance], options_.gust_amplitude_mps, options_.gust_half_length_m);
  }
  if (turbulent_) {
    m.turbulence_u_mps = cached_scales_.sigma_u_mps * x[kTurbulenceU];
    m.turbulence_w_mps = sigma_w_mps_ * DrydenWOutput(x[kTurbulenceW1], x[kTurbulenceW2]);
  }
  const bool u_gust = options_.gust_axis == GustAxis::kU;
  m.u_g_mps = m.mean_wind_mps + m.turbulence_u_mps + (u_gust ? m.gust_mps : 0.0);
  m.w_g_mps = m.turbulence_w_mps + (u_gust ? 0.0 : m.gust_mps);
  m.airspeed_mps = inertial_speed_mps - m.u_g_mps;
  if (options_.pitch_rate_gust) {
    // q_g = −(s/V)/(1 + τ s)·w_g with τ = 4b/(πV): with the lag p = w_g/(1 + τ s),
    // q_g = −ṗ/V = −(w_g − p)·π/(4b), ṗ = (w_g − p)·πV/(4b).
    const double k = std::numbers::pi / (4.0 * options_.wing_span_m);
    m.q_g_radps = -(m.w_g_mps - x[kPitchRateLag]) * k;
  }
  m.w_g_dot_mps2 = std::numeric_limits<double>::quiet_NaN();  // not computed here (Evaluate)
  return m;
}

AirMotion DisturbanceField::Evaluate(const Segment& segment, double height_m, double inertial_speed_mps,
                                     const State& x, State& dxdt) const {
  AirMotion m = Motion(segment, height_m, inertial_speed_mps, x);
  m.w_g_dot_mps2 = 0.0;
  dxdt.fill(0.0);
  const bool u_gust = options_.gust_axis == GustAxis::kU;
  if (turbulent_) {
    if (segment.sample_index != cached_index_) {
      cached_u_ = HeldNoise(NoiseStream::kTurbulenceU, segment.sample_index);
      cached_w_ = HeldNoise(NoiseStream::kTurbulenceW, segment.sample_index);
      cached_index_ = segment.sample_index;
    }
    // The rates and their square roots depend on the height and the airspeed alone: a step's end and
    // the restart at a sample instant share them (the same doubles as DrydenRates and the filters' √).
    if (!(height_m == cached_rates_height_m_ && m.airspeed_mps == cached_rates_airspeed_mps_)) {
      const DrydenFilterRates rates = DrydenRates(cached_scales_, m.airspeed_mps);
      cached_a_u_ = rates.a_u_per_s;
      cached_a_w_ = rates.a_w_per_s;
      cached_gain_u_ = std::sqrt(2.0 * rates.a_u_per_s);
      cached_gain_w_ = std::sqrt(rates.a_w_per_s);
      cached_rates_height_m_ = height_m;
      cached_rates_airspeed_mps_ = m.airspeed_mps;
    }
    // DrydenUDerivative and DrydenWDerivative (dryden.h) with their square roots taken above.
    dxdt[kTurbulenceU] = -cached_a_u_ * x[kTurbulenceU] + cached_gain_u_ * cached_u_;
    dxdt[kTurbulenceW1] = -cached_a_w_ * x[kTurbulenceW1] + cached_gain_w_ * cached_w_;
    dxdt[kTurbulenceW2] = cached_a_w_ * (x[kTurbulenceW1] - x[kTurbulenceW2]);
    // σ_w does not vary with height, so ẇ_g of the turbulence is σ_w times the output's rate.
    m.w_g_dot_mps2 = sigma_w_mps_ * DrydenWOutput(dxdt[kTurbulenceW1], dxdt[kTurbulenceW2]);
  }
  if (has_gust_ && segment.gust_started) {
    dxdt[kGustDistance] = m.airspeed_mps;  // the gust is frozen in the air mass
    if (!u_gust) {
      const double gust_slope =
          OneMinusCosineGustSlope(x[kGustDistance], options_.gust_amplitude_mps, options_.gust_half_length_m);
      m.w_g_dot_mps2 += gust_slope * m.airspeed_mps;
    }
  }
  if (options_.pitch_rate_gust) {
    const double k = std::numbers::pi / (4.0 * options_.wing_span_m);
    const double lead = m.w_g_mps - x[kPitchRateLag];
    dxdt[kPitchRateLag] = lead * k * std::max(m.airspeed_mps, 0.0);
  }
  return m;
}

}  // namespace gesweep
