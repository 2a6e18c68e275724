#include "engine/control/riccati.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <vector>

#include "engine/common/errors.h"

// SLICOT SB02OD (Fortran 77, compiled by gfortran). gfortran passes every argument by reference and
// appends one hidden length argument (size_t since GCC 8) per CHARACTER argument, in order.
extern "C" void sb02od_(const char* dico, const char* jobb, const char* fact, const char* uplo,
                        const char* jobl, const char* sort, const int* n, const int* m, const int* p,
                        const double* a, const int* lda, const double* b, const int* ldb, const double* q,
                        const int* ldq, const double* r, const int* ldr, const double* l, const int* ldl,
                        double* rcond, double* x, const int* ldx, double* alfar, double* alfai, double* beta,
                        double* s, const int* lds, double* t, const int* ldt, double* u, const int* ldu,
                        const double* tol, int* iwork, double* dwork, const int* ldwork, int* bwork,
                        int* info, std::size_t dico_len, std::size_t jobb_len, std::size_t fact_len,
                        std::size_t uplo_len, std::size_t jobl_len, std::size_t sort_len);

namespace gesweep {
namespace {

using Eigen::MatrixXcd;
using Eigen::MatrixXd;
using Eigen::VectorXcd;

/// Symmetry and semi-definiteness are judged relative to the matrix's size: 1e-10 is far above the
/// rounding of a product CᵀQC (~1e-16·‖·‖) and far below any weight a person would write.
constexpr double kSymmetryTolerance = 1e-10;
constexpr double kSemidefiniteTolerance = 1e-10;

std::string FormatComplex(std::complex<double> z) {
  std::ostringstream out;
  out.precision(6);
  out << z.real() << (z.imag() < 0 ? "-" : "+") << std::abs(z.imag()) << "i";
  return out.str();
}

bool AllFinite(const MatrixXd& m) { return m.size() == 0 || m.allFinite(); }

bool IsSymmetric(const MatrixXd& m) {
  const double scale = std::max(1.0, m.cwiseAbs().maxCoeff());
  return (m - m.transpose()).cwiseAbs().maxCoeff() <= kSymmetryTolerance * scale;
}

double AxisThreshold(const MatrixXd& A, const RiccatiTolerances& tolerances) {
  const double norm1 = A.size() == 0 ? 0.0 : A.cwiseAbs().colwise().sum().maxCoeff();
  return -tolerances.axis * std::max(1.0, norm1);
}

/// PBH rank test of the stacked matrix built by `build(λ)` (n rows of rank to test after a transpose
/// when needed): fails when its n-th singular value is relatively ≤ the rank tolerance.
template <typename Build>
PbhTest PbhRank(const MatrixXd& A, int n, Build build, const RiccatiTolerances& tolerances) {
  PbhTest result;
  if (n == 0) return result;
  const VectorXcd eigenvalues = Eigen::EigenSolver<MatrixXd>(A, false).eigenvalues();
  const double threshold = AxisThreshold(A, tolerances);
  for (Eigen::Index i = 0; i < eigenvalues.size(); ++i) {
    const std::complex<double> lambda = eigenvalues(i);
    if (lambda.real() < threshold) continue;
    const MatrixXcd pbh = build(lambda);
    const Eigen::VectorXd sigma = Eigen::JacobiSVD<MatrixXcd>(pbh).singularValues();
    // min(rows, cols) ≥ n for both tests; σ(n−1) is the n-th largest singular value.
    const double relative = sigma(n - 1) / std::max(1.0, sigma(0));
    if (relative <= tolerances.rank) {
      result.holds = false;
      result.failing_eigenvalue = lambda;
      result.relative_singular_value = relative;
      return result;
    }
  }
  return result;
}

/// The PBH matrix [A − λI, B] of stabilizability (B beside A) or [A − λI; C] of detectability (C below).
MatrixXcd PbhMatrix(const MatrixXd& A, std::complex<double> lambda, const MatrixXd& other, bool below) {
  MatrixXcd shifted = A.cast<std::complex<double>>();
  shifted.diagonal().array() -= lambda;
  MatrixXcd pbh(A.rows() + (below ? other.rows() : 0), A.cols() + (below ? 0 : other.cols()));
  pbh << shifted, other.cast<std::complex<double>>();
  return pbh;
}

/// Symmetric square root of a positive semi-definite matrix (negative rounding eigenvalues → 0).
MatrixXd SymmetricSqrt(const MatrixXd& m) {
  Eigen::SelfAdjointEigenSolver<MatrixXd> solver(m);
  const Eigen::VectorXd roots = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return solver.eigenvectors() * roots.asDiagonal() * solver.eigenvectors().transpose();
}

LqrResult Failure(RiccatiStatus status, std::string message) {
  LqrResult result;
  result.status = status;
  result.message = std::move(message);
  return result;
}

/// SB02OD, continuous time, B and R given, Q and R unfactored (upper triangles read), L = N, stable
/// eigenvalues first so that X is the stabilising solution: X into `x` (n × n), the reciprocal
/// condition number into `rcond`; SB02OD's INFO (0: solved).
int SolveSb02od(const MatrixXd& A, const MatrixXd& B, const MatrixXd& Q, const MatrixXd& R,
                const MatrixXd& cross, MatrixXd& x, double& rcond) {
  const Eigen::Index n = A.rows();
  const Eigen::Index m = B.cols();
  const int n_i = static_cast<int>(n);
  const int m_i = static_cast<int>(m);
  const int p_i = 0;  // not referenced when FACT = 'N'
  const int two_n = 2 * n_i;
  const int lds = two_n + m_i;
  const int ldl = n_i;
  MatrixXd a = A, b = B, q = Q, r = R, l = cross;
  x = MatrixXd::Zero(n, n);
  std::vector<double> alfar(two_n), alfai(two_n), beta(two_n);
  MatrixXd s = MatrixXd::Zero(lds, lds), t = MatrixXd::Zero(lds, two_n), u = MatrixXd::Zero(two_n, two_n);
  // Documented minimum max(7(2n+1)+16, 16n, 2n+m, 3m); SLICOT's own notes say it can be too small for
  // large n, so take generously more (these systems are small).
  const int ldwork = std::max({7 * (two_n + 1) + 16, 16 * n_i, two_n + m_i, 3 * m_i}) * 8 + 64 * lds;
  std::vector<double> dwork(ldwork);
  std::vector<int> iwork(std::max({1, m_i, two_n}));
  std::vector<int> bwork(two_n);
  const double tol = 0.0;  // SB02OD's default: machine epsilon
  rcond = 0;
  int info = 0;
  sb02od_("C", "B", "N", "U", "N", "S", &n_i, &m_i, &p_i, a.data(), &n_i, b.data(), &n_i, q.data(), &n_i,
          r.data(), &m_i, l.data(), &ldl, &rcond, x.data(), &n_i, alfar.data(), alfai.data(), beta.data(),
          s.data(), &lds, t.data(), &lds, u.data(), &two_n, &tol, iwork.data(), dwork.data(), &ldwork,
          bwork.data(), &info, 1, 1, 1, 1, 1, 1);
  return info;
}

/// The failure of an SB02OD that returned INFO ≠ 0, with SB02OD's reason for INFO 1 to 6.
LqrResult Sb02odFailure(int info) {
  static constexpr const char* kReasons[] = {
      "",
      "the extended matrix pencil is singular",
      "the QZ algorithm failed",
      "reordering of the generalized eigenvalues failed",
      "rounding moved eigenvalues across the stability boundary after reordering",
      "the stable deflating subspace does not have dimension n (eigenvalues on the imaginary axis?)",
      "the solution matrix system is singular",
  };
  std::ostringstream message;
  message << "SB02OD failed with INFO = " << info;
  if (info >= 1 && info <= 6) message << ": " << kReasons[info];
  return Failure(RiccatiStatus::kSolverFailed, message.str());
}

/// The result from SB02OD's X: S = (X + Xᵀ)/2, K = R⁻¹(BᵀS + Nᵀ) and the eigenvalues of A − BK,
/// largest real part first; a failure when S or K is not finite or A − BK is not stable.
LqrResult StabilisingGain(const MatrixXd& A, const MatrixXd& B, const MatrixXd& cross,
                          const Eigen::LLT<MatrixXd>& r_factor, const MatrixXd& x, double rcond) {
  LqrResult result;
  result.reciprocal_condition = rcond;
  result.S = 0.5 * (x + x.transpose());
  result.K = r_factor.solve(B.transpose() * result.S + cross.transpose());
  VectorXcd closed = Eigen::EigenSolver<MatrixXd>(A - B * result.K, false).eigenvalues();
  std::sort(closed.data(), closed.data() + closed.size(),
            [](const std::complex<double>& a, const std::complex<double>& b) {
              return a.real() != b.real() ? a.real() > b.real() : a.imag() > b.imag();
            });
  result.closed_loop_eigenvalues = closed;
  if (!result.S.allFinite() || !result.K.allFinite() || !(closed(0).real() < 0.0)) {
    return Failure(RiccatiStatus::kSolverFailed,
                   "SB02OD returned a solution that does not stabilise A - BK (closed-loop eigenvalue " +
                       FormatComplex(closed(0)) + ")");
  }
  result.status = RiccatiStatus::kOk;
  return result;
}

}  // namespace

PbhTest CheckStabilizable(const MatrixXd& A, const MatrixXd& B, const RiccatiTolerances& tolerances) {
  GESWEEP_DEMAND(A.rows() == A.cols() && B.rows() == A.rows());
  return PbhRank(
      A, static_cast<int>(A.rows()),
      [&](std::complex<double> lambda) { return PbhMatrix(A, lambda, B, false); }, tolerances);
}

PbhTest CheckDetectable(const MatrixXd& A, const MatrixXd& C, const RiccatiTolerances& tolerances) {
  GESWEEP_DEMAND(A.rows() == A.cols() && C.cols() == A.cols());
  return PbhRank(
      A, static_cast<int>(A.rows()),
      [&](std::complex<double> lambda) { return PbhMatrix(A, lambda, C, true); }, tolerances);
}

double RiccatiResidual(const MatrixXd& A, const MatrixXd& B, const MatrixXd& Q, const MatrixXd& R,
                       const MatrixXd& N, const MatrixXd& S) {
  const MatrixXd cross = N.size() == 0 ? MatrixXd::Zero(A.rows(), B.cols()) : N;
  const MatrixXd SB_N = S * B + cross;
  return (A.transpose() * S + S * A - SB_N * R.ldlt().solve(SB_N.transpose()) + Q).norm();
}

LqrResult Lqr(const MatrixXd& A, const MatrixXd& B, const MatrixXd& Q, const MatrixXd& R, const MatrixXd& N,
              const RiccatiTolerances& tolerances) {
  const Eigen::Index n = A.rows();
  const Eigen::Index m = B.cols();
  GESWEEP_DEMAND(A.cols() == n && B.rows() == n && Q.rows() == n && Q.cols() == n);
  GESWEEP_DEMAND(R.rows() == m && R.cols() == m);
  GESWEEP_DEMAND(N.size() == 0 || (N.rows() == n && N.cols() == m));
  GESWEEP_DEMAND(n > 0 && m > 0);
  const MatrixXd cross = N.size() == 0 ? MatrixXd::Zero(n, m) : N;

  if (!AllFinite(A) || !AllFinite(B)) {
    return Failure(RiccatiStatus::kSolverFailed, "A or B has a non-finite entry");
  }
  if (!AllFinite(Q) || !AllFinite(R) || !AllFinite(cross)) {
    return Failure(RiccatiStatus::kInvalidWeights, "a weight (Q, R or N) is not finite");
  }
  if (!IsSymmetric(Q) || !IsSymmetric(R)) {
    return Failure(RiccatiStatus::kInvalidWeights, "Q and R must be symmetric");
  }
  const Eigen::LLT<MatrixXd> r_factor(0.5 * (R + R.transpose()));
  if (r_factor.info() != Eigen::Success) {
    return Failure(RiccatiStatus::kInvalidWeights, "R is not positive definite");
  }
  // The cross term is removed by the change of input v = u + R⁻¹Nᵀx: Ā = A − BR⁻¹Nᵀ, Q̄ = Q − NR⁻¹Nᵀ.
  const MatrixXd r_inv_nt = r_factor.solve(cross.transpose());
  const MatrixXd A_bar = A - B * r_inv_nt;
  MatrixXd Q_bar = Q - cross * r_inv_nt;
  Q_bar = 0.5 * (Q_bar + Q_bar.transpose());
  const Eigen::VectorXd q_eigen = Eigen::SelfAdjointEigenSolver<MatrixXd>(Q_bar).eigenvalues();
  if (q_eigen.minCoeff() < -kSemidefiniteTolerance * std::max(1.0, q_eigen.cwiseAbs().maxCoeff())) {
    std::ostringstream message;
    message << "Q - N R^-1 N' is not positive semi-definite (smallest eigenvalue " << q_eigen.minCoeff()
            << ")";
    return Failure(RiccatiStatus::kInvalidWeights, message.str());
  }

  const PbhTest stabilizable = CheckStabilizable(A, B, tolerances);
  if (!stabilizable.holds) {
    return Failure(RiccatiStatus::kNotStabilizable, "(A, B) is not stabilizable: the mode at lambda = " +
                                                        FormatComplex(stabilizable.failing_eigenvalue) +
                                                        " is uncontrollable");
  }
  const PbhTest detectable = CheckDetectable(A_bar, SymmetricSqrt(Q_bar), tolerances);
  if (!detectable.holds) {
    return Failure(RiccatiStatus::kNotDetectable, "(Q, A) is not detectable: the mode at lambda = " +
                                                      FormatComplex(detectable.failing_eigenvalue) +
                                                      " is unweighted by Q and not stable");
  }

  MatrixXd x;
  double rcond = 0;
  const int info = SolveSb02od(A, B, Q, R, cross, x, rcond);
  if (info != 0) return Sb02odFailure(info);
  return StabilisingGain(A, B, cross, r_factor, x, rcond);
}

LqrResult Lqry(const StateSpace& system, const MatrixXd& Q, const MatrixXd& R,
               const RiccatiTolerances& tolerances) {
  const Eigen::Index n = system.A.rows();
  const Eigen::Index m = system.B.cols();
  const Eigen::Index p = system.C.rows();
  GESWEEP_DEMAND(system.C.cols() == n && system.D.rows() == p && system.D.cols() == m);
  GESWEEP_DEMAND(Q.rows() == p && Q.cols() == p);
  if (!AllFinite(Q) || !IsSymmetric(Q)) {
    return Failure(RiccatiStatus::kInvalidWeights, "the output weight Q must be finite and symmetric");
  }
  const MatrixXd q_bar = system.C.transpose() * Q * system.C;
  const MatrixXd r_bar = R + system.D.transpose() * Q * system.D;
  const MatrixXd n_bar = system.C.transpose() * Q * system.D;
  return Lqr(system.A, system.B, 0.5 * (q_bar + q_bar.transpose()), 0.5 * (r_bar + r_bar.transpose()), n_bar,
             tolerances);
}

}  // namespace gesweep
