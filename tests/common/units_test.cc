#include "engine/common/units.h"

#include <gtest/gtest.h>

#include <numbers>

namespace gesweep {
namespace {

// Oracles are the units' definitions, not the header: 1 ft = 0.3048 m and 1 kt = 1852 m per 3600 s
// exactly, 180° = π rad with π from std::numbers. A factor rounds once, so a product of a factor and
// its inverse may miss 1 by an ulp or two.
constexpr double kRoundTripTolerance = 4e-16;  // two roundings of a double near 1

TEST(Units, DegreesAndRadians) {
  EXPECT_DOUBLE_EQ(DegreesToRadians(180.0), std::numbers::pi);
  EXPECT_DOUBLE_EQ(DegreesToRadians(90.0), std::numbers::pi / 2.0);
  EXPECT_DOUBLE_EQ(RadiansToDegrees(std::numbers::pi), 180.0);
  EXPECT_DOUBLE_EQ(RadiansToDegrees(1.0), 57.29577951308232);  // 180/π to 16 digits
  EXPECT_NEAR(kRadiansPerDegree * kDegreesPerRadian, 1.0, kRoundTripTolerance);
  EXPECT_EQ(DegreesToRadians(0.0), 0.0);
}

TEST(Units, FeetAndMetres) {
  EXPECT_DOUBLE_EQ(FeetToMetres(1.0), 0.3048);
  EXPECT_DOUBLE_EQ(FeetToMetres(1000.0), 304.8);
  EXPECT_DOUBLE_EQ(MetresToFeet(0.3048 * 20.0), 20.0);
  EXPECT_DOUBLE_EQ(MetresToFeet(1.0), 1.0 / 0.3048);  // 3.280839895... ft
  EXPECT_DOUBLE_EQ(MetresToFeet(FeetToMetres(0.15)), 0.15);
}

TEST(Units, KnotsAndMetresPerSecond) {
  EXPECT_DOUBLE_EQ(KnotsToMetresPerSecond(3600.0), 1852.0);  // a nautical mile per hour
  EXPECT_DOUBLE_EQ(KnotsToMetresPerSecond(30.0), 15.433333333333334);
  EXPECT_DOUBLE_EQ(MetresPerSecondToKnots(1852.0 / 3600.0), 1.0);
  EXPECT_DOUBLE_EQ(MetresPerSecondToKnots(KnotsToMetresPerSecond(45.0)), 45.0);
}

// The factors are usable where a constant expression is required.
static_assert(DegreesToRadians(0.0) == 0.0 && FeetToMetres(0.0) == 0.0);
static_assert(kMetresPerFoot == 0.3048);

}  // namespace
}  // namespace gesweep
