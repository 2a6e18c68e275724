#pragma once
/// Continuous-time algebraic Riccati equation and linear-quadratic regulators (docs/landing.md §1).
///
/// The equation solved is  AᵀS + SA − (SB + N)R⁻¹(BᵀS + Nᵀ) + Q = 0  for the stabilising S, by
/// SLICOT's SB02OD (the generalised-Schur / deflating-subspace method of Van Dooren, the routine behind
/// MATLAB's and Octave's care/lqr and python-control's slycot path). Before calling it the solver checks
/// the assumptions under which that S exists and is unique: R > 0, Q − N R⁻¹ Nᵀ ≥ 0, (A, B) stabilisable
/// and (Q − N R⁻¹ Nᵀ, A − B R⁻¹ Nᵀ) detectable, by Popov–Belevitch–Hautus rank tests at each eigenvalue
/// on or right of the imaginary axis. A failure is data: a status and a message, never an exception.

#include <Eigen/Core>
#include <complex>
#include <string>
#include <string_view>

#include "engine/common/enum_names.h"

namespace gesweep {

/// Outcome of a Riccati/LQR solve.
enum class RiccatiStatus {
  kOk,               ///< S found, A − BK Hurwitz
  kInvalidWeights,   ///< a weight is not finite, R is not positive definite or Q − NR⁻¹Nᵀ not ≥ 0
  kNotStabilizable,  ///< (A, B) fails the PBH test at an eigenvalue with Re λ ≥ 0
  kNotDetectable,    ///< (Q̄^{1/2}, Ā) fails the PBH test at an eigenvalue with Re λ ≥ 0
  kSolverFailed,     ///< SB02OD returned INFO ≠ 0, or its S did not stabilise A − BK
};

/// The name of each status (in messages and the landing's design_failed reason).
GESWEEP_ENUM_NAMES(RiccatiStatus, {kOk, "ok"}, {kInvalidWeights, "invalid_weights"},
                   {kNotStabilizable, "not_stabilizable"}, {kNotDetectable, "not_detectable"},
                   {kSolverFailed, "solver_failed"});

/// The result of Lqr / Lqry / SolveContinuousRiccati.
struct LqrResult {
  RiccatiStatus status = RiccatiStatus::kSolverFailed;
  /// Empty when status is kOk; otherwise one sentence saying what failed and where.
  std::string message;
  Eigen::MatrixXd K;  ///< m×n gain, u = −Kx: K = R⁻¹(BᵀS + Nᵀ) (empty unless kOk)
  Eigen::MatrixXd S;  ///< n×n symmetric stabilising Riccati solution (empty unless kOk)
  /// The n eigenvalues of A − BK, sorted by real part, largest first (empty unless kOk).
  Eigen::VectorXcd closed_loop_eigenvalues;
  /// SB02OD's estimate of the reciprocal condition number of the system it solved for S (0..1).
  double reciprocal_condition = 0;

  bool ok() const { return status == RiccatiStatus::kOk; }
};

/// A continuous-time state-space system ẋ = Ax + Bu, y = Cx + Du.
struct StateSpace {
  Eigen::MatrixXd A;  ///< n×n
  Eigen::MatrixXd B;  ///< n×m
  Eigen::MatrixXd C;  ///< p×n
  Eigen::MatrixXd D;  ///< p×m
};

/// Tolerances of the pre-checks. Both are relative to the scale of the matrices tested.
struct RiccatiTolerances {
  /// An eigenvalue counts as "on or right of the imaginary axis" when Re λ ≥ −axis·max(1, ‖A‖₁).
  /// 1e-8: a structural zero root computed in double precision lands within ~1e-14·‖A‖ of the axis, a
  /// genuinely stable mode of a flight model is ≥ 1e-4 s⁻¹ away.
  double axis = 1e-8;
  /// A PBH matrix is rank deficient when σ_min ≤ rank·max(1, σ_max). 1e-7 ≈ √ε: an eigenvalue of a
  /// defective (repeated) mode is computed only to about √ε, which perturbs σ_min by as much.
  double rank = 1e-7;
};

/// Solves the CARE above for the stabilising S with SB02OD and returns K = R⁻¹(BᵀS + Nᵀ).
/// A: n×n, B: n×m, Q: n×n symmetric, R: m×m symmetric, N: n×m (pass an empty matrix for N = 0).
/// Dimension mismatches are programming errors (GESWEEP_DEMAND); everything else is a status.
LqrResult Lqr(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& Q,
              const Eigen::MatrixXd& R, const Eigen::MatrixXd& N = Eigen::MatrixXd(),
              const RiccatiTolerances& tolerances = {});

/// MATLAB's lqry: output weighting J = ∫ yᵀQy + uᵀRu dt, solved as Lqr(A, B, CᵀQC, R + DᵀQD, CᵀQD).
/// Q: p×p, R: m×m.
LqrResult Lqry(const StateSpace& system, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R,
               const RiccatiTolerances& tolerances = {});

/// Result of a PBH test.
struct PbhTest {
  bool holds = true;
  std::complex<double> failing_eigenvalue;  ///< the first eigenvalue at which the rank dropped
  double relative_singular_value = 0;       ///< σ_min/max(1, σ_max) there
};

/// (A, B) stabilisable: rank [A − λI, B] = n at every eigenvalue λ of A with Re λ ≥ −axis tolerance.
PbhTest CheckStabilizable(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B,
                          const RiccatiTolerances& tolerances = {});

/// (C, A) detectable: rank [A − λI; C] = n at every eigenvalue λ of A with Re λ ≥ −axis tolerance.
PbhTest CheckDetectable(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C,
                        const RiccatiTolerances& tolerances = {});

/// ‖AᵀS + SA − (SB + N)R⁻¹(BᵀS + Nᵀ) + Q‖_F: the residual of S in the CARE (N empty means 0).
double RiccatiResidual(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& Q,
                       const Eigen::MatrixXd& R, const Eigen::MatrixXd& N, const Eigen::MatrixXd& S);

}  // namespace gesweep
