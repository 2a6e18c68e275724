#include "engine/modal/modal_analysis.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "engine/aircraft/atmosphere.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

// Tolerances: each says where it comes from.
/// Period 2π/ω of a ~25 s phugoid from roots good to kRootTolerance: T·Δω/ω ≈ 1e-7 s, with margin.
constexpr double kPeriodTolerance_s = 1e-6;
/// ln2/|σ| with σ = 0.004 amplifies the roots' 1e-9 error by ln2/σ² ≈ 4e4: 4e-5 s, with margin.
constexpr double kTimeToDoubleTolerance_s = 1e-4;

using Complex = std::complex<double>;

// Eigenvalues of a companion matrix of a well-conditioned quintic are accurate to ~1e-12·|λ|max.
constexpr double kRootTolerance = 1e-9;

// The companion matrix of ∏(s − r_i): its eigenvalues are exactly the roots (the oracle).
Matrix5d Companion(const std::vector<Complex>& roots) {
  std::vector<Complex> poly{1.0};  // coefficients, highest power first
  for (const Complex& r : roots) {
    std::vector<Complex> next(poly.size() + 1, 0.0);
    for (std::size_t i = 0; i < poly.size(); ++i) {
      next[i] += poly[i];
      next[i + 1] -= r * poly[i];
    }
    poly = next;
  }
  Matrix5d A = Matrix5d::Zero();
  for (int j = 0; j < 5; ++j) A(0, j) = -poly[j + 1].real();
  for (int i = 1; i < 5; ++i) A(i, i - 1) = 1.0;
  return A;
}

void ExpectRoot(Complex actual, Complex expected) {
  EXPECT_NEAR(actual.real(), expected.real(), kRootTolerance) << actual << " vs " << expected;
  EXPECT_NEAR(actual.imag(), expected.imag(), kRootTolerance) << actual << " vs " << expected;
}

TEST(AnalyzeModes, ReproducesCompanionMatrixRootsAndIdentifiesModes) {
  const Complex sp{-1.3, 3.2}, ph{-0.004, 0.25};
  const double height = -0.01;
  const ModalAnalysis modal = AnalyzeModes(Companion({sp, std::conj(sp), ph, std::conj(ph), height}));
  EXPECT_EQ(modal.classification, ModeClassification::kStandard);
  ExpectRoot(modal.eigenvalues[0], sp);
  ExpectRoot(modal.eigenvalues[1], std::conj(sp));
  ExpectRoot(modal.eigenvalues[2], ph);
  ExpectRoot(modal.eigenvalues[3], std::conj(ph));
  ExpectRoot(modal.eigenvalues[4], height);
  // Mode properties from their definitions (docs/model.md §6).
  EXPECT_NEAR(modal.short_period.natural_frequency_radps, std::abs(sp), kRootTolerance);
  EXPECT_NEAR(modal.short_period.damping_ratio, 1.3 / std::abs(sp), kRootTolerance);
  EXPECT_NEAR(modal.phugoid.period_s, 2 * M_PI / 0.25, kPeriodTolerance_s);
  EXPECT_NEAR(modal.phugoid.time_to_half_or_double_s, std::log(2.0) / 0.004, kTimeToDoubleTolerance_s);
  EXPECT_NEAR(modal.stability_margin_per_s, -0.004, kRootTolerance);
  EXPECT_TRUE(modal.stable);
}

TEST(AnalyzeModes, UnstablePhugoidSetsTheMargin) {
  const ModalAnalysis modal =
      AnalyzeModes(Companion({{-1.3, 3.2}, {-1.3, -3.2}, {0.03, 0.6}, {0.03, -0.6}, -0.009}));
  EXPECT_NEAR(modal.stability_margin_per_s, 0.03, kRootTolerance);
  EXPECT_FALSE(modal.stable);
  EXPECT_LT(modal.phugoid.damping_ratio, 0.0);
}

TEST(AnalyzeModes, SplitPairsAreClassifiedAndSaidSo) {
  // Phugoid split into two real roots: the remaining pair is the larger, so it is the short period.
  const ModalAnalysis phugoid_split = AnalyzeModes(Companion({{-1.3, 3.2}, {-1.3, -3.2}, -0.3, -0.2, -0.01}));
  EXPECT_EQ(phugoid_split.classification, ModeClassification::kPhugoidSplit);
  ExpectRoot(phugoid_split.eigenvalues[0], {-1.3, 3.2});
  ExpectRoot(phugoid_split.eigenvalues[2], -0.2);
  ExpectRoot(phugoid_split.eigenvalues[3], -0.3);
  ExpectRoot(phugoid_split.eigenvalues[4], -0.01);
  // Short period split: the remaining pair is smaller than the largest real root.
  const ModalAnalysis sp_split = AnalyzeModes(Companion({-4.0, -2.5, {-0.01, 0.25}, {-0.01, -0.25}, -0.02}));
  EXPECT_EQ(sp_split.classification, ModeClassification::kShortPeriodSplit);
  ExpectRoot(sp_split.eigenvalues[0], -2.5);
  ExpectRoot(sp_split.eigenvalues[2], {-0.01, 0.25});
  const ModalAnalysis all_real = AnalyzeModes(Companion({-4.0, -2.5, -0.5, -0.3, -0.02}));
  EXPECT_EQ(all_real.classification, ModeClassification::kAllReal);
  ExpectRoot(all_real.eigenvalues[4], -0.02);
}

TEST(AnalyzeModes, NonFiniteMatrixIsReportedNotCrashed) {
  Matrix5d A = Matrix5d::Identity();
  A(2, 3) = std::nan("");
  const ModalAnalysis modal = AnalyzeModes(A);
  EXPECT_FALSE(modal.finite);
  EXPECT_FALSE(modal.stable);
}

class AnceModes : public ::testing::Test {
 protected:
  Aircraft ance_ = LoadAircraftFile(testing::AnceAircraftPath());
};

TEST_F(AnceModes, WithoutHDerivativesTheHeightRootIsExactlyNeutral) {
  ModelOptions off;
  off.h_derivatives = false;
  const LongitudinalModel model(ance_, off);
  for (double h : {0.788, 1.3, 2.5935, 7.0, 13.373, std::numeric_limits<double>::infinity()}) {
    const ModalAnalysis modal = AnalyzeModes(model.StateMatrix(h, 32.0208));
    EXPECT_LE(std::abs(modal.height.eigenvalue), kNeutralEigenvalueTolerance_per_s) << "H=" << h;
    EXPECT_TRUE(modal.height.neutral);
    EXPECT_LT(modal.stability_margin_per_s, 0.0) << "neutral root must not count as instability, H=" << h;
  }
}

TEST_F(AnceModes, FreeFlightPhugoidAgreesWithLanchester) {
  // Lanchester's phugoid ωn = √2·g/u0 assumes lift = weight. At α = 0 that holds at the speed where
  // CLo·½ρ0u²·S = m·g. Lanchester neglects drag and pitch stiffness coupling; for a light airplane it
  // is good to some 5–10 %.
  constexpr double kLanchesterAccuracy = 0.08;
  const LongitudinalModel model(ance_, ModelOptions{});
  const double CLo = ance_.free_flight[Index(Coefficient::CLo)];
  const double trim_speed =
      std::sqrt(2.0 * ance_.mass_kg * kGravity_mps2 / (kSeaLevelDensity_kgpm3 * ance_.wing_area_m2 * CLo));
  const double inf = std::numeric_limits<double>::infinity();
  const ModalAnalysis modal = AnalyzeModes(model.StateMatrix(inf, trim_speed));
  const double lanchester = std::sqrt(2.0) * kGravity_mps2 / trim_speed;
  EXPECT_NEAR(modal.phugoid.natural_frequency_radps, lanchester, kLanchesterAccuracy * lanchester);
  EXPECT_GT(modal.phugoid.damping_ratio, 0.0);
  EXPECT_LT(modal.phugoid.damping_ratio, 0.1);  // lightly damped, as phugoids are
}

TEST_F(AnceModes, FreeFlightShortPeriodAgreesWithTheClassicalApproximation) {
  // Short-period approximation (Etkin; constant speed): ωn² = Zw·Mq − u0·Mw and
  // 2ζωn = −(Zw + Mq + u0·Mẇ). Good to a few per cent when the modes are well separated.
  constexpr double kApproximationAccuracy = 0.05;
  const LongitudinalModel model(ance_, ModelOptions{});
  const double inf = std::numeric_limits<double>::infinity();
  for (double u0 : {32.0208, 52.21}) {
    const DimensionalDerivatives d = model.DerivativesAt(inf, u0);
    const double wn = std::sqrt(d.Zw * d.Mq - u0 * d.Mw);
    const double zeta = -(d.Zw + d.Mq + u0 * d.Mw_dot) / (2.0 * wn);
    const ModalAnalysis modal = AnalyzeModes(model.StateMatrix(inf, u0));
    EXPECT_NEAR(modal.short_period.natural_frequency_radps, wn, kApproximationAccuracy * wn) << u0;
    EXPECT_NEAR(modal.short_period.damping_ratio, zeta, kApproximationAccuracy * zeta) << u0;
  }
}

TEST(Eigenvalues5, LapackAgreesWithEigenSolverOnModelAndRandomMatrices) {
  // 1e5 matrices: the ANCE's A over heights and speeds under random ±50 % coefficient scales, and
  // random matrices with a known, well-conditioned spectrum. Both solvers are backward stable; on
  // these matrices they agree to 1e-12 of max(1, |λ|), and the classification is the same.
  constexpr double kAgreement = 1e-12;
  const Aircraft ance = LoadAircraftFile(testing::AnceAircraftPath());
  std::mt19937_64 random(16);
  std::uniform_real_distribution<double> factor(0.5, 1.5), height(0.79, 14.0), speed(24.0, 60.0);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0;
  int matrices = 0;
  auto compare = [&](const Matrix5d& A) {
    const auto a = Eigenvalues5(A, EigenvalueSolver::kEigen);
    const auto b = Eigenvalues5(A, EigenvalueSolver::kLapack);
    for (const auto& x : a) {
      double nearest = INFINITY;
      for (const auto& y : b) nearest = std::min(nearest, std::abs(x - y));
      worst = std::max(worst, nearest / std::max(1.0, std::abs(x)));
    }
    EXPECT_EQ(AnalyzeModes(A, EigenvalueSolver::kEigen).classification,
              AnalyzeModes(A, EigenvalueSolver::kLapack).classification);
    ++matrices;
  };
  for (int n = 0; n < 200; ++n) {
    ModelOptions options;
    for (int c = 0; c < kCoefficientCount; ++c)
      options.coefficient_scale[static_cast<std::size_t>(c)] = factor(random);
    const LongitudinalModel model(ance, options);
    for (int i = 0; i < 250; ++i) compare(model.StateMatrix(height(random), speed(random)));
  }
  for (int n = 0; n < 50000; ++n) {
    Matrix5d D = Matrix5d::Zero();
    D(0, 0) = D(1, 1) = 2 * u(random);
    D(0, 1) = 1 + 3 * std::abs(u(random));
    D(1, 0) = -D(0, 1);
    D(2, 2) = D(3, 3) = u(random);
    D(2, 3) = 0.1 + std::abs(u(random));
    D(3, 2) = -D(2, 3);
    D(4, 4) = 0.01 * u(random);
    Matrix5d S = Matrix5d::Identity();
    for (int i = 0; i < 25; ++i) S.data()[i] += 0.3 * u(random);
    compare(S * D * S.inverse());
  }
  EXPECT_EQ(matrices, 100000);
  EXPECT_LT(worst, kAgreement);
}

}  // namespace
}  // namespace gesweep
