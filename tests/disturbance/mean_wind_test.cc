// The MIL-F-8785C mean wind and its shear (docs/model.md §9) against the formula worked by hand.
#include "engine/disturbance/mean_wind.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gesweep {
namespace {

// Hand values: z0 = 0.15 ft = 0.04572 m, 20 ft = 6.096 m, ln(6.096/0.04572) = ln(133.333…) = 4.892852258.
constexpr double kZ0_m = 0.04572;
constexpr double kReferenceLog = 4.892852258;
// Tolerances: each says where it comes from.
/// kReferenceLog carries 10 digits; everything else is exact arithmetic.
constexpr double kRelativeTolerance = 1e-9;
/// At 20 ft the engine divides ln(20 ft/z0) by the same logarithm: the ratio is 1, so W20 comes back
/// to a rounding (an ulp of 7.7 m/s is 8.9e-16 m/s).
constexpr double kReferenceHeightRounding_mps = 1e-12;
/// docs/model.md §9's table prints W/W20 to 3 decimals: half a unit of the last digit.
constexpr double kPrintedTable = 5e-4;
/// Above 1000 ft against HandProfile(5 m/s, 304.8 m) = 9.0 m/s: kReferenceLog's 10 digits (4.4e-10 below
/// ln(400/3)) move the hand value by 8e-10 m/s; 1e-8 m/s is that with a margin.
constexpr double kHeldWindTolerance_mps = 1e-8;

double HandProfile(double w20, double h_m) { return w20 * std::log(h_m / kZ0_m) / kReferenceLog; }

TEST(MeanWind, LogarithmicProfileAtChosenHeights) {
  const double w20 = -7.717;  // 15 kt headwind
  for (double h : {0.05, 0.788, 1.5561, 2.5935, 6.096, 10.0, 50.0, 100.0, 304.8}) {
    EXPECT_NEAR(MeanWindAt(w20, h, WindShear::kLogarithmic), HandProfile(w20, h),
                std::abs(HandProfile(w20, h)) * kRelativeTolerance)
        << "h = " << h;
  }
  EXPECT_NEAR(MeanWindAt(w20, 6.096, WindShear::kLogarithmic), w20, kReferenceHeightRounding_mps)
      << "W20 at 20 ft";
}

TEST(MeanWind, RatiosOfTheModelTable) {
  // docs/model.md §9's table (3 decimals), independent of this code.
  const double w20 = 1.0;
  EXPECT_NEAR(MeanWindAt(w20, 0.788, WindShear::kLogarithmic), 0.582, kPrintedTable);
  EXPECT_NEAR(MeanWindAt(w20, 2.5935, WindShear::kLogarithmic), 0.825, kPrintedTable);
  EXPECT_NEAR(MeanWindAt(w20, 10.0, WindShear::kLogarithmic), 1.101, kPrintedTable);
  EXPECT_NEAR(MeanWindAt(w20, 304.8, WindShear::kLogarithmic), 1.800, kPrintedTable);
}

TEST(MeanWind, ZeroBelowRoughnessHeldAboveThousandFeetConstantWithoutShear) {
  EXPECT_EQ(MeanWindAt(5.0, 0.04, WindShear::kLogarithmic), 0.0);
  EXPECT_EQ(MeanWindAt(5.0, kZ0_m, WindShear::kLogarithmic), 0.0);
  EXPECT_EQ(MeanWindAt(5.0, -1.0, WindShear::kLogarithmic), 0.0);
  EXPECT_GT(MeanWindAt(5.0, 0.05, WindShear::kLogarithmic), 0.0);
  EXPECT_NEAR(MeanWindAt(5.0, 500.0, WindShear::kLogarithmic), HandProfile(5.0, 304.8),
              kHeldWindTolerance_mps);
  EXPECT_EQ(MeanWindAt(5.0, 500.0, WindShear::kLogarithmic), MeanWindAt(5.0, 304.8, WindShear::kLogarithmic));
  for (double h : {0.0, 0.788, 50.0, 500.0}) EXPECT_EQ(MeanWindAt(-3.5, h, WindShear::kNone), -3.5);
  EXPECT_TRUE(std::isnan(MeanWindAt(5.0, std::nan(""), WindShear::kLogarithmic)));
}

}  // namespace
}  // namespace gesweep
