#pragma once
/// The Dryden form of continuous turbulence of MIL-F-8785C, section 3.7, low altitude
/// (docs/model.md §9): the intensities and scale lengths as functions of height, the one-sided
/// spectra Φ_u, Φ_w, and the forming filters in the normalised realisation of docs/disturbance.md.
/// Feet inside the formulas, SI at the interface.

#include <cmath>

#include "engine/disturbance/mean_wind.h"

namespace gesweep {

/// The height floor of the scale formulas: 10 ft (docs/model.md §9, a choice, as JSBSim does).
inline constexpr double kDrydenFloorHeight_m = 10.0 * kMetresPerFoot;

/// Intensities (m/s) and scale lengths (m) of the u and w components at one height.
struct DrydenScales {
  double sigma_u_mps = 0;
  double sigma_w_mps = 0;
  double length_u_m = 0;
  double length_w_m = 0;
};

/// Low-altitude scales at height h (m) for the vertical intensity σ_w (m/s, ≥ 0; 0.1·|W20| by the
/// specification): with h in feet clamped to [10, 1000], L_w = h, L_u = h/(0.177 + 0.000823 h)^1.2,
/// σ_u = σ_w/(0.177 + 0.000823 h)^0.4. NaN height gives NaN scales.
DrydenScales LowAltitudeDrydenScales(double height_m, double sigma_w_mps);

/// Φ_u(Ω) = σ_u²·(2 L_u/π)/(1 + (L_u Ω)²): one-sided spectrum of u_g over the spatial frequency
/// Ω ≥ 0 (rad/m), in (m/s)² per rad/m; ∫₀^∞ Φ_u dΩ = σ_u².
double DrydenSpectrumU(double spatial_frequency_radpm, const DrydenScales& scales);
/// Φ_w(Ω) = σ_w²·(L_w/π)·(1 + 3 (L_w Ω)²)/(1 + (L_w Ω)²)², as Φ_u.
double DrydenSpectrumW(double spatial_frequency_radpm, const DrydenScales& scales);

/// The forming filters, normalised to unit variance and driven by unit-intensity white noise ξ
/// (E[ξ(t)ξ(t+τ)] = δ(τ)); the physical outputs are u_g = σ_u·z and w_g = σ_w·(√3 x1 + (1−√3) x2).
/// With a_u = V/L_u and a_w = V/L_w (V the airspeed):
///   ż  = −a_u z + √(2 a_u) ξ_u                       (σ_u √(2L_u/V)/(1 + (L_u/V) s) in u_g)
///   ẋ1 = −a_w x1 + √a_w ξ_w,  ẋ2 = a_w (x1 − x2)     (σ_w √(L_w/V)(1 + √3 (L_w/V) s)/(1 + (L_w/V) s)²)
/// which are the specification's filters with the one-sided/two-sided factor √π taken into the
/// unit-intensity noise. Their stationary covariances (z: 1; x: [[1/2, 1/4], [1/4, 1/4]]) do not
/// depend on a, so a varying height or airspeed leaves the variance at σ(h)² at every instant.
struct DrydenFilterRates {
  double a_u_per_s = 0;
  double a_w_per_s = 0;
};

/// The filters' rates at airspeed V (m/s; a negative airspeed counts as 0: the filters freeze).
inline DrydenFilterRates DrydenRates(const DrydenScales& scales, double airspeed_mps) {
  const double v = airspeed_mps > 0.0 ? airspeed_mps : 0.0;
  return {v / scales.length_u_m, v / scales.length_w_m};
}

/// √3, of the w filter's zero and output.
inline constexpr double kSqrt3 = 1.7320508075688772;

/// ż of the normalised u filter driven by ξ_u (1/√s).
inline double DrydenUDerivative(double a_u_per_s, double z, double noise_u) {
  return -a_u_per_s * z + std::sqrt(2.0 * a_u_per_s) * noise_u;
}

/// (ẋ1, ẋ2) of the normalised w filter driven by ξ_w.
inline void DrydenWDerivative(double a_w_per_s, double x1, double x2, double noise_w, double* dx1,
                              double* dx2) {
  *dx1 = -a_w_per_s * x1 + std::sqrt(a_w_per_s) * noise_w;
  *dx2 = a_w_per_s * (x1 - x2);
}

/// The normalised w output √3 x1 + (1 − √3) x2 (unit variance when stationary).
inline double DrydenWOutput(double x1, double x2) { return kSqrt3 * x1 + (1.0 - kSqrt3) * x2; }

}  // namespace gesweep
