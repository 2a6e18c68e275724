#include "engine/estimators/boundary_curve.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

// Tolerances: each says where it comes from.
/// A central difference with ΔU = 1e-2 m/s is accurate to ~1e-4 relative on the smooth curve; 1e-3 leaves
/// margin.
constexpr double kSlopeRelativeTolerance = 1e-3;

// The former sampled search (σ sampled per segment, TOMS 748 to its tolerance) is the oracle: it
// shares nothing with continuation or the Hurwitz criterion.
BoundaryResult Sampled(const LongitudinalModel& model, double speed_mps) {
  BoundaryOptions options;
  options.method = BoundaryMethod::kSampled;
  options.tolerance_m = 1e-7;
  return FindBoundary(model, speed_mps, options);
}
// The sampled search brackets to 1e-7 m; TOMS 748 returns the bracket's middle.
constexpr double kOracle_m = 1e-6;

class AnceCurve : public ::testing::Test {
 protected:
  Aircraft ance_ = LoadAircraftFile(testing::AnceAircraftPath());
  LongitudinalModel model_{ance_, ModelOptions{}};
};

TEST_F(AnceCurve, FollowsTheBoundaryAndFindsWhereItAppears) {
  const BoundaryCurve curve = TraceBoundary(model_, 24.0, 60.0);
  ASSERT_FALSE(curve.points.empty());
  // The ANCE is unstable at every height below about 25.7 m/s (the free-flight phugoid): one event,
  // the boundary appearing there.
  ASSERT_EQ(curve.events.size(), 1u);
  const BoundaryCurveEvent& appears = curve.events.front();
  EXPECT_EQ(appears.what, "appears");
  EXPECT_GT(appears.speed_mps, 25.5);
  EXPECT_LT(appears.speed_mps, 26.0);
  EXPECT_FALSE(Sampled(model_, appears.speed_mps - 1e-3).height_m.has_value());
  EXPECT_TRUE(Sampled(model_, appears.speed_mps + 1e-3).height_m.has_value());
  // Every traced point is H* by the oracle.
  for (const auto& p : curve.points) {
    const BoundaryResult oracle = Sampled(model_, p.speed_mps);
    ASSERT_TRUE(oracle.height_m) << p.speed_mps;
    EXPECT_NEAR(p.height_m, *oracle.height_m, kOracle_m) << p.speed_mps;
  }
  // Between points, the curve gives H* at any speed, and dH*/du0 matches a difference of the oracle.
  for (double u : {27.3, 32.0208, 41.7, 55.5}) {
    const auto h = BoundaryOnCurve(model_, curve, u);
    ASSERT_TRUE(h) << u;
    EXPECT_NEAR(*h, *Sampled(model_, u).height_m, kOracle_m) << u;
  }
  const auto at =
      std::find_if(curve.points.begin(), curve.points.end(), [](const auto& p) { return p.speed_mps > 40; });
  ASSERT_NE(at, curve.points.end());
  constexpr double kDu = 1e-2;  // H* moves ~1e-4 m, far above the oracle's 1e-7 m bracket
  const double fd =
      (*Sampled(model_, at->speed_mps + kDu).height_m - *Sampled(model_, at->speed_mps - kDu).height_m) /
      (2 * kDu);
  EXPECT_NEAR(at->height_speed_derivative, fd,
              kSlopeRelativeTolerance * std::max(1.0, std::abs(fd)) + 2 * kOracle_m / kDu);
  EXPECT_EQ(curve.points.front().speed_mps, appears.speed_mps);
  EXPECT_EQ(curve.points.back().speed_mps, 60.0);
}

TEST_F(AnceCurve, WithoutHDerivativesThereIsNoBranch) {
  ModelOptions off;
  off.h_derivatives = false;
  const BoundaryCurve curve = TraceBoundary(LongitudinalModel(ance_, off), 28.0, 40.0);
  EXPECT_TRUE(curve.points.empty());
  EXPECT_TRUE(curve.events.empty());
}

}  // namespace
}  // namespace gesweep
