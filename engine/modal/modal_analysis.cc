#include "engine/modal/modal_analysis.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>

#include "engine/common/errors.h"

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

// |Im z| ≤ tolerance·max(1, |z|), compared in squares (no hypot: this runs ~10 times per analysis).
bool IsReal(std::complex<double> z) {
  const double im2 = z.imag() * z.imag();
  if (im2 == 0.0) return true;
  const double modulus2 = z.real() * z.real() + im2;
  if (!std::isfinite(modulus2)) return std::abs(z.imag()) <= kRealRootRelativeTolerance * std::abs(z);
  return im2 <= kRealRootRelativeTolerance * kRealRootRelativeTolerance * std::max(1.0, modulus2);
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

// Eigen's EigenSolver on dgebal's balanced A: the solver before issue 16, and the fallback.
std::array<std::complex<double>, 5> EigenSolverEigenvalues(const Matrix5d& A) {
  std::array<std::complex<double>, 5> values;
  const Eigen::EigenSolver<Matrix5d> eigen(Balanced(A), /*computeEigenvectors=*/false);
  for (int i = 0; i < 5; ++i) values[static_cast<std::size_t>(i)] = eigen.eigenvalues()[i];
  return values;
}

std::atomic<std::uint64_t> fixed_size_fallbacks{0};

}  // namespace

std::uint64_t FixedSizeSolverFallbacks() { return fixed_size_fallbacks.load(std::memory_order_relaxed); }

std::array<std::complex<double>, 5> Eigenvalues5(const Matrix5d& A, EigenvalueSolver solver,
                                                 EigenvalueReport* report, int max_iterations) {
  EigenvalueReport local;
  EigenvalueReport& r = report ? *report : local;
  r = EigenvalueReport{};
  switch (solver) {
    case EigenvalueSolver::kFixedSize: {
      const FrancisResult francis = BalancedFrancisEigenvalues5(A, max_iterations);
      r.iterations = francis.iterations;
      if (francis.converged) return francis.values;
      fixed_size_fallbacks.fetch_add(1, std::memory_order_relaxed);
      r.solver_fallback = true;
      return EigenSolverEigenvalues(A);
    }
    case EigenvalueSolver::kLapack: {
      std::array<std::complex<double>, 5> values;
      if (LapackEigenvalues(Balanced(A), values)) return values;
      r.solver_fallback = true;
      return EigenSolverEigenvalues(A);
    }
    case EigenvalueSolver::kEigen:
      return EigenSolverEigenvalues(A);
  }
  GESWEEP_DEMAND(false && "unknown EigenvalueSolver");
  return {};
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

namespace {

/// The roots of a spectrum in fixed storage (no allocation): the real ones by descending magnitude,
/// and one representative (Im > 0) per complex pair, by descending |Im λ|.
struct SortedRoots {
  std::array<std::complex<double>, 2> pair_storage;
  std::array<double, 5> real_storage;
  std::size_t pair_count = 0, real_count = 0;
  std::span<const double> reals() const { return {real_storage.data(), real_count}; }
  std::span<const std::complex<double>> pairs() const { return {pair_storage.data(), pair_count}; }
};

SortedRoots SortRoots(const std::array<std::complex<double>, 5>& values) {
  SortedRoots roots;
  auto& [pair_storage, real_storage, pair_count, real_count] = roots;
  for (const std::complex<double>& z : values) {
    if (IsReal(z)) {
      real_storage[real_count++] = z.real();
    } else if (z.imag() > 0 && pair_count < pair_storage.size()) {
      pair_storage[pair_count++] = z;
    }
  }
  // Insertion sorts of ≤ 5 entries, stable as std::stable_sort would be.
  for (std::size_t i = 1; i < real_count; ++i) {
    for (std::size_t j = i; j > 0 && std::abs(real_storage[j]) > std::abs(real_storage[j - 1]); --j) {
      std::swap(real_storage[j], real_storage[j - 1]);
    }
  }
  if (pair_count == 2 && std::abs(pair_storage[1].imag()) > std::abs(pair_storage[0].imag())) {
    std::swap(pair_storage[0], pair_storage[1]);
  }
  return roots;
}

/// The roots in result.eigenvalues' slots (short period 0–1, phugoid 2–3, height 4) and the
/// classification they make (AnalyzeModes' rule, modal_analysis.h).
void PlaceModes(const SortedRoots& roots, ModalAnalysis& result) {
  const std::span<const double> reals = roots.reals();
  const std::span<const std::complex<double>> pairs = roots.pairs();
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
}

/// σ, 1/s: the largest Re λ of the eigenvalues that are not neutral (−∞ when every one is).
double MarginOf(const std::array<std::complex<double>, 5>& eigenvalues) {
  double sigma = -std::numeric_limits<double>::infinity();
  for (const auto& z : eigenvalues) {
    const bool neutral = IsReal(z) && std::abs(z.real()) <= kNeutralEigenvalueTolerance_per_s &&
                         std::abs(z) <= kNeutralEigenvalueTolerance_per_s;
    if (!neutral) sigma = std::max(sigma, z.real());
  }
  return sigma;
}

}  // namespace

ModalAnalysis AnalyzeModes(const Matrix5d& A, EigenvalueSolver solver) {
  ModalAnalysis result;
  if (!A.allFinite()) {
    result.finite = false;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    result.eigenvalues.fill({nan, nan});
    result.stability_margin_per_s = nan;
    return result;
  }
  EigenvalueReport report;
  const std::array<std::complex<double>, 5> values = Eigenvalues5(A, solver, &report);
  result.solver_fallback = report.solver_fallback;
  PlaceModes(SortRoots(values), result);
  result.short_period = DescribeMode(result.eigenvalues[0]);
  result.phugoid = DescribeMode(result.eigenvalues[2]);
  result.height = DescribeMode(result.eigenvalues[4]);
  const double sigma = MarginOf(result.eigenvalues);
  result.stability_margin_per_s = sigma;
  result.stable = sigma < 0.0;
  return result;
}

double StabilityMargin(const LongitudinalModel& model, double height_m, double speed_mps) {
  return AnalyzeModes(model.StateMatrix(height_m, speed_mps)).stability_margin_per_s;
}

}  // namespace gesweep
