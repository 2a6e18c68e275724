#include "engine/modal/boundary.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "engine/modal/modal_analysis.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

// Tolerances: each says where it comes from.
/// Two searches that bracket the same crossing agree to their root-finding tolerance, well below 1e-9 m.
constexpr double kSameSearchTolerance_m = 1e-9;
/// Frequencies and slopes of affine blocks are read back from a linear family: exact but for rounding.
constexpr double kAffineBlockTolerance = 1e-9;

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

TEST_F(AnceBoundary, IsThePapersValueByBothMethods) {
  // H* = 2.700761 m at 32.0208 m/s (the value before issue 16, to its printed 7 digits), by the
  // certified finder and by the former sampled search kept for comparison.
  constexpr double kPrintedDigits = 5e-7;
  const LongitudinalModel model(ance_, ModelOptions{});
  const BoundaryResult hurwitz = FindBoundary(model, kPaperSpeed_mps);
  BoundaryOptions sampled_options;
  sampled_options.method = BoundaryMethod::kSampled;
  const BoundaryResult sampled = FindBoundary(model, kPaperSpeed_mps, sampled_options);
  ASSERT_TRUE(hurwitz.height_m && sampled.height_m);
  EXPECT_NEAR(*hurwitz.height_m, 2.700761, kPrintedDigits);
  EXPECT_NEAR(*sampled.height_m, *hurwitz.height_m, sampled_options.tolerance_m);
  EXPECT_TRUE(hurwitz.certified) << hurwitz.certificate;
  EXPECT_FALSE(sampled.certified);
  ASSERT_EQ(hurwitz.crossings.size(), 1u);
  const BoundaryCrossing& c = hurwitz.crossings.front();
  EXPECT_EQ(c.kind, CrossingKind::kHopf);
  EXPECT_EQ(c.mode, "phugoid");  // the paper: the phugoid is what ground effect destabilises
  EXPECT_TRUE(c.mode_stable_above);
  EXPECT_TRUE(c.stable_above);
  EXPECT_FALSE(c.stable_below);
  // Its eigenvalue is on the axis: the definition of a crossing, checked with Eigen directly.
  const auto lambda =
      Eigen::EigenSolver<Matrix5d>(model.StateMatrix(c.height_m, kPaperSpeed_mps), false).eigenvalues();
  double closest = 1;
  for (int i = 0; i < 5; ++i) closest = std::min(closest, std::abs(lambda[i].real()));
  EXPECT_LT(closest, 1e-12);
}

TEST_F(AnceBoundary, PchipIsCertifiedToo) {
  // PCHIP is a cubic on each segment, so the criteria stay polynomials (of degree ≤ 55).
  ModelOptions pchip;
  pchip.interpolation = Interpolation::kPchip;
  const LongitudinalModel model(ance_, pchip);
  const BoundaryResult result = FindBoundary(model, kPaperSpeed_mps);
  ASSERT_TRUE(result.height_m);
  EXPECT_TRUE(result.certified) << result.certificate;
  EXPECT_GT(StabilityMargin(model, *result.height_m - kMillimetre, kPaperSpeed_mps), 0.0);
  EXPECT_LT(StabilityMargin(model, *result.height_m + kMillimetre, kPaperSpeed_mps), 0.0);
}

TEST_F(AnceBoundary, FreeFlightAboveTheTableIsNeutralNotACrossing) {
  // Above the last row a₅ ≡ 0 (the free-flight height root is exactly neutral); scanning up to 40 m
  // adds no crossing, and H* stays.
  const LongitudinalModel model(ance_, ModelOptions{});
  BoundaryOptions options;
  options.upper_height_m = 40.0;
  const BoundaryResult result = FindBoundary(model, kPaperSpeed_mps, options);
  ASSERT_TRUE(result.height_m);
  EXPECT_NEAR(*result.height_m, *FindBoundary(model, kPaperSpeed_mps).height_m, kSameSearchTolerance_m);
  EXPECT_EQ(result.crossings.size(), 1u);
  EXPECT_TRUE(result.certified) << result.certificate;
}

// --- The certificate on synthetic affine families A(H) = A0 + H·A1 with known crossings ---

// S·D(H)·S⁻¹ with D(H) block-diagonal: two complex pairs whose real parts are affine in H and vanish
// at known heights, and one real root that does. Affine in H, so deg aₖ ≤ k.
struct AffineFamily {
  Matrix5d A0, A1;
  Matrix5d operator()(double h) const { return A0 + h * A1; }
};

AffineFamily MakeFamily(double pair1_root, double pair1_slope, double pair2_root, double pair2_slope,
                        double real_root, double real_slope, std::uint64_t seed) {
  Matrix5d D0 = Matrix5d::Zero(), D1 = Matrix5d::Zero();
  auto pair = [&](int i, double root, double slope, double omega) {
    D0(i, i) = D0(i + 1, i + 1) = -slope * root;
    D1(i, i) = D1(i + 1, i + 1) = slope;
    D0(i, i + 1) = omega;
    D0(i + 1, i) = -omega;
  };
  pair(0, pair1_root, pair1_slope, 3.2);
  pair(2, pair2_root, pair2_slope, 0.27);
  D0(4, 4) = -real_slope * real_root;
  D1(4, 4) = real_slope;
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  Matrix5d S = Matrix5d::Identity();
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) S(i, j) += u(random);
  const Matrix5d Si = S.inverse();
  return {S * D0 * Si, S * D1 * Si};
}

std::vector<MatrixSegment> Segments(const AffineFamily& family, const std::vector<double>& knots) {
  std::vector<MatrixSegment> segments;
  for (std::size_t i = 0; i + 1 < knots.size(); ++i) {
    MatrixSegment s;
    s.lower_height_m = knots[i];
    s.upper_height_m = knots[i + 1];
    s.coefficient_degrees = {0, 1, 2, 3, 4, 5};
    s.polynomial_matrix = s.exact_matrix = family;
    segments.push_back(s);
  }
  return segments;
}

// The roots are refined to rounding; the similarity costs a few digits.
constexpr double kRootTolerance_m = 1e-9;

TEST(CrossingSearch, FindsAClosePairTheSampledSearchMisses) {
  // Pair 1 stable above 3.10 m, pair 2 unstable above 3.15 m: the airplane is stable only in a 5 cm
  // window, between two samples of the former search (24 per 10 m segment: every 0.4 m). The real
  // root is unstable above 7.5 m.
  const AffineFamily family = MakeFamily(3.10, -0.05, 3.15, 0.02, 7.5, 0.01, 1);
  const std::vector<double> knots = {0.0, 10.0};
  const SampledSearchResult old = SampledCrossingSearch(family, knots, 24, 1e-4);
  EXPECT_TRUE(old.crossings.empty());  // σ > 0 at every sample

  const CrossingSearchResult found = CrossingSearch(Segments(family, knots), 1.0);
  ASSERT_TRUE(found.finite);
  EXPECT_TRUE(found.certified) << found.uncertified_reason;
  ASSERT_EQ(found.crossings.size(), 3u);
  EXPECT_NEAR(found.crossings[0].height_m, 3.10, kRootTolerance_m);
  EXPECT_NEAR(found.crossings[1].height_m, 3.15, kRootTolerance_m);
  EXPECT_NEAR(found.crossings[2].height_m, 7.5, kRootTolerance_m);
  EXPECT_EQ(found.crossings[0].kind, CrossingKind::kHopf);
  EXPECT_EQ(found.crossings[1].kind, CrossingKind::kHopf);
  EXPECT_EQ(found.crossings[2].kind, CrossingKind::kReal);
  EXPECT_NEAR(std::abs(found.crossings[0].eigenvalue.imag()), 3.2, kAffineBlockTolerance);
  EXPECT_NEAR(std::abs(found.crossings[1].eigenvalue.imag()), 0.27, kAffineBlockTolerance);
  // Directions: dRe λ/dH is the slope of each block.
  EXPECT_NEAR(found.crossings[0].eigenvalue_height_derivative.real(), -0.05, kAffineBlockTolerance);
  EXPECT_NEAR(found.crossings[1].eigenvalue_height_derivative.real(), 0.02, kAffineBlockTolerance);
  EXPECT_NEAR(found.crossings[2].eigenvalue_height_derivative.real(), 0.01, kAffineBlockTolerance);
  EXPECT_TRUE(found.crossings[0].mode_stable_above);
  EXPECT_FALSE(found.crossings[1].mode_stable_above);
  // Stability: unstable below 3.10, stable in the window, unstable above 3.15.
  EXPECT_FALSE(found.crossings[0].stable_below);
  EXPECT_TRUE(found.crossings[0].stable_above);
  EXPECT_FALSE(found.crossings[1].stable_above);
  EXPECT_FALSE(found.stable_at_lower);
  EXPECT_FALSE(found.stable_at_upper);
}

TEST(CrossingSearch, SeparatesCrossingsAMillimetreApartAcrossARow) {
  // Two Hopf crossings 1 mm apart with a segment boundary between them.
  const AffineFamily family = MakeFamily(4.000, -0.5, 4.001, 0.5, -3.0, 0.01, 2);
  const CrossingSearchResult found = CrossingSearch(Segments(family, {0.0, 2.5, 4.0005, 10.0}), 1.0);
  EXPECT_TRUE(found.certified) << found.uncertified_reason;
  ASSERT_EQ(found.crossings.size(), 2u);
  EXPECT_NEAR(found.crossings[0].height_m, 4.000, kRootTolerance_m);
  EXPECT_NEAR(found.crossings[1].height_m, 4.001, kRootTolerance_m);
}

TEST(CrossingSearch, SaysSoWhenAPairIsBelowTheRounding) {
  // 1e-7 m apart, Δ₄ stays below the rounding of its terms between them: the pair cannot be
  // resolved in double precision, and the result must not claim a certificate.
  const AffineFamily family = MakeFamily(4.0, -0.1, 4.0000001, 0.1, -3.0, 0.01, 2);
  const CrossingSearchResult found = CrossingSearch(Segments(family, {0.0, 2.5, 4.00000005, 10.0}), 1.0);
  EXPECT_FALSE(found.certified);
  EXPECT_FALSE(found.uncertified_reason.empty());
}

TEST(CrossingSearch, RejectsRootsOfDelta4WhereTwoRealRootsAreOpposite) {
  // D(H) with real roots r(H) and −r(H) + small: λᵢ + λⱼ = 0 at some H but nothing crosses the axis.
  Matrix5d D0 = Matrix5d::Zero(), D1 = Matrix5d::Zero();
  D0(0, 0) = -2.0;
  D1(0, 0) = 0.2;  // −2 + 0.2H
  D0(1, 1) = -1.0;
  D1(1, 1) = -0.1;  // −1 − 0.1H: sum with the first is 0 at... both negative; use
  D0(1, 1) = 3.0;
  D1(1, 1) = -0.5;  // 3 − 0.5H > 0 on [0, 5): unstable, opposite at H = 10/3
  D0(2, 2) = D0(3, 3) = -0.5;
  D0(2, 3) = 1.0;
  D0(3, 2) = -1.0;
  D0(4, 4) = -0.7;
  const AffineFamily family{D0, D1};
  const CrossingSearchResult found = CrossingSearch(Segments(family, {0.0, 5.0}), 1.0);
  EXPECT_TRUE(found.crossings.empty());
  EXPECT_FALSE(found.stable_at_lower);
}

TEST(CrossingSearch, AWrongDegreeBoundIsCaught) {
  // A quadratic family declared affine: the Chebyshev tails and the faithfulness check reject it.
  const AffineFamily linear = MakeFamily(3.0, -0.05, -5.0, 0.02, -7.0, 0.01, 3);
  MatrixSegment s;
  s.lower_height_m = 0;
  s.upper_height_m = 10;
  s.coefficient_degrees = {0, 1, 2, 3, 4, 5};
  s.polynomial_matrix =
      s.exact_matrix = [&](double h) -> Matrix5d { return linear(h) + 0.01 * h * h * linear.A1; };
  const CrossingSearchResult found = CrossingSearch({s}, 1.0);
  EXPECT_FALSE(found.certified);
}

}  // namespace
}  // namespace gesweep
