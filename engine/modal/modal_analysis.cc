#include "engine/common/errors.h"
#include "engine/modal/modal_analysis.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

// LAPACK (reference or OpenBLAS), Fortran calling convention.
extern "C" void dgebal_(const char* job, const int* n, double* a, const int* lda, int* ilo, int* ihi,
                        double* scale, int* info, std::size_t job_length);
// Unblocked Householder reduction to Hessenberg form, and the double-shift QR of a Hessenberg matrix
// (what dhseqr calls for n < 75): LAPACK's own small-matrix path, without workspace queries.
extern "C" void dgehd2_(const int* n, const int* ilo, const int* ihi, double* a, const int* lda, double* tau,
                        double* work, int* info);
extern "C" void dlahqr_(const int* wantt, const int* wantz, const int* n, const int* ilo, const int* ihi,
                        double* h, const int* ldh, double* wr, double* wi, const int* iloz, const int* ihiz,
                        double* z, const int* ldz, int* info);

namespace gesweep {
namespace {

// Balances A (LAPACK dgebal, job 'S': a diagonal similarity by powers of two, exact in floating
// point, so the eigenvalues are A's). A's entries span 1e-3 (Mh) to 32 (u0); balanced, the Francis QR
// converges in fewer sweeps: 4.1 -> 2.0 us per 5x5 spectrum, the same spectrum to 2e-13 relative
// (docs/performance.md, "Modes"). It is what numpy.linalg.eigvals does through dgeev.
Matrix5d Balanced(Matrix5d a) {
  const int n = 5;
  int ilo = 0, ihi = 0, info = 0;
  double scale[5];
  dgebal_("S", &n, a.data(), &n, &ilo, &ihi, scale, &info, 1);
  return a;  // info != 0 only for an illegal argument, impossible here
}

// An eigenvalue counts as real when its imaginary part is this small relative to its magnitude:
// EigenSolver returns exact zeros for real roots of a real matrix, so any threshold well below the
// smallest physical |Im λ| works; this one guards against a pair that has just split.
constexpr double kRealRootRelativeTolerance = 1e-12;

bool IsReal(std::complex<double> z) {
  return std::abs(z.imag()) <= kRealRootRelativeTolerance * std::max(1.0, std::abs(z));
}

// The eigenvalues of a balanced 5×5 by LAPACK: dgehd2 then dlahqr (eigenvalues only). false when the
// QR did not converge (info > 0), then Eigen's solver is used.
bool LapackEigenvalues(Matrix5d a, std::array<std::complex<double>, 5>& values) {
  const int n = 5, one = 1, no = 0;
  int info = 0;
  double tau[4], work[5], wr[5], wi[5], z[1];
  dgehd2_(&n, &one, &n, a.data(), &n, tau, work, &info);
  for (int j = 0; j < 5; ++j)
    for (int i = j + 2; i < 5; ++i) a(i, j) = 0.0;  // dgehd2 leaves its reflectors there
  dlahqr_(&no, &no, &n, &one, &n, a.data(), &n, wr, wi, &one, &n, z, &one, &info);
  if (info != 0) return false;
  for (int i = 0; i < 5; ++i) values[static_cast<std::size_t>(i)] = {wr[i], wi[i]};
  return true;
}

}  // namespace

std::array<std::complex<double>, 5> Eigenvalues5(const Matrix5d& A, EigenvalueSolver solver) {
  std::array<std::complex<double>, 5> values;
  const Matrix5d balanced = Balanced(A);
  if (solver == EigenvalueSolver::kLapack && LapackEigenvalues(balanced, values)) return values;
  const Eigen::EigenSolver<Matrix5d> eigen(balanced, /*computeEigenvectors=*/false);
  for (int i = 0; i < 5; ++i) values[static_cast<std::size_t>(i)] = eigen.eigenvalues()[i];
  return values;
}

std::string_view ToString(ModeClassification classification) {
  switch (classification) {
    case ModeClassification::kStandard: return "standard";
    case ModeClassification::kPhugoidSplit: return "phugoid_split";
    case ModeClassification::kShortPeriodSplit: return "short_period_split";
    case ModeClassification::kAllReal: return "all_real";
  }
  GESWEEP_UNREACHABLE();
}

ModeProperties DescribeMode(std::complex<double> lambda) {
  ModeProperties mode;
  mode.oscillatory = !IsReal(lambda);
  if (!mode.oscillatory) lambda = {lambda.real(), 0.0};
  if (mode.oscillatory && lambda.imag() < 0) lambda = std::conj(lambda);
  mode.eigenvalue = lambda;
  mode.natural_frequency_radps = std::abs(lambda);
  mode.neutral = !mode.oscillatory && std::abs(lambda) <= kNeutralEigenvalueTolerance_per_s;
  mode.damping_ratio = mode.natural_frequency_radps > 0 ? -lambda.real() / mode.natural_frequency_radps
                                                        : std::numeric_limits<double>::quiet_NaN();
  if (mode.neutral) mode.damping_ratio = std::numeric_limits<double>::quiet_NaN();
  mode.period_s = mode.oscillatory ? 2.0 * std::numbers::pi / std::abs(lambda.imag())
                                   : std::numeric_limits<double>::infinity();
  mode.time_to_half_or_double_s = lambda.real() != 0.0 ? std::numbers::ln2 / std::abs(lambda.real())
                                                       : std::numeric_limits<double>::infinity();
  return mode;
}

ModalAnalysis AnalyzeModes(const Matrix5d& A, EigenvalueSolver solver) {
  ModalAnalysis result;
  if (!A.allFinite()) {
    result.finite = false;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    result.eigenvalues.fill({nan, nan});
    result.stability_margin_per_s = nan;
    return result;
  }
  const std::array<std::complex<double>, 5> values = Eigenvalues5(A, solver);

  std::vector<std::complex<double>> pairs;  // one representative (Im > 0) per complex pair
  std::vector<double> reals;
  for (int i = 0; i < 5; ++i) {
    const std::complex<double> z = values[i];
    if (IsReal(z)) {
      reals.push_back(z.real());
    } else if (z.imag() > 0) {
      pairs.push_back(z);
    }
  }
  // Real roots by descending magnitude; pairs by descending |Im λ|.
  std::sort(reals.begin(), reals.end(), [](double a, double b) { return std::abs(a) > std::abs(b); });
  std::sort(pairs.begin(), pairs.end(),
            [](auto a, auto b) { return std::abs(a.imag()) > std::abs(b.imag()); });

  auto put_pair = [&](int slot, std::complex<double> z) {
    result.eigenvalues[slot] = z;
    result.eigenvalues[slot + 1] = std::conj(z);
  };
  auto put_split = [&](int slot, double a, double b) {
    result.eigenvalues[slot] = std::max(a, b);
    result.eigenvalues[slot + 1] = std::min(a, b);
  };

  if (pairs.size() == 2 && reals.size() == 1) {
    result.classification = ModeClassification::kStandard;
    put_pair(0, pairs[0]);
    put_pair(2, pairs[1]);
    result.eigenvalues[4] = reals[0];
  } else if (pairs.size() == 1 && reals.size() == 3) {
    const bool pair_is_short_period = std::abs(pairs[0]) > std::abs(reals[0]);
    result.classification =
        pair_is_short_period ? ModeClassification::kPhugoidSplit : ModeClassification::kShortPeriodSplit;
    const int pair_slot = pair_is_short_period ? 0 : 2;
    const int split_slot = pair_is_short_period ? 2 : 0;
    put_pair(pair_slot, pairs[0]);
    put_split(split_slot, reals[0], reals[1]);
    result.eigenvalues[4] = reals[2];
  } else {
    GESWEEP_DEMAND(reals.size() == 5);
    result.classification = ModeClassification::kAllReal;
    put_split(0, reals[0], reals[1]);
    put_split(2, reals[2], reals[3]);
    result.eigenvalues[4] = reals[4];
  }

  result.short_period = DescribeMode(result.eigenvalues[0]);
  result.phugoid = DescribeMode(result.eigenvalues[2]);
  result.height = DescribeMode(result.eigenvalues[4]);

  double sigma = -std::numeric_limits<double>::infinity();
  for (const auto& z : result.eigenvalues) {
    const bool neutral = IsReal(z) && std::abs(z) <= kNeutralEigenvalueTolerance_per_s;
    if (!neutral) sigma = std::max(sigma, z.real());
  }
  result.stability_margin_per_s = sigma;
  result.stable = sigma < 0.0;
  return result;
}

double StabilityMargin(const LongitudinalModel& model, double height_m, double speed_mps) {
  return AnalyzeModes(model.StateMatrix(height_m, speed_mps)).stability_margin_per_s;
}

}  // namespace gesweep
