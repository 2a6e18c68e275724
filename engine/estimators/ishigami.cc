#include "engine/estimators/ishigami.h"

#include <cmath>
#include <numbers>

namespace gesweep {

double Ishigami(const std::array<double, 3>& x, double a, double b) {
  const double sin_x2 = std::sin(x[1]);
  const double x3_squared = x[2] * x[2];
  return std::sin(x[0]) * (1.0 + b * x3_squared * x3_squared) + a * sin_x2 * sin_x2;
}

std::vector<ParameterRange> IshigamiRanges() {
  constexpr double pi = std::numbers::pi;
  return {{"x1", -pi, pi}, {"x2", -pi, pi}, {"x3", -pi, pi}};
}

}  // namespace gesweep
