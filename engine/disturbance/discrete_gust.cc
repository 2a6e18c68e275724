#include "engine/disturbance/discrete_gust.h"

#include <cmath>
#include <numbers>

namespace gesweep {

double OneMinusCosineGust(double x, double amplitude_mps, double half_length_m) {
  if (!(x > 0.0 && x < 2.0 * half_length_m)) return std::isnan(x) ? x : 0.0;
  return 0.5 * amplitude_mps * (1.0 - std::cos(std::numbers::pi * x / half_length_m));
}

double OneMinusCosineGustSlope(double x, double amplitude_mps, double half_length_m) {
  if (!(x > 0.0 && x < 2.0 * half_length_m)) return std::isnan(x) ? x : 0.0;
  return 0.5 * amplitude_mps * (std::numbers::pi / half_length_m) *
         std::sin(std::numbers::pi * x / half_length_m);
}

}  // namespace gesweep
