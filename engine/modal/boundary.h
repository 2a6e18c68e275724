#pragma once
/// The stability boundary H*(u0) of docs/model.md §6: the largest height at which the airplane
/// changes from unstable (just below) to stable (just above).
///
/// The default finder (BoundaryMethod::kHurwitz) enumerates every crossing of the imaginary axis by an
/// eigenvalue in the range and certifies the enumeration (docs/model.md, "The boundary by the Hurwitz
/// criterion"): an eigenvalue reaches the axis only where the Hurwitz determinant Δ₄ (a complex pair,
/// a Hopf crossing) or a₅ = det(−A) (a real root through 0) of det(sI − A(H)) vanishes; on each table
/// segment both are polynomials in H of known degree (once ρ(H) is replaced by its quadratic
/// interpolant, within a stated bound), whose real roots Descartes' rule on the Bernstein basis
/// isolates with certainty. The former sampled search (BoundaryMethod::kSampled: σ at a few hundred
/// heights, TOMS 748 at each sign change) stays for comparison.

#include <cmath>
#include <complex>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "engine/common/describe.h"
#include "engine/common/enum_names.h"
#include "engine/common/errors.h"
#include "engine/dynamics/longitudinal_model.h"
#include "engine/modal/modal_analysis.h"

namespace gesweep {

/// How the boundary is searched.
enum class BoundaryMethod {
  kHurwitz,  ///< certified enumeration of the roots of Δ₄ and a₅ per segment (default)
  kSampled,  ///< the former search: σ sampled per segment, TOMS 748 at each sign change
};
GESWEEP_ENUM_NAMES(BoundaryMethod, {kHurwitz, "hurwitz"}, {kSampled, "sampled"});

/// Where and how finely to look.
struct BoundaryOptions {
  /// Lowest height scanned, m; NaN: the aircraft's wheel-contact height.
  double lower_height_m = std::numeric_limits<double>::quiet_NaN();
  /// Highest height scanned, m; NaN: the last finite table row (above it the coefficients are the
  /// free-flight row and only ρ(H) varies).
  double upper_height_m = std::numeric_limits<double>::quiet_NaN();
  BoundaryMethod method = BoundaryMethod::kHurwitz;
  /// kSampled only: sample points inside each table segment (besides the table heights themselves).
  int samples_per_segment = 24;
  /// Width of the final bracket, m. kSampled stops there; kHurwitz refines each root to rounding
  /// (about 1e-12 m) and reports the bracket it reached, never wider than this.
  double tolerance_m = 1e-4;
  /// The eigen-solver of every eigen-analysis (kSampled: σ at each sample; kHurwitz: the one that
  /// names the crossing mode). kEigen reproduces the searches as they were before the fixed-size
  /// kernel, for comparison (docs/performance.md).
  EigenvalueSolver eigenvalue_solver = EigenvalueSolver::kFixedSize;

  /// The settings a person gives (engine/common/describe.h): the flags of `gesweep boundary`
  /// (samples_per_segment, a study key of [analyses.boundary], is not a flag). The eigen-solver is a
  /// comparison switch for benchmarks, not a setting.
  template <class V>
  void Describe(V& v) {
    v(Field("method", &method)
          .Doc("hurwitz (every crossing of the imaginary axis, certified) or sampled (the former search, "
               "sigma sampled per table segment; for comparison)"));
    v(Field("lower_height_m", &lower_height_m)
          .Automatic()
          .Unit("m")
          .Limit("height_m")
          .Doc("Lowest height scanned, m (default: the aircraft's wheel-contact height)"));
    v(Field("upper_height_m", &upper_height_m)
          .Automatic()
          .Unit("m")
          .Limit("height_m")
          .Doc("Highest height scanned, m (default: the aircraft's last finite table height)"));
    v(Field("tolerance_m", &tolerance_m)
          .Unit("m")
          .Limit("boundary.tolerance_m")
          .Doc("Width of the final bracket of each crossing, m (hurwitz refines to rounding within it)"));
    v(Field("samples_per_segment", &samples_per_segment)
          .StudyOnly()
          .Doc("Method sampled: sample heights inside each table segment"));
  }
};

/// The checks of BoundaryOptions that depend on the aircraft or on two fields (each field's own
/// range is its limits-table entry, CheckFieldRanges): the scanned range starts at or above the
/// wheel-contact height and is not empty. Messages name the fields by their keys; `source` is the
/// file or "command line".
inline void ValidateBoundaryOptions(const BoundaryOptions& options, const Aircraft& aircraft,
                                    const std::string& source) {
  const double lower =
      std::isnan(options.lower_height_m) ? aircraft.wheel_contact_height_m : options.lower_height_m;
  const double upper =
      std::isnan(options.upper_height_m) ? aircraft.table_heights_m.back() : options.upper_height_m;
  const std::string lower_key(KeyOf(options, &options.lower_height_m));
  const std::string upper_key(KeyOf(options, &options.upper_height_m));
  if (lower < aircraft.wheel_contact_height_m) {
    throw InputError(source, lower_key, ShortNumber(lower),
                     "expected a height >= the wheel-contact height " +
                         ShortNumber(aircraft.wheel_contact_height_m) + " m of " + aircraft.source_path);
  }
  if (!(upper > lower)) {
    if (std::isnan(options.upper_height_m)) {
      throw InputError(source, lower_key, ShortNumber(lower),
                       "expected less than " + upper_key + " = " + ShortNumber(upper) +
                           " m (by default the last finite table height of " + aircraft.source_path + ")");
    }
    throw InputError(source, upper_key, ShortNumber(upper),
                     "expected more than " + lower_key + " = " + ShortNumber(lower) + " m");
  }
}

/// What crosses the imaginary axis.
enum class CrossingKind {
  kHopf,           ///< a complex pair ±iω (Δ₄ = 0 with ω² > 0)
  kReal,           ///< a real root through 0 (a₅ = 0)
  kDiscontinuity,  ///< stability changes across the jump of the table at its last row (no root)
  kSigma,          ///< a sign change of σ found by BoundaryMethod::kSampled (not classified)
};
GESWEEP_ENUM_NAMES(CrossingKind, {kHopf, "hopf"}, {kReal, "real"}, {kDiscontinuity, "table_row"},
                   {kSigma, "sigma"});

/// One crossing of the imaginary axis along height.
struct BoundaryCrossing {
  double height_m = 0;
  double height_over_span = 0;
  CrossingKind kind = CrossingKind::kSigma;
  /// The mode that crosses, from one eigen-analysis at the root: "short_period", "phugoid" or
  /// "height" (empty for kDiscontinuity and kSigma).
  std::string mode;
  /// The crossing eigenvalue at the root (Im ≥ 0), 1/s: ≈ ±iω for kHopf, ≈ 0 for kReal.
  std::complex<double> eigenvalue;
  /// dλ/dH of the crossing eigenvalue, 1/(s·m), from the characteristic polynomial (NaN if unknown).
  std::complex<double> eigenvalue_height_derivative{std::numeric_limits<double>::quiet_NaN(), 0.0};
  /// The crossing mode is stable above the root (Re dλ/dH < 0).
  bool mode_stable_above = false;
  /// The airplane (every mode) is stable just above / just below the crossing.
  bool stable_above = false;
  bool stable_below = false;
  /// Width of the final bracket of the root, m.
  double bracket_width_m = 0;
  /// d(criterion)/dH at the root (Δ₄, Δ₃, a₅ or a₄ per metre; NaN for kSigma, kDiscontinuity).
  double criterion_height_derivative = std::numeric_limits<double>::quiet_NaN();
  /// The root lies in a segment where A has an exactly neutral root (a₅ ≡ 0: the h-derivatives off or
  /// zero, free flight): the criteria were those of the remaining quartic (Δ₃, a₄).
  bool deflated = false;
};
/// The former name.
using SigmaCrossing = BoundaryCrossing;

/// The boundary at one speed.
struct BoundaryResult {
  double speed_mps = 0;
  /// H*: the highest crossing that is unstable below and stable above; nullopt when there is none.
  std::optional<double> height_m;
  std::optional<double> height_over_span;
  /// Every crossing found in the range, highest first (H* among them). kHurwitz: of any mode, also
  /// where another mode keeps the airplane unstable; kSampled: the sign changes of σ.
  std::vector<BoundaryCrossing> crossings;
  /// Why there is no boundary (empty when there is one).
  std::string reason;
  double lower_height_m = 0, upper_height_m = 0;  ///< the range scanned
  BoundaryMethod method = BoundaryMethod::kHurwitz;
  /// kHurwitz: true when every root of the criteria in the range was isolated (certificate below).
  /// kSampled: always false (a pair of crossings between two samples is missed without a word).
  bool certified = false;
  /// What the certificate covers, or why it is missing (docs/model.md).
  std::string certificate;
  /// Relative bound on |ρ − ρ̂|/ρ over the range, ρ̂ the per-segment quadratic interpolant of ρ(H).
  double density_interpolation_bound = 0;
  int segments = 0;                ///< table segments searched (kHurwitz)
  int margin_evaluations = 0;      ///< full eigen-analyses spent
  int polynomial_evaluations = 0;  ///< characteristic polynomials spent (kHurwitz)
};

/// Finds H*(u0). Non-finite A anywhere (e.g. a density outside the ISA range) gives no boundary and
/// a reason. Precondition: upper > lower.
BoundaryResult FindBoundary(const LongitudinalModel& model, double speed_mps,
                            const BoundaryOptions& options = {});

// --- The engine of the Hurwitz finder, on any family of 5×5 matrices (also for tests) ---

/// One piece of a matrix family A(H), H ∈ [lower, upper], on which every coefficient aₖ of
/// det(sI − A(H)) is a polynomial in H of degree ≤ coefficient_degrees[k].
struct MatrixSegment {
  double lower_height_m = 0, upper_height_m = 0;
  std::array<int, 6> coefficient_degrees{};  ///< index 1…5; bounds of deg aₖ
  /// A whose aₖ are exactly those polynomials (for an aircraft: ρ replaced by ρ̂).
  std::function<Matrix5d(double)> polynomial_matrix;
  /// The exact A (roots are refined on it); may be the same function.
  std::function<Matrix5d(double)> exact_matrix;
  /// Column 4 of A is identically 0 on the segment (a₅ ≡ 0, the neutral height root).
  bool deflated = false;
  /// Column 4 of A is 0 at this end (a₅ = 0 exactly there, e.g. at a table row where CLh = CMh =
  /// CDh = 0): the root is divided out of a₅ and the end is treated as a root of the real criterion.
  bool real_root_at_lower = false, real_root_at_upper = false;
};

/// The result of CrossingSearch.
struct CrossingSearchResult {
  std::vector<BoundaryCrossing> crossings;  ///< ascending in height (the caller reorders)
  bool certified = true;
  std::string uncertified_reason;  ///< empty when certified
  int polynomial_evaluations = 0;
  int eigen_analyses = 0;
  bool finite = true;  ///< false when A was not finite somewhere: nothing else is meaningful
  std::string non_finite_reason;
  /// Stability of the airplane at the lowest and highest end of the range (just inside).
  bool stable_at_lower = false, stable_at_upper = false;
};

/// Every crossing of the imaginary axis by an eigenvalue of A(H) over consecutive segments (ascending,
/// each starting where the previous one ends; A may jump at a segment boundary). `wingspan_m` only
/// scales height_over_span.
CrossingSearchResult CrossingSearch(const std::vector<MatrixSegment>& segments, double wingspan_m,
                                    EigenvalueSolver solver = EigenvalueSolver::kFixedSize);

/// The result of SampledCrossingSearch.
struct SampledSearchResult {
  std::vector<BoundaryCrossing> crossings;  ///< ascending, kind kSigma
  std::vector<double> margins;              ///< σ at every sample
  int margin_evaluations = 0;
  bool finite = true;
  std::string non_finite_reason;
};

/// The former search (BoundaryMethod::kSampled) on any family: σ of A(H) at `samples_per_segment`
/// points inside each interval between consecutive `knots` and at the knots, then TOMS 748 to
/// `tolerance_m` at each sign change. A pair of sign changes between two samples is not seen.
SampledSearchResult SampledCrossingSearch(const std::function<Matrix5d(double)>& matrix,
                                          const std::vector<double>& knots, int samples_per_segment,
                                          double tolerance_m,
                                          EigenvalueSolver solver = EigenvalueSolver::kFixedSize);

}  // namespace gesweep
