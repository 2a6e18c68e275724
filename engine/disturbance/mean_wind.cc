#include "engine/disturbance/mean_wind.h"

#include <algorithm>
#include <cmath>

namespace gesweep {

double MeanWindAt(double wind_20ft_mps, double height_m, WindShear shear) {
  if (shear == WindShear::kNone) return wind_20ft_mps;
  if (std::isnan(height_m)) return height_m;
  if (height_m <= kTerminalRoughnessLength_m) return 0.0;  // the formula turns negative below z0
  static const double reference_log = std::log(kWindReferenceHeight_m / kTerminalRoughnessLength_m);
  const double h = std::min(height_m, kLowAltitudeCeiling_m);
  return wind_20ft_mps * std::log(h / kTerminalRoughnessLength_m) / reference_log;
}

}  // namespace gesweep
