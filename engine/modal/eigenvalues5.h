#pragma once
/// The fixed-size eigenvalue kernel of a real 5×5 matrix: balancing, Householder reduction to upper
/// Hessenberg form and the Francis double-shift QR iteration with deflation, eigenvalues only
/// (docs/model.md §6, "The eigenvalue kernel"). It follows LAPACK's small-matrix path step by step —
/// dgebal (job 'S'), dgehd2, dlahqr with dlanv2 for the 2×2 blocks — written for n = 5: loop bounds
/// known at compile time, no workspace, no library calls, the QR applied to the active block only.
/// `AnalyzeModes` uses it by default (engine/modal/modal_analysis.h).

#include <array>
#include <complex>

#include "engine/dynamics/longitudinal_model.h"

namespace gesweep {

/// dlahqr's iteration limit for n = 5: 30·max(10, n) double-shift sweeps per eigenvalue block.
inline constexpr int kFrancisMaxIterations = 300;

/// The balanced matrix D⁻¹AD and the diagonal of D (powers of 2, so the similarity is exact).
struct BalancedMatrix5 {
  Matrix5d matrix;
  std::array<double, 5> scale{};
};

/// LAPACK dgebal with job 'S' (scaling only; LAPACK ≥ 3.5: row and column 2-norms, radix 2, a step
/// taken when it cuts their sum by 5 %) for a finite 5×5. The same D as dgebal wherever BLAS dnrm2 is a
/// plain sum of squares (every nonzero entry between 2⁻⁵¹¹ and 2⁴⁸⁶); outside that range the norms are
/// scaled against overflow and underflow, so D may differ from dgebal's, but the similarity stays
/// exact and the eigenvalues are A's.
BalancedMatrix5 Balance5(const Matrix5d& A);

/// The eigenvalues of one real 5×5 and how the QR went.
struct FrancisResult {
  /// In the order of the Hessenberg diagonal after convergence. A complex pair occupies two adjacent
  /// entries, Im > 0 first, with exactly opposite imaginary parts; a real eigenvalue has Im exactly 0.
  std::array<std::complex<double>, 5> values{};
  /// false when a block did not converge within the iteration limit (then `values` is meaningless).
  bool converged = true;
  int iterations = 0;  ///< double-shift sweeps, all blocks together
};

/// Householder reduction of A to Hessenberg form (dgehd2), then dlahqr's Francis double-shift QR
/// (eigenvalues only): the Ahues–Kressner deflation criterion, exceptional shifts after every 10 and
/// 20 sweeps without a deflation, the search for two small consecutive subdiagonal entries to start
/// the bulge, dlanv2's standardisation of a converged 2×2 block (a complex pair gets equal diagonal
/// entries; a real pair is made triangular). A whose largest entry lies outside [2⁻⁴⁵⁹, 2⁴⁵⁹] is
/// first multiplied by a power of two that brings it to [1, 2), as dgeev scales before dlahqr (whose
/// negligibility thresholds are absolute), and the eigenvalues are scaled back. No balancing here
/// (Balance5, or BalancedFrancisEigenvalues5). A must be finite; `max_iterations` ≥ 0 bounds the
/// sweeps per block.
FrancisResult FrancisEigenvalues5(const Matrix5d& A, int max_iterations = kFrancisMaxIterations);

/// Balance5 then FrancisEigenvalues5, without leaving the kernel's own storage: the eigenvalues of A.
FrancisResult BalancedFrancisEigenvalues5(const Matrix5d& A, int max_iterations = kFrancisMaxIterations);

}  // namespace gesweep
