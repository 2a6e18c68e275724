#pragma once
/// The characteristic polynomial of a 5×5 state matrix and the Hurwitz determinants that say where an
/// eigenvalue can cross the imaginary axis (docs/model.md, "The boundary by the Hurwitz criterion").
///
/// For p(s) = det(sI − A) = s⁵ + a₁s⁴ + a₂s³ + a₃s² + a₄s + a₅ with roots λᵢ, Orlando's formula gives
/// the fourth Hurwitz determinant Δ₄ = Π_{i<j} (λᵢ + λⱼ): it vanishes where a complex pair sits on the
/// imaginary axis (a Hopf crossing), and also where two real roots are opposite (±r, no crossing).
/// a₅ = det(−A) vanishes where a real root passes through 0.

#include <array>
#include <complex>

#include "engine/dynamics/longitudinal_model.h"

namespace gesweep {

/// Coefficients a₀ = 1, a₁, …, a₅ of det(sI − A) (index k: the coefficient of s^{5−k}).
using CharacteristicCoefficients = std::array<double, 6>;

/// det(sI − A). For a matrix with the sparsity of Eq. (1) (rows Δθ and ΔH kinematic, zeros at
/// (Δu, q), (Δw, Δθ), (q, Δθ)) by its expansion, about 60 flops; otherwise by
/// HessenbergCharacteristicPolynomial. A must be finite.
CharacteristicCoefficients CharacteristicPolynomial(const Matrix5d& A);

/// det(sI − A) of any A by an orthogonal (Householder) reduction to upper Hessenberg form and the
/// Hessenberg recurrence for the leading minors (Wilkinson, The Algebraic Eigenvalue Problem, §7.11):
/// backward stable in the reduction, about 300 flops.
CharacteristicCoefficients HessenbergCharacteristicPolynomial(const Matrix5d& A);

/// det(sI − A) by the Faddeev–LeVerrier recurrence, in any scalar type: with std::complex<double> and
/// A + i·h·dA it gives the directional derivative of every coefficient exactly (complex step), which
/// the implicit-function sensitivities use. Less accurate than CharacteristicPolynomial for the values.
template <typename Scalar>
std::array<Scalar, 6> FaddeevLeVerrier(const Eigen::Matrix<Scalar, 5, 5>& A) {
  using Matrix = Eigen::Matrix<Scalar, 5, 5>;
  std::array<Scalar, 6> a{};
  a[0] = Scalar(1);
  Matrix M = Matrix::Zero();
  for (int k = 1; k <= 5; ++k) {
    M = A * M + a[static_cast<std::size_t>(k - 1)] * Matrix::Identity();
    a[static_cast<std::size_t>(k)] = -(A * M).trace() / Scalar(k);
  }
  return a;
}

/// Δ₄ of the quintic: (a₁a₂ − a₃)(a₃a₄ − a₂a₅) − (a₁a₄ − a₅)² (the 4×4 leading minor of the Hurwitz
/// matrix). Zero exactly where two roots sum to zero.
template <typename Scalar>
Scalar HurwitzDelta4(const std::array<Scalar, 6>& a) {
  const Scalar e = a[1] * a[4] - a[5];
  return (a[1] * a[2] - a[3]) * (a[3] * a[4] - a[2] * a[5]) - e * e;
}

/// Δ₃ of the quartic s⁴ + a₁s³ + a₂s² + a₃s + a₄ (the quintic's coefficients with a₅ = 0 dropped):
/// a₁a₂a₃ − a₃² − a₁²a₄. The Hopf criterion where A has an exactly neutral root (a₅ ≡ 0).
template <typename Scalar>
Scalar HurwitzDelta3(const std::array<Scalar, 6>& a) {
  return a[1] * a[2] * a[3] - a[3] * a[3] - a[1] * a[1] * a[4];
}

/// The square of the crossing frequency where Δ₄ = 0: ω² = (a₁a₄ − a₅)/(a₁a₂ − a₃). Positive: a pair
/// ±iω sits on the axis (a Hopf point). Negative: a real pair ±√(−ω²) instead (no crossing). NaN when
/// a₁a₂ = a₃ (then the test is undecided).
double HopfFrequencySquared(const CharacteristicCoefficients& a);
/// The same where a₅ ≡ 0, from the quartic's Δ₃ = 0: ω² = a₃/a₁.
double DeflatedHopfFrequencySquared(const CharacteristicCoefficients& a);

/// Liénard–Chipart: every root of the quintic in the open left half-plane ⇔ all aₖ > 0, Δ₂ > 0, Δ₄ > 0.
bool HurwitzStable(const CharacteristicCoefficients& a);
/// The same for the quartic factor where a₅ ≡ 0 (the neutral root left out): a₁…a₄ > 0 and Δ₃ > 0.
bool DeflatedHurwitzStable(const CharacteristicCoefficients& a);

}  // namespace gesweep
