// The 1 − cos discrete gust (docs/model.md §9): shape, ends and slope.
#include "engine/disturbance/discrete_gust.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gesweep {
namespace {

constexpr double kTolerance = 1e-12;  // cos of exact multiples of π/4: rounding only

TEST(DiscreteGust, ShapeAtQuarterPointsAndEnds) {
  const double vm = 3.0, dm = 40.0;
  EXPECT_EQ(OneMinusCosineGust(-1.0, vm, dm), 0.0);
  EXPECT_EQ(OneMinusCosineGust(0.0, vm, dm), 0.0);
  EXPECT_NEAR(OneMinusCosineGust(dm / 4, vm, dm), 0.5 * vm * (1.0 - std::sqrt(0.5)), kTolerance);
  EXPECT_NEAR(OneMinusCosineGust(dm / 2, vm, dm), vm / 2, kTolerance);
  EXPECT_NEAR(OneMinusCosineGust(dm, vm, dm), vm, kTolerance);
  EXPECT_NEAR(OneMinusCosineGust(1.5 * dm, vm, dm), vm / 2, kTolerance);
  EXPECT_EQ(OneMinusCosineGust(2 * dm, vm, dm), 0.0);
  EXPECT_EQ(OneMinusCosineGust(2 * dm + 1.0, vm, dm), 0.0);
  // Continuous at both ends: just inside is O(x²).
  EXPECT_LT(OneMinusCosineGust(1e-3, vm, dm), 1e-8);
  EXPECT_LT(OneMinusCosineGust(2 * dm - 1e-3, vm, dm), 1e-8);
  // Symmetric bump, sign follows the amplitude.
  EXPECT_NEAR(OneMinusCosineGust(0.3 * dm, -vm, dm), -OneMinusCosineGust(1.7 * dm, vm, dm), kTolerance);
}

TEST(DiscreteGust, SlopeIsTheDerivative) {
  const double vm = -2.0, dm = 25.0;
  constexpr double kStep = 1e-4;                 // central difference, error ~ kStep² · v''' ≈ 1e-11
  constexpr double kDifferenceTolerance = 1e-8;  // rounding of the difference: 1e-16 · vm / kStep
  for (double x : {0.5, 5.0, 12.5, 25.0, 40.0, 49.5}) {
    const double fd =
        (OneMinusCosineGust(x + kStep, vm, dm) - OneMinusCosineGust(x - kStep, vm, dm)) / (2 * kStep);
    EXPECT_NEAR(OneMinusCosineGustSlope(x, vm, dm), fd, kDifferenceTolerance) << x;
  }
  EXPECT_EQ(OneMinusCosineGustSlope(-1.0, vm, dm), 0.0);
  EXPECT_EQ(OneMinusCosineGustSlope(60.0, vm, dm), 0.0);
}

}  // namespace
}  // namespace gesweep
