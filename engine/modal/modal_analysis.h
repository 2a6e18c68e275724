#pragma once
/// Eigen-analysis of the 5-state model with mode identification and the stability margin
/// (docs/model.md §6).

#include <array>
#include <complex>
#include <cstdint>
#include <string_view>

#include "engine/common/describe.h"
#include "engine/common/enum_names.h"
#include "engine/dynamics/longitudinal_model.h"
#include "engine/modal/eigenvalues5.h"

namespace gesweep {

/// A real eigenvalue of magnitude at most this is the neutral free-flight height mode (docs/model.md §6).
inline constexpr double kNeutralEigenvalueTolerance_per_s = 1e-9;

/// Properties of one mode, from its representative eigenvalue λ (Im λ ≥ 0 for a pair).
struct ModeProperties {
  std::complex<double> eigenvalue;
  double natural_frequency_radps = 0;  ///< ωn = |λ|
  double damping_ratio = 0;            ///< ζ = −Re λ/|λ| (NaN for a neutral root)
  double period_s = 0;                 ///< 2π/|Im λ|; +∞ for a real root
  /// ln2/|Re λ|: time to half amplitude when Re λ < 0, to double amplitude when Re λ > 0; +∞ when 0.
  double time_to_half_or_double_s = 0;
  bool oscillatory = false;  ///< a complex pair
  bool neutral = false;      ///< a real root with |λ| ≤ kNeutralEigenvalueTolerance_per_s
};

/// How the eigenvalues were assigned to modes.
enum class ModeClassification {
  kStandard,          ///< two complex pairs and one real root
  kPhugoidSplit,      ///< the phugoid pair split into two real roots
  kShortPeriodSplit,  ///< the short-period pair split into two real roots
  kAllReal,           ///< both pairs split; assigned by magnitude
};
GESWEEP_ENUM_NAMES(ModeClassification, {kStandard, "standard"}, {kPhugoidSplit, "phugoid_split"},
                   {kShortPeriodSplit, "short_period_split"}, {kAllReal, "all_real"});

/// The settings of an eigen-analysis a person asks for (`gesweep modes`, at a list of heights given
/// apart); in a sweep the run's speed_mps is a parameter instead.
struct ModesOptions {
  double speed_mps = 0;  ///< reference speed u0, m/s

  template <class V>
  void Describe(V& v) {
    v(Field("speed_mps", &speed_mps)
          .Unit("m/s")
          .Limit("speed_mps")
          .CommandLineOnly()
          .Doc("Reference speed u0, m/s"));
  }
};

/// The result of one eigen-analysis.
struct ModalAnalysis {
  /// Ordered: short period (two), phugoid (two), height (one). A pair is written with Im > 0 first;
  /// a split pair with the larger real part first.
  std::array<std::complex<double>, 5> eigenvalues;
  ModeProperties short_period, phugoid, height;
  ModeClassification classification = ModeClassification::kStandard;
  /// σ = the largest Re λ, the neutral height root left out (docs/model.md §6).
  double stability_margin_per_s = 0;
  bool stable = false;  ///< σ < 0
  bool finite = true;   ///< false when A had a non-finite entry (then nothing else is meaningful)
  /// The fixed-size QR did not converge; Eigen's EigenSolver computed the eigenvalues (counted by
  /// FixedSizeSolverFallbacks()).
  bool solver_fallback = false;
};

/// Which QR computes the eigenvalues.
enum class EigenvalueSolver {
  /// The fixed-size 5×5 kernel (engine/modal/eigenvalues5.h): dgebal's balancing, Hessenberg
  /// reduction and dlahqr's Francis double-shift QR for n = 5 (default). Where it does not converge
  /// within kFrancisMaxIterations sweeps per block, kEigen computes the eigenvalues instead, and the
  /// result says so (ModalAnalysis::solver_fallback, FixedSizeSolverFallbacks()).
  kFixedSize,
  /// LAPACK's dgebal, then Eigen's EigenSolver: the solver before issue 16, kept for comparison.
  kEigen,
  /// dgebal, then LAPACK dgehd2 + dlahqr, the double-shift QR that dhseqr uses at this size: the same
  /// spectrum, measured 1.9 times slower than kEigen at 5×5 (docs/performance.md, "Modes").
  kLapack,
};

/// How Eigenvalues5 went.
struct EigenvalueReport {
  /// kFixedSize did not converge and kEigen computed the eigenvalues (kLapack: dlahqr failed, ditto).
  bool solver_fallback = false;
  int iterations = 0;  ///< kFixedSize: double-shift sweeps
};

/// The five eigenvalues of A (balanced first), in the solver's order. A must be finite.
/// `max_iterations` bounds kFixedSize's sweeps per block (tests of the fallback set it low).
std::array<std::complex<double>, 5> Eigenvalues5(const Matrix5d& A,
                                                 EigenvalueSolver solver = EigenvalueSolver::kFixedSize,
                                                 EigenvalueReport* report = nullptr,
                                                 int max_iterations = kFrancisMaxIterations);

/// How many times, in this process, kFixedSize fell back to kEigen (all threads; never reset).
std::uint64_t FixedSizeSolverFallbacks();

/// Eigenvalues of A (any real 5×5), modes identified by docs/model.md §6. When a pair has split, the
/// remaining complex pair is the short period if its |λ| exceeds every real root's, otherwise the
/// phugoid; the split mode takes the two real roots of largest magnitude and the height mode the
/// remaining one. With no pair left, roots are assigned by magnitude.
ModalAnalysis AnalyzeModes(const Matrix5d& A, EigenvalueSolver solver = EigenvalueSolver::kFixedSize);

/// Properties of one eigenvalue (docs/model.md §6).
ModeProperties DescribeMode(std::complex<double> eigenvalue);

/// σ(H, u) of a model: AnalyzeModes(model.StateMatrix(H, u)).stability_margin_per_s.
double StabilityMargin(const LongitudinalModel& model, double height_m, double speed_mps);

}  // namespace gesweep
