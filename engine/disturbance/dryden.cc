#include "engine/disturbance/dryden.h"

#include <algorithm>
#include <numbers>

#include "engine/disturbance/mean_wind.h"

namespace gesweep {

DrydenScales LowAltitudeDrydenScales(double height_m, double sigma_w_mps) {
  DrydenScales s;
  if (std::isnan(height_m)) {
    s.sigma_u_mps = s.sigma_w_mps = s.length_u_m = s.length_w_m = height_m;
    return s;
  }
  const double h_ft = std::clamp(height_m, kDrydenFloorHeight_m, kLowAltitudeCeiling_m) / kMetresPerFoot;
  const double base = 0.177 + 0.000823 * h_ft;
  // One pow: base^0.4 = b², base^1.2 = b⁶ with b = base^0.2.
  const double b = std::pow(base, 0.2);
  const double b2 = b * b;
  s.sigma_w_mps = sigma_w_mps;
  s.sigma_u_mps = sigma_w_mps / b2;
  s.length_w_m = h_ft * kMetresPerFoot;
  s.length_u_m = h_ft * kMetresPerFoot / (b2 * b2 * b2);
  return s;
}

double DrydenSpectrumU(double omega, const DrydenScales& s) {
  const double lo = s.length_u_m * omega;
  return s.sigma_u_mps * s.sigma_u_mps * (2.0 * s.length_u_m / std::numbers::pi) / (1.0 + lo * lo);
}

double DrydenSpectrumW(double omega, const DrydenScales& s) {
  const double lo2 = (s.length_w_m * omega) * (s.length_w_m * omega);
  return s.sigma_w_mps * s.sigma_w_mps * (s.length_w_m / std::numbers::pi) * (1.0 + 3.0 * lo2) /
         ((1.0 + lo2) * (1.0 + lo2));
}

}  // namespace gesweep
