#include "engine/estimators/eigen_sensitivity.h"

#include <gtest/gtest.h>

#include <complex>

namespace gesweep {
namespace {

using Complex = std::complex<double>;
// Eigen's QR iterations return eigenvalues and vectors to a few ulps of ‖A‖ ~ 1–10.
constexpr double kRounding = 1e-12;

/// The index of the eigenvalue of `system` closest to z.
Eigen::Index Closest(const EigenSystem& system, Complex z) {
  Eigen::Index best = 0;
  for (Eigen::Index i = 1; i < system.eigenvalues.size(); ++i) {
    if (std::abs(system.eigenvalues[i] - z) < std::abs(system.eigenvalues[best] - z)) best = i;
  }
  return best;
}

class Companion : public ::testing::TestWithParam<std::pair<double, double>> {};

TEST_P(Companion, DerivativesMatchTheQuadraticFormula) {
  // A = [0 1; −k −c] has λ² + cλ + k = 0, so ∂λ/∂k = −1/(2λ + c) and ∂λ/∂c = −λ/(2λ + c).
  const auto [k, c] = GetParam();
  Eigen::MatrixXd A(2, 2);
  A << 0, 1, -k, -c;
  Eigen::MatrixXd dA_dk(2, 2), dA_dc(2, 2);
  dA_dk << 0, 0, -1, 0;
  dA_dc << 0, 0, 0, -1;
  const EigenSystem system = ComputeEigenSystem(A);
  ASSERT_TRUE(system.finite);
  const Eigen::VectorXcd by_k = EigenvalueDerivatives(system, dA_dk);
  const Eigen::VectorXcd by_c = EigenvalueDerivatives(system, dA_dc);
  const Complex root = std::sqrt(Complex(c * c - 4 * k));
  for (const Complex lambda : {(-c + root) / 2.0, (-c - root) / 2.0}) {
    const Eigen::Index i = Closest(system, lambda);
    EXPECT_LT(std::abs(system.eigenvalues[i] - lambda), kRounding);
    EXPECT_LT(std::abs(by_k[i] - (-1.0 / (2.0 * lambda + c))), kRounding) << lambda;
    EXPECT_LT(std::abs(by_c[i] - (-lambda / (2.0 * lambda + c))), kRounding) << lambda;
    EXPECT_LT(system.match_distances[i], kRounding);
    EXPECT_GE(system.condition_numbers[i], 1.0 - kRounding);
  }
}

INSTANTIATE_TEST_SUITE_P(ComplexAndRealRoots, Companion,
                         ::testing::Values(std::pair{4.0, 1.0}, std::pair{1.0, 3.0}, std::pair{25.0, 0.2}));

TEST(EigenSystem, TriangularMatrixPerturbations) {
  // A non-normal upper-triangular matrix: its eigenvalues are its diagonal, exactly, for any change of
  // the diagonal or the upper part; so ∂λ_i/∂a_jj = δ_ij and ∂λ/∂a_jk = 0 for j < k.
  Eigen::MatrixXd T(3, 3);
  T << -1.0, 5.0, -3.0, 0.0, -0.2, 8.0, 0.0, 0.0, 2.0;
  const EigenSystem system = ComputeEigenSystem(T);
  for (int j = 0; j < 3; ++j) {
    Eigen::MatrixXd E = Eigen::MatrixXd::Zero(3, 3);
    E(j, j) = 1.0;
    const Eigen::VectorXcd d = EigenvalueDerivatives(system, E);
    for (int i = 0; i < 3; ++i) {
      const Eigen::Index slot = Closest(system, T(i, i));
      EXPECT_LT(std::abs(d[slot] - Complex(i == j ? 1.0 : 0.0)), kRounding) << i << j;
    }
  }
  Eigen::MatrixXd upper = Eigen::MatrixXd::Zero(3, 3);
  upper(0, 2) = 1.0;
  upper(1, 2) = 1.0;
  EXPECT_LT(EigenvalueDerivatives(system, upper).cwiseAbs().maxCoeff(), kRounding);
}

TEST(EigenSystem, LeftVectorsAreLeftEigenvectors) {
  Eigen::MatrixXd A(4, 4);
  A << -0.02, 0.1, 0, -9.8, -0.3, -2.0, 30.0, 0, 0.01, -0.4, -1.5, 0, 0, 0, 1, 0;
  const EigenSystem system = ComputeEigenSystem(A);
  const Eigen::MatrixXcd Ac = A.cast<Complex>();
  for (Eigen::Index i = 0; i < 4; ++i) {
    const Eigen::VectorXcd y = system.left.col(i);
    const Eigen::RowVectorXcd residual = y.adjoint() * Ac - system.eigenvalues[i] * y.adjoint();
    EXPECT_LT(residual.norm(), 1e-10 * y.norm()) << i;
  }
}

TEST(EigenSystem, NonFiniteMatrixGivesNaN) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(2, 2);
  A(0, 1) = std::numeric_limits<double>::quiet_NaN();
  const EigenSystem system = ComputeEigenSystem(A);
  EXPECT_FALSE(system.finite);
  EXPECT_TRUE(std::isnan(system.eigenvalues[0].real()));
}

}  // namespace
}  // namespace gesweep
