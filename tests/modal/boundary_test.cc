#include "engine/modal/boundary.h"

#include <gtest/gtest.h>

#include "engine/modal/modal_analysis.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

constexpr double kPaperSpeed_mps = 32.0208;  // 1.3 × stall speed, the paper's open-loop cases
constexpr double kMillimetre = 1e-3;         // the required accuracy of H*

class AnceBoundary : public ::testing::Test {
 protected:
  BoundaryResult Find(const ModelOptions& options, double speed = kPaperSpeed_mps) {
    return FindBoundary(LongitudinalModel(ance_, options), speed);
  }
  Aircraft ance_ = LoadAircraftFile(testing::AnceAircraftPath());
};

TEST_F(AnceBoundary, LiesBetweenThePapersNeighbouringRows) {
  // The paper (Section IV; Boschetti & Cárdenas) finds the ANCE stable down to H/b = 0.5 (2.5935 m)
  // and unstable below; on its table that places the sign change between the rows at H/b = 0.4 and 0.58.
  const BoundaryResult result = Find(ModelOptions{});
  ASSERT_TRUE(result.height_m.has_value()) << result.reason;
  EXPECT_GT(*result.height_m, 2.0748);
  EXPECT_LT(*result.height_m, 2.9987);
  EXPECT_GT(*result.height_over_span, 0.4);
  EXPECT_LT(*result.height_over_span, 0.5781);
}

TEST_F(AnceBoundary, IsLocatedToAMillimetre) {
  const LongitudinalModel model(ance_, ModelOptions{});
  const BoundaryResult result = FindBoundary(model, kPaperSpeed_mps);
  ASSERT_TRUE(result.height_m.has_value());
  // The definition itself is the oracle: unstable a millimetre below, stable a millimetre above.
  EXPECT_GT(StabilityMargin(model, *result.height_m - kMillimetre, kPaperSpeed_mps), 0.0);
  EXPECT_LT(StabilityMargin(model, *result.height_m + kMillimetre, kPaperSpeed_mps), 0.0);
  EXPECT_LE(result.crossings.front().bracket_width_m, kMillimetre);
}

TEST_F(AnceBoundary, VanishesWithoutHDerivatives) {
  ModelOptions off;
  off.h_derivatives = false;
  const BoundaryResult result = Find(off);
  EXPECT_FALSE(result.height_m.has_value());
  EXPECT_NE(result.reason.find("stable at every height"), std::string::npos) << result.reason;
}

TEST_F(AnceBoundary, MovesUpWithStrongerLiftHeightDerivative) {
  // CLh < 0 (lift grows as the airplane sinks) couples height into the phugoid and destabilises it
  // (Staufenbiel & Schlichting): a stronger CLh must raise the boundary, a weaker one lower it.
  const double base = *Find(ModelOptions{}).height_m;
  ModelOptions stronger, weaker;
  stronger.coefficient_scale[Index(Coefficient::CLh)] = 2.0;
  weaker.coefficient_scale[Index(Coefficient::CLh)] = 0.5;
  const BoundaryResult up = Find(stronger);
  const BoundaryResult down = Find(weaker);
  ASSERT_TRUE(up.height_m && down.height_m);
  EXPECT_GT(*up.height_m, base + 0.1);
  EXPECT_LT(*down.height_m, base - 0.1);
}

TEST_F(AnceBoundary, ReportsEveryCrossingHighestFirst) {
  const BoundaryResult result = Find(ModelOptions{});
  for (std::size_t i = 1; i < result.crossings.size(); ++i) {
    EXPECT_GT(result.crossings[i - 1].height_m, result.crossings[i].height_m);
  }
  EXPECT_EQ(result.crossings.front().height_m, *result.height_m);
}

}  // namespace
}  // namespace gesweep
