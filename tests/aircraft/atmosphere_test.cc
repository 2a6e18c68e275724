#include "engine/aircraft/atmosphere.h"

#include <gtest/gtest.h>

#include <cmath>

namespace gesweep {
namespace {

// Published ISA densities (ISO 2533 tables) are printed to 5 significant digits at geometric
// altitude; the engine takes geopotential altitude, which differs by 0.16 m at 1 km (Δρ ≈ 2e-5).
constexpr double kTablePrecision = 1e-4;

TEST(IsaDensity, MatchesPublishedTable) {
  EXPECT_NEAR(IsaDensity(0.0), 1.2250, kTablePrecision);
  EXPECT_NEAR(IsaDensity(1000.0), 1.1117, kTablePrecision);
  EXPECT_NEAR(IsaDensity(5000.0), 0.73612, kTablePrecision);
  EXPECT_NEAR(IsaDensity(11000.0), 0.36392, kTablePrecision);
}

TEST(IsaDensity, DecreasesWithAltitudeAndIsNanOutsideTheTroposphere) {
  EXPECT_GT(IsaDensity(0.0), IsaDensity(1.0));
  EXPECT_TRUE(std::isnan(IsaDensity(20000.0)));
  EXPECT_TRUE(std::isnan(IsaDensity(std::nan(""))));
}

}  // namespace
}  // namespace gesweep
