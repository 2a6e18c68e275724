#include "engine/aircraft/atmosphere.h"

#include <cmath>
#include <limits>

namespace gesweep {

double IsaDensity(double altitude_m) {
  if (!(altitude_m >= -610.0 && altitude_m <= kTropopauseAltitude_m)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  constexpr double kExponent = kGravity_mps2 / (kAirGasConstant_JpkgK * kTroposphereLapseRate_Kpm) - 1.0;
  const double temperature_ratio = 1.0 - kTroposphereLapseRate_Kpm * altitude_m / kSeaLevelTemperature_K;
  return kSeaLevelDensity_kgpm3 * std::pow(temperature_ratio, kExponent);
}

}  // namespace gesweep
