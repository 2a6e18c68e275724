#include "engine/modal/hurwitz.h"

#include <cmath>
#include <limits>

namespace gesweep {

namespace {

// A has the sparsity of Eq. (1): row Δθ = [0 0 1 0 0], row ΔH = [0 −1 0 u0 0], and zeros at
// (Δu, q), (Δw, Δθ), (q, Δθ).
bool HasEquation1Pattern(const Matrix5d& A) {
  return A(0, 2) == 0.0 && A(1, 3) == 0.0 && A(2, 3) == 0.0 && A(3, 0) == 0.0 && A(3, 1) == 0.0 &&
         A(3, 2) == 1.0 && A(3, 3) == 0.0 && A(3, 4) == 0.0 && A(4, 0) == 0.0 && A(4, 1) == -1.0 &&
         A(4, 2) == 0.0 && A(4, 4) == 0.0;
}

// det(sI − A) expanded for that pattern (the expansion checked against the Hessenberg path in
// tests/modal/hurwitz_test.cc): a sum of products, rounding relative to its terms as the reduction.
CharacteristicCoefficients Equation1Polynomial(const Matrix5d& A) {
  const double a00 = A(0, 0), a01 = A(0, 1), a03 = A(0, 3), a04 = A(0, 4);
  const double a10 = A(1, 0), a11 = A(1, 1), a12 = A(1, 2), a14 = A(1, 4);
  const double a20 = A(2, 0), a21 = A(2, 1), a22 = A(2, 2), a24 = A(2, 4);
  const double a43 = A(4, 3);
  const double m01 = a00 * a11 - a01 * a10;  // leading 2×2 minor
  const double m12 = a11 * a22 - a12 * a21;
  const double m02 = a00 * a22;
  CharacteristicCoefficients a;
  a[0] = 1.0;
  a[1] = -a00 - a11 - a22;
  a[2] = m01 + m02 + m12 + a14;
  a[3] = -a00 * m12 - a01 * (a12 * a20 - a10 * a22) - a03 * a20 + a04 * a10 + a12 * a24 - a14 * a22 -
         a00 * a14 - a24 * a43;
  a[4] = a00 * (a14 * a22 - a12 * a24 + a24 * a43) + a03 * (a11 * a20 - a10 * a21) +
         a04 * (a12 * a20 - a10 * a22 - a20 * a43) + a43 * (a11 * a24 - a14 * a21);
  a[5] =
      a43 * (a00 * (a14 * a21 - a11 * a24) + a01 * (a10 * a24 - a14 * a20) + a04 * (a11 * a20 - a10 * a21)) +
      a03 * (a10 * a24 - a14 * a20);
  return a;
}

}  // namespace

CharacteristicCoefficients CharacteristicPolynomial(const Matrix5d& A) {
  if (HasEquation1Pattern(A)) return Equation1Polynomial(A);
  return HessenbergCharacteristicPolynomial(A);
}

CharacteristicCoefficients HessenbergCharacteristicPolynomial(const Matrix5d& A) {
  // Householder reduction to upper Hessenberg form H = QᵀAQ (same characteristic polynomial).
  double h[5][5];
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) h[i][j] = A(i, j);
  for (int k = 0; k < 3; ++k) {
    double norm2 = 0;
    for (int i = k + 1; i < 5; ++i) norm2 += h[i][k] * h[i][k];
    const double tail2 = norm2 - h[k + 1][k] * h[k + 1][k];
    if (tail2 == 0.0) continue;  // already Hessenberg in this column
    const double alpha = h[k + 1][k] >= 0 ? -std::sqrt(norm2) : std::sqrt(norm2);
    double v[5] = {0, 0, 0, 0, 0};
    v[k + 1] = h[k + 1][k] - alpha;
    for (int i = k + 2; i < 5; ++i) v[i] = h[i][k];
    const double vv = v[k + 1] * v[k + 1] + tail2;
    const double beta = 2.0 / vv;
    // H ← (I − βvvᵀ) H (I − βvvᵀ)
    for (int j = 0; j < 5; ++j) {
      double s = 0;
      for (int i = k + 1; i < 5; ++i) s += v[i] * h[i][j];
      s *= beta;
      for (int i = k + 1; i < 5; ++i) h[i][j] -= s * v[i];
    }
    for (int i = 0; i < 5; ++i) {
      double s = 0;
      for (int j = k + 1; j < 5; ++j) s += h[i][j] * v[j];
      s *= beta;
      for (int j = k + 1; j < 5; ++j) h[i][j] -= s * v[j];
    }
    h[k + 1][k] = alpha;
    for (int i = k + 2; i < 5; ++i) h[i][k] = 0.0;
  }
  // p_k: the characteristic polynomial of the leading k×k block, p_k[m] the coefficient of s^{k−m}.
  // p_k(s) = (s − h_jj) p_{k−1}(s) − Σ_{i<j} h_ij (h_{i+1,i} ⋯ h_{j,j−1}) p_i(s), j = k − 1.
  double p[6][6] = {};
  p[0][0] = 1.0;
  for (int k = 1; k <= 5; ++k) {
    const int j = k - 1;
    p[k][0] = 1.0;
    for (int m = 1; m <= k; ++m) p[k][m] = (m < k ? p[k - 1][m] : 0.0) - h[j][j] * p[k - 1][m - 1];
    double product = 1.0;
    for (int i = j - 1; i >= 0; --i) {
      product *= h[i + 1][i];
      const double c = h[i][j] * product;
      if (c == 0.0) continue;
      // p_i has degree i: its coefficient m' of s^{i−m'} lands on s^{k−(k−i+m')}.
      for (int m = 0; m <= i; ++m) p[k][k - i + m] -= c * p[i][m];
    }
  }
  CharacteristicCoefficients a;
  for (int m = 0; m <= 5; ++m) a[static_cast<std::size_t>(m)] = p[5][m];
  return a;
}

double HopfFrequencySquared(const CharacteristicCoefficients& a) {
  const double denominator = a[1] * a[2] - a[3];
  if (denominator == 0.0) return std::numeric_limits<double>::quiet_NaN();
  return (a[1] * a[4] - a[5]) / denominator;
}

double DeflatedHopfFrequencySquared(const CharacteristicCoefficients& a) {
  if (a[1] == 0.0) return std::numeric_limits<double>::quiet_NaN();
  return a[3] / a[1];
}

bool HurwitzStable(const CharacteristicCoefficients& a) {
  for (int k = 1; k <= 5; ++k)
    if (!(a[static_cast<std::size_t>(k)] > 0.0)) return false;
  return a[1] * a[2] - a[3] > 0.0 && HurwitzDelta4(a) > 0.0;
}

bool DeflatedHurwitzStable(const CharacteristicCoefficients& a) {
  for (int k = 1; k <= 4; ++k)
    if (!(a[static_cast<std::size_t>(k)] > 0.0)) return false;
  return HurwitzDelta3(a) > 0.0;
}

}  // namespace gesweep
