// The Riccati/LQR wrapper against known solutions (docs/landing.md §1).
#include "engine/control/riccati.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

namespace gesweep {
namespace {

// Tolerances: each says where it comes from.
/// An eigenvalue that is exactly 0 comes back from LAPACK as rounding of an O(1) matrix.
constexpr double kEigenvalueRoundingTolerance = 1e-12;

using Eigen::MatrixXd;

/// Analytic solutions are exact; SB02OD's backward-stable solve leaves a few ulps times the condition.
constexpr double kAnalyticTolerance = 1e-10;
/// The issue's 2×2 example is published to 4 decimals: half a unit in the last place.
constexpr double kFourDecimalTolerance = 5e-5;
/// Relative CARE residual on random well-conditioned systems: rounding of an n = 6 QZ solve.
constexpr double kRelativeResidualTolerance = 1e-9;

MatrixXd Mat(std::initializer_list<std::initializer_list<double>> rows) {
  MatrixXd m(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(rows.begin()->size()));
  Eigen::Index i = 0;
  for (const auto& row : rows) {
    Eigen::Index j = 0;
    for (double v : row) m(i, j++) = v;
    ++i;
  }
  return m;
}

TEST(Lqr, DoubleIntegratorMatchesTheAnalyticSolution) {
  // ẋ1 = x2, ẋ2 = u, Q = I, R = 1: S = [[√3, 1], [1, √3]], K = [1, √3], poles −(√3 ± i)/2.
  const MatrixXd A = Mat({{0, 1}, {0, 0}});
  const MatrixXd B = Mat({{0}, {1}});
  const LqrResult result = Lqr(A, B, MatrixXd::Identity(2, 2), MatrixXd::Identity(1, 1));
  ASSERT_TRUE(result.ok()) << result.message;
  const double r3 = std::sqrt(3.0);
  EXPECT_NEAR(result.S(0, 0), r3, kAnalyticTolerance);
  EXPECT_NEAR(result.S(0, 1), 1.0, kAnalyticTolerance);
  EXPECT_NEAR(result.S(1, 0), 1.0, kAnalyticTolerance);
  EXPECT_NEAR(result.S(1, 1), r3, kAnalyticTolerance);
  EXPECT_NEAR(result.K(0, 0), 1.0, kAnalyticTolerance);
  EXPECT_NEAR(result.K(0, 1), r3, kAnalyticTolerance);
  ASSERT_EQ(result.closed_loop_eigenvalues.size(), 2);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(result.closed_loop_eigenvalues(i).real(), -r3 / 2, kAnalyticTolerance);
    EXPECT_NEAR(std::abs(result.closed_loop_eigenvalues(i).imag()), 0.5, kAnalyticTolerance);
  }
}

TEST(Lqr, IssueTwoByTwoExample) {
  const MatrixXd A = Mat({{-3, 2}, {1, 1}});
  const MatrixXd B = Mat({{0}, {1}});
  const MatrixXd C = Mat({{1, -1}});
  const LqrResult result = Lqr(A, B, C.transpose() * C, Mat({{3}}));
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_NEAR(result.S(0, 0), 0.5895, kFourDecimalTolerance);
  EXPECT_NEAR(result.S(0, 1), 1.8216, kFourDecimalTolerance);
  EXPECT_NEAR(result.S(1, 1), 8.8188, kFourDecimalTolerance);
  EXPECT_NEAR(result.K(0, 0), 0.6072, kFourDecimalTolerance);
  EXPECT_NEAR(result.K(0, 1), 2.9396, kFourDecimalTolerance);
  EXPECT_LT(result.closed_loop_eigenvalues(0).real(), 0.0);
}

TEST(Lqry, OutputWeightingWithoutFeedthroughIsTheSameProblem) {
  StateSpace system{Mat({{-3, 2}, {1, 1}}), Mat({{0}, {1}}), Mat({{1, -1}}), Mat({{0}})};
  const LqrResult result = Lqry(system, Mat({{1}}), Mat({{3}}));
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_NEAR(result.K(0, 0), 0.6072, kFourDecimalTolerance);
  EXPECT_NEAR(result.K(0, 1), 2.9396, kFourDecimalTolerance);
}

TEST(Lqry, ScalarSystemWithFeedthroughMatchesTheQuadraticFormula) {
  // ẋ = a x + b u, y = c x + d u, J = ∫ q y² + r u². With Q̄ = c²q, R̄ = r + d²q, N̄ = cqd the scalar CARE
  // (b²/R̄) S² + 2(N̄b/R̄ − a) S + (N̄²/R̄ − Q̄) = 0 has the stabilising root below; k = (bS + N̄)/R̄.
  const double a = 0.7, b = 1.3, c = 2.0, d = 0.5, q = 1.5, r = 0.4;
  const double Qb = c * c * q, Rb = r + d * d * q, Nb = c * q * d;
  const double qa = b * b / Rb, qb = 2 * (Nb * b / Rb - a), qc = Nb * Nb / Rb - Qb;
  const double S = (-qb + std::sqrt(qb * qb - 4 * qa * qc)) / (2 * qa);
  const double k = (b * S + Nb) / Rb;
  ASSERT_LT(a - b * k, 0.0);  // the root taken is the stabilising one
  StateSpace system{Mat({{a}}), Mat({{b}}), Mat({{c}}), Mat({{d}})};
  const LqrResult result = Lqry(system, Mat({{q}}), Mat({{r}}));
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_NEAR(result.S(0, 0), S, kAnalyticTolerance);
  EXPECT_NEAR(result.K(0, 0), k, kAnalyticTolerance);
  EXPECT_NEAR(result.closed_loop_eigenvalues(0).real(), a - b * k, kAnalyticTolerance);
}

TEST(Lqr, ResidualIsSmallOnRandomStabilizableSystems) {
  std::mt19937_64 generator(20240611);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto random = [&](int rows, int cols) {
    MatrixXd m(rows, cols);
    for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = normal(generator);
    return m;
  };
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 3 + trial % 5;
    const int m = 1 + trial % 3;
    const MatrixXd A = random(n, n);
    const MatrixXd B = random(n, m);
    const MatrixXd M = random(n, n);
    const MatrixXd Q = M.transpose() * M + 0.1 * MatrixXd::Identity(n, n);
    const MatrixXd W = random(m, m);
    const MatrixXd R = W.transpose() * W + MatrixXd::Identity(m, m);
    const MatrixXd N = trial % 2 == 0 ? MatrixXd() : MatrixXd(0.1 * random(n, m));
    const LqrResult result = Lqr(A, B, Q, R, N);
    ASSERT_TRUE(result.ok()) << "trial " << trial << ": " << result.message;
    // The residual written out here, not through the library's helper.
    const MatrixXd cross = N.size() == 0 ? MatrixXd::Zero(n, m) : N;
    const MatrixXd& S = result.S;
    const MatrixXd SBN = S * B + cross;
    const MatrixXd residual = A.transpose() * S + S * A - SBN * R.inverse() * SBN.transpose() + Q;
    const double scale = (A.transpose() * S).norm() + (SBN * R.inverse() * SBN.transpose()).norm() + Q.norm();
    EXPECT_LT(residual.norm() / scale, kRelativeResidualTolerance) << "trial " << trial;
    EXPECT_LT(result.closed_loop_eigenvalues.real().maxCoeff(), 0.0) << "trial " << trial;
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<MatrixXd>(S).eigenvalues().minCoeff(), -1e-9 * S.norm());
  }
}

TEST(Lqr, UnstabilizableSystemFailsCleanly) {
  // The unstable mode x1 (λ = 1) is not reached by the input.
  const LqrResult result = Lqr(Mat({{1, 0}, {0, -1}}), Mat({{0}, {1}}), MatrixXd::Identity(2, 2), Mat({{1}}));
  EXPECT_EQ(result.status, RiccatiStatus::kNotStabilizable);
  EXPECT_NE(result.message.find("not stabilizable"), std::string::npos) << result.message;
  EXPECT_EQ(result.K.size(), 0);
}

TEST(Lqr, TwoIntegratorsOfTheSameSignalAreNotStabilizable) {
  // The landing model's trap: ΔH and d both integrate one signal, so ΔH − d is an uncontrollable zero root.
  const MatrixXd A = Mat({{-1, 0, 0}, {1, 0, 0}, {1, 0, 0}});
  const MatrixXd B = Mat({{1}, {0}, {0}});
  const LqrResult result = Lqr(A, B, MatrixXd::Identity(3, 3), Mat({{1}}));
  EXPECT_EQ(result.status, RiccatiStatus::kNotStabilizable);
  EXPECT_NEAR(std::abs(CheckStabilizable(A, B).failing_eigenvalue), 0.0, kEigenvalueRoundingTolerance);
}

TEST(Lqr, UndetectableUnstableModeFailsCleanly) {
  // x1 unstable and unweighted: the "optimal" control leaves it alone, so no stabilising S is optimal.
  const LqrResult result =
      Lqr(Mat({{1, 0}, {0, -2}}), MatrixXd::Identity(2, 2), Mat({{0, 0}, {0, 1}}), MatrixXd::Identity(2, 2));
  EXPECT_EQ(result.status, RiccatiStatus::kNotDetectable);
}

TEST(Lqr, InvalidWeightsAreReported) {
  const MatrixXd A = Mat({{0, 1}, {0, 0}});
  const MatrixXd B = Mat({{0}, {1}});
  EXPECT_EQ(Lqr(A, B, MatrixXd::Identity(2, 2), Mat({{0}})).status, RiccatiStatus::kInvalidWeights);
  EXPECT_EQ(Lqr(A, B, Mat({{1, 0}, {0, -1}}), Mat({{1}})).status, RiccatiStatus::kInvalidWeights);
  EXPECT_EQ(Lqr(A, B, Mat({{1, 1}, {0, 1}}), Mat({{1}})).status, RiccatiStatus::kInvalidWeights);
  EXPECT_EQ(Lqr(A, B, MatrixXd::Identity(2, 2), Mat({{std::nan("")}})).status,
            RiccatiStatus::kInvalidWeights);
}

TEST(Pbh, StableUncontrollableModeIsStillStabilizable) {
  EXPECT_TRUE(CheckStabilizable(Mat({{-1, 0}, {0, 2}}), Mat({{0}, {1}})).holds);
  EXPECT_FALSE(CheckStabilizable(Mat({{-1, 0}, {0, 2}}), Mat({{1}, {0}})).holds);
  EXPECT_TRUE(CheckDetectable(Mat({{-1, 0}, {0, 2}}), Mat({{0, 1}})).holds);
  EXPECT_FALSE(CheckDetectable(Mat({{-1, 0}, {0, 2}}), Mat({{1, 0}})).holds);
}

}  // namespace
}  // namespace gesweep
