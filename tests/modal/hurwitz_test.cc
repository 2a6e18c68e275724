#include "engine/modal/hurwitz.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

namespace gesweep {
namespace {

// Tolerances: each says where it comes from.
/// FromRoots multiplies five factors: a coefficient's rounding grows with their count and sizes.
constexpr double kFromRootsMargin = 20;
/// Two algorithms for the characteristic coefficients agree to ~1e-13 of ‖A‖^k (Faddeev–LeVerrier loses a
/// digit or two).
constexpr double kCharacteristicRelative = 1e-13;
/// The expanded path for Eq. (1) and the Hessenberg reduction agree to a few ulps of ‖A‖^k.
constexpr double kReducedRelative = 1e-14;
/// Δ₄ is a sum of products of four coefficients: its rounding, relative to the scale of the root products.
constexpr double kDelta4Relative = 1e-11;
/// A coefficient that is exactly 0 (a root at the origin): rounding of O(1) products.
constexpr double kLeadingZeroTolerance = 1e-15;
/// Hurwitz determinants and frequencies of O(1) coefficients: rounding, with margin.
constexpr double kHurwitzRoundingTolerance = 1e-12;
/// Δ₄ of O(1–10) coefficients is a longer sum: a decade above kHurwitzRoundingTolerance.
constexpr double kDelta4RoundingTolerance = 1e-11;

// Coefficients of a monic polynomial from its roots, by expanding Π (s − rᵢ) in complex arithmetic.
CharacteristicCoefficients FromRoots(const std::array<std::complex<double>, 5>& roots) {
  std::array<std::complex<double>, 6> c{};
  c[0] = 1.0;
  for (int i = 0; i < 5; ++i) {
    for (int k = i + 1; k >= 1; --k)
      c[static_cast<std::size_t>(k)] -=
          roots[static_cast<std::size_t>(i)] * c[static_cast<std::size_t>(k - 1)];
  }
  CharacteristicCoefficients a;
  for (int k = 0; k < 6; ++k) a[static_cast<std::size_t>(k)] = c[static_cast<std::size_t>(k)].real();
  return a;
}

// A real matrix with the given (conjugate-closed) spectrum: a real block-diagonal form under a
// random, well-conditioned similarity.
Matrix5d WithSpectrum(double re1, double im1, double re2, double im2, double real, std::mt19937_64& random) {
  Matrix5d D = Matrix5d::Zero();
  D(0, 0) = D(1, 1) = re1;
  D(0, 1) = im1;
  D(1, 0) = -im1;
  D(2, 2) = D(3, 3) = re2;
  D(2, 3) = im2;
  D(3, 2) = -im2;
  D(4, 4) = real;
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  Matrix5d S = Matrix5d::Identity();
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) S(i, j) += u(random);
  return S * D * S.inverse();
}

// Rounding of the characteristic coefficients of a matrix with entries and roots of order 1-10:
// about 1e-15 of the largest term; the inverse of the similarity costs up to two more digits.
constexpr double kCoefficientTolerance = 1e-11;

TEST(CharacteristicPolynomial, ReproducesTheCoefficientsOfAKnownSpectrum) {
  std::mt19937_64 random(3);
  const Matrix5d A = WithSpectrum(-1.3, 3.2, 0.01, 0.27, -0.005, random);
  const CharacteristicCoefficients expected =
      FromRoots({{{-1.3, 3.2}, {-1.3, -3.2}, {0.01, 0.27}, {0.01, -0.27}, {-0.005, 0}}});
  const CharacteristicCoefficients a = CharacteristicPolynomial(A);
  for (int k = 0; k < 6; ++k)
    EXPECT_NEAR(a[static_cast<std::size_t>(k)], expected[static_cast<std::size_t>(k)],
                kCoefficientTolerance * kFromRootsMargin)
        << k;
}

TEST(CharacteristicPolynomial, AgreesWithFaddeevLeVerrierOnRandomMatrices) {
  std::mt19937_64 random(5);
  std::normal_distribution<double> n(0.0, 3.0);
  for (int trial = 0; trial < 200; ++trial) {
    Matrix5d A;
    for (int i = 0; i < 25; ++i) A.data()[i] = n(random);
    const CharacteristicCoefficients a = CharacteristicPolynomial(A);
    const auto b = FaddeevLeVerrier<double>(A);
    for (int k = 1; k < 6; ++k) {
      const double scale = std::pow(A.norm(), k) * 10;
      EXPECT_NEAR(a[static_cast<std::size_t>(k)], b[static_cast<std::size_t>(k)],
                  kCharacteristicRelative * scale)
          << trial << " " << k;
    }
  }
}

TEST(CharacteristicPolynomial, TheExpansionForEquation1AgreesWithTheReduction) {
  // Random matrices with the sparsity of Eq. (1) take the expanded path; the Hessenberg path and
  // Faddeev-LeVerrier are the oracles.
  std::mt19937_64 random(9);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 500; ++trial) {
    Matrix5d A = Matrix5d::Zero();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 5; ++j) A(i, j) = n(random);
    A(0, 2) = A(1, 3) = A(2, 3) = 0.0;
    A(0, 3) = -9.80665;
    A(1, 2) = 30 + n(random);
    A(3, 2) = 1.0;
    A(4, 1) = -1.0;
    A(4, 3) = A(1, 2);
    const CharacteristicCoefficients fast = CharacteristicPolynomial(A);
    const CharacteristicCoefficients reduced = HessenbergCharacteristicPolynomial(A);
    const auto flv = FaddeevLeVerrier<double>(A);
    for (int k = 1; k < 6; ++k) {
      const double scale = std::pow(A.norm(), k) * 10;
      EXPECT_NEAR(fast[static_cast<std::size_t>(k)], reduced[static_cast<std::size_t>(k)],
                  kReducedRelative * scale)
          << k;
      EXPECT_NEAR(fast[static_cast<std::size_t>(k)], flv[static_cast<std::size_t>(k)],
                  kCharacteristicRelative * scale)
          << k;
    }
  }
}

TEST(HurwitzDelta4, IsOrlandosProductOfRootSums) {
  // Orlando (1911): Δ_{n−1} = Π_{i<j} (λᵢ + λⱼ) for a monic polynomial of degree 5; the oracle takes
  // the eigenvalues from Eigen's EigenSolver.
  std::mt19937_64 random(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    Matrix5d A;
    for (int i = 0; i < 25; ++i) A.data()[i] = n(random);
    const Eigen::Matrix<std::complex<double>, 5, 1> lambda =
        Eigen::EigenSolver<Matrix5d>(A, false).eigenvalues();
    std::complex<double> product = 1.0;
    double scale = 1.0;
    for (int i = 0; i < 5; ++i)
      for (int j = i + 1; j < 5; ++j) {
        product *= lambda[i] + lambda[j];
        scale *= std::abs(lambda[i]) + std::abs(lambda[j]);
      }
    const double delta4 = HurwitzDelta4(CharacteristicPolynomial(A));
    EXPECT_NEAR(delta4, product.real(), kDelta4Relative * scale) << trial;
  }
}

TEST(HurwitzDelta3, VanishesWithAPairOnTheAxisOfTheQuartic) {
  // s·(s² + ω²)(s² + 2s + 5): the quartic factor has ±iω, so its Δ₃ = 0 and ω² = a₃/a₁.
  const double omega = 0.7;
  const CharacteristicCoefficients a = FromRoots({{{0, omega}, {0, -omega}, {-1, 2}, {-1, -2}, {0, 0}}});
  EXPECT_NEAR(a[5], 0.0, kLeadingZeroTolerance);
  EXPECT_NEAR(HurwitzDelta3(a), 0.0, kHurwitzRoundingTolerance);
  EXPECT_NEAR(DeflatedHopfFrequencySquared(a), omega * omega, kHurwitzRoundingTolerance);
}

TEST(HopfFrequencySquared, TellsAnAxisPairFromAnOppositeRealPair) {
  const CharacteristicCoefficients hopf = FromRoots({{{0, 0.4}, {0, -0.4}, {-1, 3}, {-1, -3}, {-0.2, 0}}});
  EXPECT_NEAR(HurwitzDelta4(hopf), 0.0, kDelta4RoundingTolerance);
  EXPECT_NEAR(HopfFrequencySquared(hopf), 0.16, kHurwitzRoundingTolerance);
  const CharacteristicCoefficients opposite =
      FromRoots({{{0.5, 0}, {-0.5, 0}, {-1, 3}, {-1, -3}, {-0.2, 0}}});
  EXPECT_NEAR(HurwitzDelta4(opposite), 0.0, kDelta4RoundingTolerance);
  EXPECT_NEAR(HopfFrequencySquared(opposite), -0.25, kHurwitzRoundingTolerance);
}

TEST(HurwitzStable, MatchesTheEigenvaluesOnRandomMatrices) {
  std::mt19937_64 random(11);
  std::normal_distribution<double> n(0.0, 1.0);
  int stable = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Matrix5d A;
    for (int i = 0; i < 25; ++i) A.data()[i] = n(random);
    A -= 1.2 * Matrix5d::Identity();  // about half of them stable
    const auto lambda = Eigen::EigenSolver<Matrix5d>(A, false).eigenvalues();
    bool all_left = true;
    for (int i = 0; i < 5; ++i) all_left &= lambda[i].real() < 0;
    EXPECT_EQ(HurwitzStable(CharacteristicPolynomial(A)), all_left) << trial;
    stable += all_left;
  }
  EXPECT_GT(stable, 200);
  EXPECT_LT(stable, 1800);
}

}  // namespace
}  // namespace gesweep
