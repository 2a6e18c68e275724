// MIL-F-8785C Category C ratings (engine/modal/flying_qualities.h, docs/model.md §11). The oracles are
// the limits themselves: state matrices built to have chosen eigenvalues, a damping ratio or a time to
// double just inside and just outside each limit, and the level each side of it read off the table
// of docs/model.md §11 (written out again here, not taken from the code's constants).
#include "engine/modal/flying_qualities.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/modal/boundary.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

using Complex = std::complex<double>;
using Level = FlyingQualitiesLevel;

// How far inside or outside a limit the test puts a damping ratio (or, relatively, a time to
// double): far above the error of ζ computed from the eigenvalues of a well-conditioned 5×5 (about
// 1e-14), far below the distance to any other limit.
constexpr double kEdge = 1e-6;
// The damping ratio and time to double the rating reports are those of the chosen eigenvalues to
// the accuracy of a 5×5 eigen-solve of these block matrices.
constexpr double kRatedValueTolerance = 1e-10;

// The table of docs/model.md §11, Category C.
constexpr double kSpL1Low = 0.35, kSpL1High = 1.30, kSpL2Low = 0.25, kSpL2High = 2.00, kSpL3Low = 0.15;
constexpr double kPhL1 = 0.04, kPhL2 = 0.0, kPhT2_s = 55.0;

// Natural frequencies of the test modes: well separated, as an airplane's (short period a few rad/s,
// phugoid a few tenths), and a slow subsidence root.
constexpr double kShortPeriodFrequency_radps = 3.5;
constexpr double kPhugoidFrequency_radps = 0.3;
constexpr double kHeightRoot_per_s = -0.005;

// The upper root of a mode of frequency wn and damping zeta: a pair (Im > 0) for |zeta| < 1, else
// the real root of larger real part; Roots() gives both.
std::array<Complex, 2> Roots(double zeta, double wn) {
  if (std::abs(zeta) < 1) {
    const Complex root{-zeta * wn, wn * std::sqrt(1 - zeta * zeta)};
    return {root, std::conj(root)};
  }
  const double s = std::sqrt(zeta * zeta - 1);
  return {Complex{wn * (-zeta + s), 0}, Complex{wn * (-zeta - s), 0}};
}

// A real 5×5 with exactly these eigenvalues: 2×2 blocks [[a, b], [−b, a]] for a pair a ± ib, diagonal
// entries for real roots, made dense by a fixed well-conditioned similarity so that the solver has
// real work to do.
Matrix5d WithEigenvalues(const std::array<Complex, 2>& sp, const std::array<Complex, 2>& ph, double height) {
  Matrix5d block = Matrix5d::Zero();
  auto put = [&](int i, const std::array<Complex, 2>& mode) {
    if (mode[0].imag() != 0) {
      block(i, i) = block(i + 1, i + 1) = mode[0].real();
      block(i, i + 1) = mode[0].imag();
      block(i + 1, i) = -mode[0].imag();
    } else {
      block(i, i) = mode[0].real();
      block(i + 1, i + 1) = mode[1].real();
    }
  };
  put(0, sp);
  put(2, ph);
  block(4, 4) = height;
  Matrix5d T = Matrix5d::Identity();
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j)
      if (i != j) T(i, j) = 0.1 * std::sin(1.0 + 3 * i + j);
  return T * block * T.inverse();
}

ModalAnalysis Modes(const std::array<Complex, 2>& sp, const std::array<Complex, 2>& ph,
                    double height = kHeightRoot_per_s) {
  return AnalyzeModes(WithEigenvalues(sp, ph, height));
}

const std::array<Complex, 2> kGoodShortPeriod = Roots(0.7, kShortPeriodFrequency_radps);
const std::array<Complex, 2> kGoodPhugoid = Roots(0.1, kPhugoidFrequency_radps);

Level ShortPeriodLevel(double zeta) {
  const ModalAnalysis modal = Modes(Roots(zeta, kShortPeriodFrequency_radps), kGoodPhugoid);
  EXPECT_EQ(modal.classification,
            std::abs(zeta) < 1 ? ModeClassification::kStandard : ModeClassification::kShortPeriodSplit)
      << zeta;
  const ModeRating rating = RateShortPeriod(modal);
  EXPECT_NEAR(rating.damping_ratio, zeta, kRatedValueTolerance) << zeta;
  return rating.level;
}

Level PhugoidLevel(double zeta) {
  const ModalAnalysis modal = Modes(kGoodShortPeriod, Roots(zeta, kPhugoidFrequency_radps));
  EXPECT_EQ(modal.classification,
            std::abs(zeta) < 1 ? ModeClassification::kStandard : ModeClassification::kPhugoidSplit)
      << zeta;
  const ModeRating rating = RatePhugoid(modal);
  EXPECT_NEAR(rating.damping_ratio, zeta, kRatedValueTolerance) << zeta;
  return rating.level;
}

TEST(FlyingQualities, ShortPeriodPairAtEachDampingLimit) {
  EXPECT_EQ(ShortPeriodLevel(kSpL1Low + kEdge), Level::kLevel1);
  EXPECT_EQ(ShortPeriodLevel(kSpL1Low - kEdge), Level::kLevel2);
  EXPECT_EQ(ShortPeriodLevel(0.7), Level::kLevel1);
  EXPECT_EQ(ShortPeriodLevel(kSpL2Low + kEdge), Level::kLevel2);
  EXPECT_EQ(ShortPeriodLevel(kSpL2Low - kEdge), Level::kLevel3);
  EXPECT_EQ(ShortPeriodLevel(kSpL3Low + kEdge), Level::kLevel3);
  EXPECT_EQ(ShortPeriodLevel(kSpL3Low - kEdge), Level::kWorseThanLevel3);
  EXPECT_EQ(ShortPeriodLevel(0.0 + kEdge), Level::kWorseThanLevel3);
  EXPECT_EQ(ShortPeriodLevel(-0.2), Level::kWorseThanLevel3);  // a divergent oscillation
}

TEST(FlyingQualities, SplitShortPeriodIsRatedOnItsSecondOrderDamping) {
  // Two stable real roots ωn(−ζ ± √(ζ² − 1)): ζ ≥ 1 recovered from λ1 + λ2 and λ1·λ2 (§11).
  EXPECT_EQ(ShortPeriodLevel(1.05), Level::kLevel1);
  EXPECT_EQ(ShortPeriodLevel(kSpL1High - kEdge), Level::kLevel1);
  EXPECT_EQ(ShortPeriodLevel(kSpL1High + kEdge), Level::kLevel2);
  EXPECT_EQ(ShortPeriodLevel(kSpL2High - kEdge), Level::kLevel2);
  EXPECT_EQ(ShortPeriodLevel(kSpL2High + kEdge), Level::kLevel3);
  EXPECT_EQ(ShortPeriodLevel(8.0), Level::kLevel3);  // Level 3 has no upper limit
}

TEST(FlyingQualities, SplitShortPeriodWithAnUnstableRootIsWorseThanLevel3) {
  // Roots +0.4 and −6 (of larger magnitude than the phugoid pair: the short period split).
  const ModalAnalysis modal = Modes({Complex{0.4, 0}, Complex{-6.0, 0}}, kGoodPhugoid);
  ASSERT_EQ(modal.classification, ModeClassification::kShortPeriodSplit);
  const ModeRating rating = RateShortPeriod(modal);
  EXPECT_EQ(rating.level, Level::kWorseThanLevel3);
  EXPECT_TRUE(std::isnan(rating.damping_ratio));  // roots of opposite signs: no second-order ζ
  EXPECT_NEAR(rating.time_to_double_s, std::numbers::ln2 / 0.4, kRatedValueTolerance);
}

TEST(FlyingQualities, PhugoidPairAtEachDampingLimit) {
  EXPECT_EQ(PhugoidLevel(0.2), Level::kLevel1);
  EXPECT_EQ(PhugoidLevel(kPhL1 + kEdge), Level::kLevel1);
  EXPECT_EQ(PhugoidLevel(kPhL1 - kEdge), Level::kLevel2);
  EXPECT_EQ(PhugoidLevel(kPhL2 + kEdge), Level::kLevel2);
  // Just unstable: Re λ = 1e-6·0.3 1/s doubles in 2.3e6 s, far above 55 s.
  EXPECT_EQ(PhugoidLevel(kPhL2 - kEdge), Level::kLevel3);
}

// A phugoid pair or real root with Re λ = ln 2/T2.
double RealPartFor(double time_to_double_s) { return std::numbers::ln2 / time_to_double_s; }

TEST(FlyingQualities, UnstablePhugoidIsLevel3WhileItDoublesInAtLeast55Seconds) {
  for (const double t2 : {kPhT2_s * (1 + kEdge), kPhT2_s * (1 - kEdge), 300.0, 12.0}) {
    const Complex root{RealPartFor(t2), kPhugoidFrequency_radps};
    const ModalAnalysis modal = Modes(kGoodShortPeriod, {root, std::conj(root)});
    ASSERT_EQ(modal.classification, ModeClassification::kStandard);
    const ModeRating rating = RatePhugoid(modal);
    EXPECT_EQ(rating.level, t2 >= kPhT2_s ? Level::kLevel3 : Level::kWorseThanLevel3) << t2;
    EXPECT_NEAR(rating.time_to_double_s, t2, kRatedValueTolerance * t2) << t2;
    EXPECT_LT(rating.damping_ratio, 0.0);
  }
}

TEST(FlyingQualities, SplitPhugoid) {
  // Both roots stable: a second-order system with ζ ≥ 1, Level 1.
  const ModalAnalysis stable = Modes(kGoodShortPeriod, {Complex{-0.2, 0}, Complex{-0.3, 0}});
  ASSERT_EQ(stable.classification, ModeClassification::kPhugoidSplit);
  const ModeRating stable_rating = RatePhugoid(stable);
  EXPECT_EQ(stable_rating.level, Level::kLevel1);
  EXPECT_NEAR(stable_rating.damping_ratio, 0.5 / (2 * std::sqrt(0.06)), kRatedValueTolerance);
  EXPECT_EQ(stable_rating.time_to_double_s, std::numeric_limits<double>::infinity());
  // One root unstable: an aperiodic divergence, Level 3 by its T2 when ≥ 55 s.
  for (const double t2 : {kPhT2_s * (1 + kEdge), kPhT2_s * (1 - kEdge)}) {
    const ModalAnalysis modal = Modes(kGoodShortPeriod, {Complex{RealPartFor(t2), 0}, Complex{-0.3, 0}});
    ASSERT_EQ(modal.classification, ModeClassification::kPhugoidSplit);
    const ModeRating rating = RatePhugoid(modal);
    EXPECT_EQ(rating.level, t2 >= kPhT2_s ? Level::kLevel3 : Level::kWorseThanLevel3) << t2;
    EXPECT_NEAR(rating.time_to_double_s, t2, kRatedValueTolerance * t2) << t2;
    EXPECT_TRUE(std::isnan(rating.damping_ratio));
  }
}

TEST(FlyingQualities, LimitsAreInclusive) {
  // Exactly at a limit the mode meets it (docs/model.md §11: "0.35 ≤ ζ_sp ≤ 1.30"). A computed
  // eigenvalue never lands exactly on a limit, so the mode's properties are set by hand.
  auto short_period = [](double zeta) {
    ModalAnalysis modal;
    modal.short_period.eigenvalue = {-zeta, std::sqrt(std::abs(1 - zeta * zeta))};
    modal.short_period.damping_ratio = zeta;
    modal.short_period.oscillatory = true;
    return RateShortPeriod(modal).level;
  };
  EXPECT_EQ(short_period(kSpL1Low), Level::kLevel1);
  EXPECT_EQ(short_period(kSpL1High), Level::kLevel1);
  EXPECT_EQ(short_period(kSpL2Low), Level::kLevel2);
  EXPECT_EQ(short_period(kSpL2High), Level::kLevel2);
  EXPECT_EQ(short_period(kSpL3Low), Level::kLevel3);
  auto phugoid = [](double zeta) {
    ModalAnalysis modal;
    modal.phugoid.eigenvalue = {-zeta, std::sqrt(1 - zeta * zeta)};
    modal.phugoid.damping_ratio = zeta;
    modal.phugoid.oscillatory = true;
    return RatePhugoid(modal).level;
  };
  EXPECT_EQ(phugoid(kPhL1), Level::kLevel1);
  EXPECT_EQ(phugoid(kPhL2), Level::kLevel2);  // Re λ = 0: neutral, not divergent
}

TEST(FlyingQualities, TheAirplaneTakesTheWorseOfItsTwoModes) {
  const FlyingQualities a =
      RateFlyingQualities(Modes(kGoodShortPeriod, Roots(0.02, kPhugoidFrequency_radps)));
  EXPECT_EQ(a.short_period.level, Level::kLevel1);
  EXPECT_EQ(a.phugoid.level, Level::kLevel2);
  EXPECT_EQ(a.worst, Level::kLevel2);
  const FlyingQualities b = RateFlyingQualities(Modes(Roots(0.2, kShortPeriodFrequency_radps), kGoodPhugoid));
  EXPECT_EQ(b.short_period.level, Level::kLevel3);
  EXPECT_EQ(b.phugoid.level, Level::kLevel1);
  EXPECT_EQ(b.worst, Level::kLevel3);
  EXPECT_EQ(Worst(Level::kWorseThanLevel3, Level::kLevel1), Level::kWorseThanLevel3);
  EXPECT_EQ(ToString(Level::kWorseThanLevel3), "worse than level 3");
}

TEST(FlyingQualities, TheHeightModeIsNotRated) {
  // A divergent height (subsidence) root changes neither mode's level (it has no requirement, §11).
  const FlyingQualities rated = RateFlyingQualities(Modes(kGoodShortPeriod, kGoodPhugoid, +0.05));
  EXPECT_EQ(rated.short_period.level, Level::kLevel1);
  EXPECT_EQ(rated.phugoid.level, Level::kLevel1);
  EXPECT_EQ(rated.worst, Level::kLevel1);
}

// ---- The ANCE (studies/aircraft/ance.toml) --------------------------------------------------------

// Coefficients c1..cn of det(sI − M) = sⁿ + c1 sⁿ⁻¹ + ... + cn by Faddeev–LeVerrier: traces of matrix
// products only, no eigen-solver.
template <int N>
std::array<double, N + 1> CharacteristicPolynomial(const Eigen::Matrix<double, N, N>& M) {
  using Matrix = Eigen::Matrix<double, N, N>;
  std::array<double, N + 1> c{};
  c[0] = 1;
  Matrix Mk = Matrix::Zero();
  for (int k = 1; k <= N; ++k) {
    Mk = M * Mk + c[k - 1] * Matrix::Identity();
    c[k] = -(M * Mk).trace() / k;
  }
  return c;
}

// The number of roots of p (highest power first) with Re s > 0: sign changes down the first column
// of the Routh array (no zero appears in it for the matrices used here; the test says so if one does).
template <std::size_t K>
int RootsInRightHalfPlane(const std::array<double, K>& p) {
  std::vector<std::vector<double>> rows(K);
  for (std::size_t i = 0; i < K; ++i) rows[i % 2].push_back(p[i]);
  rows[1].resize(rows[0].size(), 0.0);
  for (std::size_t r = 2; r < K; ++r) {
    const auto& a = rows[r - 2];
    const auto& b = rows[r - 1];
    EXPECT_NE(b[0], 0.0) << "a zero in the Routh array's first column";
    rows[r].assign(a.size(), 0.0);
    for (std::size_t j = 0; j + 1 < a.size(); ++j) rows[r][j] = (b[0] * a[j + 1] - a[0] * b[j + 1]) / b[0];
  }
  int changes = 0;
  for (std::size_t r = 1; r < K; ++r) changes += (rows[r][0] > 0) != (rows[r - 1][0] > 0);
  return changes;
}

// The expected level of a pair of damping ratio ζ (|ζ| < 1) by the table of docs/model.md §11.
Level ExpectedShortPeriodLevel(double zeta) {
  if (zeta >= kSpL1Low && zeta <= kSpL1High) return Level::kLevel1;
  if (zeta >= kSpL2Low && zeta <= kSpL2High) return Level::kLevel2;
  return zeta >= kSpL3Low ? Level::kLevel3 : Level::kWorseThanLevel3;
}
Level ExpectedStablePhugoidLevel(double zeta) { return zeta >= kPhL1 ? Level::kLevel1 : Level::kLevel2; }

// The classical approximate factorisation of a quartic with well-separated modes (Etkin & Reid):
// s⁴ + B s³ + C s² + D s + E ≈ (s² + B s + C)(s² + (DC − BE)/C² s + E/C). Its error is of the order
// of (ωp/ωsp)², 0.5 % for the ANCE in free flight; this allows ten times that.
constexpr double kFactorisationAccuracy = 0.05;

class AnceFlyingQualities : public ::testing::Test {
 protected:
  LongitudinalModel model_{LoadAircraftFile(testing::AnceAircraftPath()), ModelOptions{}};
};

TEST_F(AnceFlyingQualities, FreeFlightLevelsFromTheApproximateFactorisation) {
  // In free flight the height state does not feed back (no h-derivatives above the last table row):
  // the upper-left 4×4 block of A holds the short period and the phugoid.
  const double inf = std::numeric_limits<double>::infinity();
  for (const double u0 : {32.0208, 52.21}) {
    const Matrix5d A = model_.StateMatrix(inf, u0);
    const Eigen::Matrix4d block = A.topLeftCorner<4, 4>();
    const auto c = CharacteristicPolynomial<4>(block);
    const double B = c[1], C = c[2], D = c[3], E = c[4];
    const double zeta_sp = B / (2 * std::sqrt(C));
    const double wn_p = std::sqrt(E / C);
    const double zeta_p = (D * C - B * E) / (C * C) / (2 * wn_p);
    // The approximations decide the level only when no limit lies within their accuracy.
    for (const double f : {1 - kFactorisationAccuracy, 1 + kFactorisationAccuracy}) {
      ASSERT_EQ(ExpectedShortPeriodLevel(zeta_sp * f), ExpectedShortPeriodLevel(zeta_sp)) << u0;
      ASSERT_GT(zeta_p * f, 0.0) << u0;
      ASSERT_EQ(ExpectedStablePhugoidLevel(zeta_p * f), ExpectedStablePhugoidLevel(zeta_p)) << u0;
    }
    const FlyingQualities rated = RateFlyingQualities(AnalyzeModes(A));
    EXPECT_EQ(rated.short_period.level, ExpectedShortPeriodLevel(zeta_sp)) << u0;
    EXPECT_EQ(rated.phugoid.level, ExpectedStablePhugoidLevel(zeta_p)) << u0;
    EXPECT_NEAR(rated.short_period.damping_ratio, zeta_sp, kFactorisationAccuracy * zeta_sp) << u0;
    EXPECT_NEAR(rated.phugoid.damping_ratio, zeta_p, kFactorisationAccuracy * zeta_p) << u0;
    EXPECT_EQ(rated.worst, Worst(rated.short_period.level, rated.phugoid.level));
  }
}

// Heights this far from the boundary H* lie on its side: far above the finder's bracket (1e-4 m by
// default, refined to rounding) and far below the distance to any other crossing.
constexpr double kBesideBoundary_m = 1e-3;

TEST_F(AnceFlyingQualities, ThePhugoidLosesLevel2AtTheBoundaryAndLevel3WhereItDoublesIn55Seconds) {
  constexpr double u0 = 32.0208;
  // The boundary by the Hurwitz criterion (engine/modal/boundary.cc), not by eigenvalues: the
  // phugoid pair crosses the imaginary axis at H*, stable above. Just above, 0 < ζ_p ≪ 0.04: Level 2;
  // just below, ζ_p < 0 and T2 → ∞ > 55 s: Level 3.
  const BoundaryResult boundary = FindBoundary(model_, u0);
  ASSERT_TRUE(boundary.height_m.has_value());
  const double h_star = *boundary.height_m;
  ASSERT_FALSE(boundary.crossings.empty());
  EXPECT_EQ(boundary.crossings.front().mode, "phugoid");
  EXPECT_EQ(boundary.crossings.front().kind, CrossingKind::kHopf);
  const FlyingQualities above =
      RateFlyingQualities(AnalyzeModes(model_.StateMatrix(h_star + kBesideBoundary_m, u0)));
  const FlyingQualities below =
      RateFlyingQualities(AnalyzeModes(model_.StateMatrix(h_star - kBesideBoundary_m, u0)));
  EXPECT_EQ(above.phugoid.level, Level::kLevel2);
  EXPECT_EQ(below.phugoid.level, Level::kLevel3);
  // Where the phugoid doubles in 55 s: the roots of A with Re λ > α = ln 2/55 are the roots of
  // det(sI − (A − αI)) in the right half plane, counted by Routh. A pair there (two roots) near the
  // wheels and none just below H*: worse than Level 3, and Level 3.
  const double alpha = std::numbers::ln2 / kPhT2_s;
  const Matrix5d shift = alpha * Matrix5d::Identity();
  const double wheels_m = 0.8;
  EXPECT_EQ(RootsInRightHalfPlane(CharacteristicPolynomial<5>(
                Matrix5d(model_.StateMatrix(h_star - kBesideBoundary_m, u0) - shift))),
            0);
  ASSERT_EQ(
      RootsInRightHalfPlane(CharacteristicPolynomial<5>(Matrix5d(model_.StateMatrix(wheels_m, u0) - shift))),
      2);
  const FlyingQualities near_wheels = RateFlyingQualities(AnalyzeModes(model_.StateMatrix(wheels_m, u0)));
  EXPECT_EQ(near_wheels.phugoid.level, Level::kWorseThanLevel3);
  EXPECT_LT(near_wheels.phugoid.time_to_double_s, kPhT2_s);
  EXPECT_EQ(near_wheels.worst, Level::kWorseThanLevel3);
}

}  // namespace
}  // namespace gesweep
