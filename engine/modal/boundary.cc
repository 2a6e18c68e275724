#include "engine/modal/boundary.h"

#include <algorithm>
#include <boost/math/tools/toms748_solve.hpp>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <sstream>

#include "engine/aircraft/atmosphere.h"
#include "engine/common/errors.h"
#include "engine/modal/bernstein.h"
#include "engine/modal/hurwitz.h"
#include "engine/modal/modal_analysis.h"

namespace gesweep {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A Bernstein coefficient of a criterion within this fraction of the scale of its terms may have
// either sign: the rounding of the characteristic coefficients (about 1e-15 of their terms) and of
// the Chebyshev fit, with a safety factor of 1000.
constexpr double kRoundingAllowance = 1e-12;
// The fitted polynomial must reproduce the exact criterion (true ρ, a point that is not a node) to
// this fraction of the terms' scale; else the degree bound or the ρ interpolation is wrong there.
constexpr double kFaithfulness = 1e-9;
// A coefficient's Chebyshev tail beyond its degree bound must be rounding: this fraction of its scale
// (plus kFaithfulness of the largest coefficient's scale, for coefficients that are themselves tiny).
constexpr double kTailTolerance = 1e-9;
// Where the criteria vanish at a table row, the signs just inside the two segments are taken this
// fraction of each segment's length away from it.
constexpr double kKnotOffset = 0x1p-24;
std::string FormatMetres(double value) {
  std::ostringstream out;
  out.precision(7);
  out << value << " m";
  return out.str();
}

// ---------------------------------------------------------------------------------------------
// The former sampled search (BoundaryMethod::kSampled), unchanged but for the result's new fields.

void SampledSearch(const LongitudinalModel& model, double speed_mps, const BoundaryOptions& options,
                   BoundaryResult& result, std::vector<double>& margins) {
  std::vector<double> knots{result.lower_height_m};
  for (double h : model.aircraft().table_heights_m) {
    if (h > result.lower_height_m && h < result.upper_height_m) knots.push_back(h);
  }
  knots.push_back(result.upper_height_m);
  SampledSearchResult search =
      SampledCrossingSearch([&](double h) { return model.StateMatrix(h, speed_mps); }, knots,
                            options.samples_per_segment, options.tolerance_m, options.eigenvalue_solver);
  result.margin_evaluations = search.margin_evaluations;
  if (!search.finite) {
    result.reason = search.non_finite_reason;
    return;
  }
  margins = std::move(search.margins);
  result.crossings.assign(search.crossings.rbegin(), search.crossings.rend());
  result.certificate = "none: sigma sampled at " + std::to_string(margins.size()) +
                       " heights; a pair of crossings between two samples is not seen";
}

// ---------------------------------------------------------------------------------------------
// The Hurwitz search.

// The criteria of one segment as polynomials in t ∈ [0, 1] (H = lower + t·(upper − lower)).
struct SegmentPolynomials {
  std::array<BernsteinPolynomial, 6> a;  // a[1..5]
  BernsteinPolynomial hopf, real;        // Δ₄ and a₅, or Δ₃ and a₄ when deflated
  double hopf_scale = 0, real_scale = 0;
  std::array<double, 6> scale{};  // of each aₖ: its largest Bernstein coefficient, floored at rounding
  bool hopf_excluded = false;     // interval arithmetic showed Δ has no root here
  bool hopf_built = false;
};

// A closed interval, for the quick exclusion of a segment.
struct Range {
  double lo = 0, hi = 0;
  static Range Of(const BernsteinPolynomial& p) {
    Range r{p.coefficient(0), p.coefficient(0)};
    for (int k = 1; k <= p.degree(); ++k) {
      r.lo = std::min(r.lo, p.coefficient(k));
      r.hi = std::max(r.hi, p.coefficient(k));
    }
    return r;
  }
  friend Range operator*(Range x, Range y) {
    const double a = x.lo * y.lo, b = x.lo * y.hi, c = x.hi * y.lo, d = x.hi * y.hi;
    return {std::min({a, b, c, d}), std::max({a, b, c, d})};
  }
  friend Range operator-(Range x, Range y) { return {x.lo - y.hi, x.hi - y.lo}; }
  Range Squared() const {
    if (lo >= 0) return {lo * lo, hi * hi};
    if (hi <= 0) return {hi * hi, lo * lo};
    return {0.0, std::max(lo * lo, hi * hi)};
  }
  bool ExcludesZero(double margin) const { return lo > margin || hi < -margin; }
};

double HopfCriterion(const CharacteristicCoefficients& a, bool deflated) {
  return deflated ? HurwitzDelta3(a) : HurwitzDelta4(a);
}
double RealCriterion(const CharacteristicCoefficients& a, bool deflated) { return deflated ? a[4] : a[5]; }
bool StableBy(const CharacteristicCoefficients& a, bool deflated) {
  return deflated ? DeflatedHurwitzStable(a) : HurwitzStable(a);
}

struct Candidate {
  double lower_m, upper_m;  // bracket of the root
  bool hopf;
  std::size_t segment;
  bool certified;
  bool undeflated = false;  // evaluate Δ₄ even on a deflated segment (a root at a row between the two)
};

class Search {
 public:
  Search(const std::vector<MatrixSegment>& segments, double wingspan_m, EigenvalueSolver solver)
      : segments_(segments), wingspan_m_(wingspan_m), solver_(solver) {}

  /// The crossings of the segments' criteria, each confirmed on the exact model, ascending, with the
  /// stability on either side; the result so far when a segment's matrix is not finite.
  CrossingSearchResult Run() {
    polynomials_.resize(segments_.size());
    lower_zone_.resize(segments_.size());
    upper_zone_.resize(segments_.size());
    std::vector<Candidate> candidates;
    for (std::size_t s = 0; s < segments_.size(); ++s) {
      if (!BuildPolynomials(s)) return result_;
      IsolateSegmentRoots(s, candidates);
    }
    CheckZoneWidths();
    AddRowCandidates(candidates);
    for (const Candidate& candidate : candidates) Confirm(candidate);
    std::sort(result_.crossings.begin(), result_.crossings.end(),
              [](const auto& x, const auto& y) { return x.height_m < y.height_m; });
    AssignStability();
    return result_;
  }

 private:
  double Length(std::size_t s) const { return segments_[s].upper_height_m - segments_[s].lower_height_m; }
  double HeightAt(std::size_t s, double t) const { return segments_[s].lower_height_m + t * Length(s); }
  std::string CriterionName(bool hopf, std::size_t s) const {
    if (segments_[s].deflated) return hopf ? "Delta3" : "a4";
    return hopf ? "Delta4" : "a5";
  }
  void Uncertify(const std::string& why) {
    if (result_.certified) result_.uncertified_reason = why;
    result_.certified = false;
  }
  bool Continuous(std::size_t s) const {
    const double knot = segments_[s].upper_height_m;
    const Matrix5d below = segments_[s].exact_matrix(knot), above = segments_[s + 1].exact_matrix(knot);
    return (below - above).cwiseAbs().maxCoeff() <= 1e-12 * std::max(1.0, below.cwiseAbs().maxCoeff());
  }

  /// The roots of segment s's two criteria (Hopf, real) isolated on its polynomials: a candidate per
  /// root interval inside the segment; one at an end where the criterion is ~0 widens that end's zone
  /// instead (decided with the neighbouring segment). An unresolved cluster uncertifies.
  void IsolateSegmentRoots(std::size_t s, std::vector<Candidate>& candidates) {
    for (int c = 0; c < 2; ++c) {
      const bool hopf = c == 0;
      const SegmentPolynomials& p = polynomials_[s];
      lower_zone_[s][c] = (!hopf && segments_[s].real_root_at_lower) ? 0.0 : -1.0;
      upper_zone_[s][c] = (!hopf && segments_[s].real_root_at_upper) ? 1.0 : -1.0;
      if (hopf && p.hopf_excluded) continue;
      const BernsteinPolynomial& poly = hopf ? p.hopf : p.real;
      const double allowance = kRoundingAllowance * (hopf ? p.hopf_scale : p.real_scale);
      const RootIsolation isolation = IsolateRoots(poly, allowance);
      for (const RootInterval& interval : isolation.intervals) {
        if (interval.lower_t == 0.0 && isolation.sign_at_lower == 0) {
          lower_zone_[s][c] = interval.upper_t;  // decided with the segment below
          continue;
        }
        if (interval.upper_t == 1.0 && isolation.sign_at_upper == 0) {
          upper_zone_[s][c] = interval.lower_t;  // decided with the segment above
          continue;
        }
        if (!interval.certified) {
          Uncertify("an unresolved cluster of roots of " + CriterionName(hopf, s) + " within " +
                    FormatMetres((interval.upper_t - interval.lower_t) * Length(s)) +
                    " of H = " + FormatMetres(HeightAt(s, interval.lower_t)) +
                    (interval.sign_change ? " (an odd number: one crossing reported)"
                                          : " (an even number: a tangency or a close pair, none reported)"));
          if (!interval.sign_change) continue;
        }
        candidates.push_back(
            {HeightAt(s, interval.lower_t), HeightAt(s, interval.upper_t), hopf, s, interval.certified});
      }
    }
  }

  /// Where a criterion is ~0 at a table row or an end of the range, the region the isolation left
  /// undecided there (its zone) is decided by the signs of the exact criterion at its two sides (an
  /// odd number of roots when they differ; AddRowCandidates). Wider than kKnotOffset, a zone may hide
  /// an even number: not certified.
  void CheckZoneWidths() {
    for (std::size_t s = 0; s < segments_.size(); ++s) {
      for (int c = 0; c < 2; ++c) {
        if (lower_zone_[s][c] >= 0) CheckZoneWidth(s, c, lower_zone_[s][c], segments_[s].lower_height_m);
        if (upper_zone_[s][c] >= 0)
          CheckZoneWidth(s, c, 1.0 - upper_zone_[s][c], segments_[s].upper_height_m);
      }
    }
  }
  /// Uncertifies when criterion c's zone of segment s at H = end_m (m), width_t of the segment's
  /// length, is wider than kKnotOffset.
  void CheckZoneWidth(std::size_t s, int c, double width_t, double end_m) {
    if (width_t > kKnotOffset * 1.0000001) {
      Uncertify(CriterionName(c == 0, s) + " is indistinguishable from 0 within " +
                FormatMetres(width_t * Length(s)) + " of H = " + FormatMetres(end_m) +
                "; a close pair of crossings there cannot be excluded");
    }
  }

  /// A candidate at each table row where a criterion is ~0 and the exact criterion has opposite signs
  /// just outside the zones of the two segments (the model continuous across the row).
  void AddRowCandidates(std::vector<Candidate>& candidates) {
    for (std::size_t s = 0; s + 1 < segments_.size(); ++s) {
      int continuous = -1;  // Continuous(s), evaluated where needed (two exact matrices)
      for (int c = 0; c < 2; ++c) {
        if (upper_zone_[s][c] < 0 && lower_zone_[s + 1][c] < 0) continue;
        if (continuous < 0) continuous = Continuous(s) ? 1 : 0;
        if (continuous == 0) break;
        const bool hopf = c == 0;
        // Where a₅ becomes identically 0 at the row, the neutral root arrives there and stays (the
        // stability comparison reports it); Δ₄ = a₄Δ₃ continues Δ₃ across the row.
        const bool mixed = segments_[s].deflated != segments_[s + 1].deflated;
        if (mixed && !hopf) continue;
        const double below_t = std::min(upper_zone_[s][c] < 0 ? 1.0 : upper_zone_[s][c], 1.0 - kKnotOffset);
        const double above_t = std::max(lower_zone_[s + 1][c] < 0 ? 0.0 : lower_zone_[s + 1][c], kKnotOffset);
        const double below = HeightAt(s, below_t), above = HeightAt(s + 1, above_t);
        const double fb = ExactCriterion(s, below, hopf, mixed),
                     fa = ExactCriterion(s + 1, above, hopf, mixed);
        if ((fb < 0) != (fa < 0) && fb != 0 && fa != 0)
          candidates.push_back({below, above, hopf, s, true, mixed});
      }
    }
  }

  CharacteristicCoefficients Exact(std::size_t s, double height_m) {
    ++result_.polynomial_evaluations;
    const Matrix5d A = segments_[s].exact_matrix(height_m);
    if (!A.allFinite()) {
      CharacteristicCoefficients nan;
      nan.fill(kNaN);
      return nan;
    }
    return CharacteristicPolynomial(A);
  }
  double ExactCriterion(std::size_t s, double height_m, bool hopf, bool undeflated = false) {
    const CharacteristicCoefficients a = Exact(s, height_m);
    const bool deflated = segments_[s].deflated && !undeflated;
    return hopf ? HopfCriterion(a, deflated) : RealCriterion(a, deflated);
  }

  // aₖ(H), k = 1..5, at the Chebyshev nodes of a segment: [k][node].
  using CoefficientSamples = std::array<std::array<double, BernsteinPolynomial::kMaxDegree + 2>, 6>;

  // The Bernstein forms of segment s's characteristic coefficients and of its stability criteria,
  // each checked (degree bound, faithfulness to the exact model); false when the matrix is not finite.
  bool BuildPolynomials(std::size_t s) {
    const MatrixSegment& segment = segments_[s];
    int degree = 0;
    for (int k = 1; k <= 5; ++k)
      degree = std::max(degree, segment.coefficient_degrees[static_cast<std::size_t>(k)]);
    // One node more than the degree needs: the tail of every coefficient checks its degree bound.
    const int m = degree + 2;
    CoefficientSamples values;
    double entry_scale = 0;
    if (!SampleCoefficients(s, m, values, entry_scale)) return false;
    FitCoefficients(s, m, values, entry_scale);
    SetCriteria(s);
    return true;
  }

  // aₖ(H), k = 1..5, at the m Chebyshev nodes of segment s (values[k][i]), and the largest |entry| of
  // A there; false (and the reason) when A is not finite at a node.
  bool SampleCoefficients(std::size_t s, int m, CoefficientSamples& values, double& entry_scale) {
    const MatrixSegment& segment = segments_[s];
    const std::vector<double>& nodes = Nodes(m);
    for (int i = 0; i < m; ++i) {
      const double h = HeightAt(s, nodes[static_cast<std::size_t>(i)]);
      const Matrix5d A = segment.polynomial_matrix(h);
      ++result_.polynomial_evaluations;
      // One pass for both: the largest |entry| is NaN or ∞ exactly when some entry is not finite.
      const double largest = A.cwiseAbs().maxCoeff<Eigen::PropagateNaN>();
      if (!std::isfinite(largest)) {
        result_.finite = false;
        result_.non_finite_reason = "the state matrix is not finite at H = " + FormatMetres(h);
        return false;
      }
      entry_scale = std::max(entry_scale, largest);
      const CharacteristicCoefficients a = CharacteristicPolynomial(A);
      for (int k = 1; k <= 5; ++k)
        values[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)] = a[static_cast<std::size_t>(k)];
    }
    return true;
  }

  // The Bernstein form of each aₖ from its samples, its degree bound checked by the Chebyshev tail and
  // the fit checked against the exact model at a point that is no node; either failing uncertifies.
  void FitCoefficients(std::size_t s, int m, const CoefficientSamples& values, double entry_scale) {
    const MatrixSegment& segment = segments_[s];
    SegmentPolynomials& p = polynomials_[s];
    std::array<double, 6> scale{};
    double entry_power = 1.0;
    for (int k = 1; k <= 5; ++k) {
      double tail = 0;
      const int dk = segment.coefficient_degrees[static_cast<std::size_t>(k)];
      p.a[static_cast<std::size_t>(k)] =
          BernsteinPolynomial::FromChebyshevSamples(values[static_cast<std::size_t>(k)].data(), m, dk, &tail);
      scale[static_cast<std::size_t>(k)] = p.a[static_cast<std::size_t>(k)].MaxAbsCoefficient();
      // A coefficient is a sum of products of k entries: its rounding is relative to entry_scale^k.
      entry_power *= entry_scale;
      const double floor = 1e-14 * entry_power;
      if (tail > kTailTolerance * scale[static_cast<std::size_t>(k)] + floor) {
        Uncertify("segment " + FormatMetres(segment.lower_height_m) + " to " +
                  FormatMetres(segment.upper_height_m) + ": a" + std::to_string(k) +
                  " is not a polynomial of degree " + std::to_string(dk) + " (Chebyshev tail " +
                  std::to_string(tail) + ")");
      }
      scale[static_cast<std::size_t>(k)] = std::max(scale[static_cast<std::size_t>(k)], floor);
    }
    p.scale = scale;
    const auto& a = p.a;
    const auto& S = scale;
    // Faithfulness: each fitted coefficient against the exact one (true ρ) at a point that is no node.
    constexpr double kCheckT = 0.3819660112501051;  // 2 − φ
    const CharacteristicCoefficients exact = Exact(s, HeightAt(s, kCheckT));
    double worst = 0;
    for (int k = 1; k <= 5; ++k) {
      const double error =
          std::abs(a[static_cast<std::size_t>(k)](kCheckT) - exact[static_cast<std::size_t>(k)]);
      worst = std::max(worst, error / S[static_cast<std::size_t>(k)]);
    }
    if (!(worst <= kFaithfulness)) {
      Uncertify("segment " + FormatMetres(segment.lower_height_m) + " to " +
                FormatMetres(segment.upper_height_m) +
                ": the fitted coefficients do not reproduce the exact model (relative error " +
                std::to_string(worst) + ")");
    }
  }

  // The Hopf (Δ₄, or Δ₃ when deflated) and real-root (a₅, or a₄) criteria's scales and the real one's
  // polynomial; then Δ's sign, excluded over the segment by interval arithmetic where it can be.
  void SetCriteria(std::size_t s) {
    const MatrixSegment& segment = segments_[s];
    SegmentPolynomials& p = polynomials_[s];
    const auto& a = p.a;
    const auto& S = p.scale;
    if (!segment.deflated) {
      p.hopf_scale =
          (S[1] * S[2] + S[3]) * (S[3] * S[4] + S[2] * S[5]) + (S[1] * S[4] + S[5]) * (S[1] * S[4] + S[5]);
      p.real_scale = S[5];
      // An exact zero of a₅ at an end (column 4 of A vanishes there) is divided out: the quotient
      // has the other roots, and its sign at that end is a₅'s just inside.
      p.real = a[5];
      if (segment.real_root_at_lower) p.real = p.real.DividedByT();
      if (segment.real_root_at_upper) p.real = p.real.DividedByOneMinusT();
    } else {
      p.hopf_scale = S[1] * S[2] * S[3] + S[3] * S[3] + S[1] * S[1] * S[4];
      p.real_scale = S[4];
      p.real = a[4];
    }
    // Δ by interval arithmetic first: most segments are far from any root, and then the degree-27
    // products are not needed. Where Δ has opposite signs at the two ends (the end coefficients are
    // the values there) a root is certain and no exclusion is tried.
    const double margin = kRoundingAllowance * p.hopf_scale;
    CharacteristicCoefficients lower_end{}, upper_end{};
    for (int k = 1; k <= 5; ++k) {
      lower_end[static_cast<std::size_t>(k)] = a[static_cast<std::size_t>(k)].coefficient(0);
      upper_end[static_cast<std::size_t>(k)] =
          a[static_cast<std::size_t>(k)].coefficient(a[static_cast<std::size_t>(k)].degree());
    }
    const double hopf_lower = HopfCriterion(lower_end, segment.deflated);
    const double hopf_upper = HopfCriterion(upper_end, segment.deflated);
    const bool root_certain =
        (hopf_lower > margin && hopf_upper < -margin) || (hopf_lower < -margin && hopf_upper > margin);
    if (root_certain) {
      BuildHopf(s, -1.0);
      return;
    }
    // Interval bounds of each aₖ over the segment (the range of its Bernstein coefficients, which the
    // basis, a partition of unity, keeps the polynomial in) and Δ's formula in them.
    std::array<Range, 6> r;
    for (int k = 1; k <= 5; ++k) r[static_cast<std::size_t>(k)] = Range::Of(a[static_cast<std::size_t>(k)]);
    Range bound;
    if (!segment.deflated) {
      const Range e = r[1] * r[4] - r[5];
      bound = (r[1] * r[2] - r[3]) * (r[3] * r[4] - r[2] * r[5]) - e.Squared();
    } else {
      bound = r[1] * r[2] * r[3] - r[3].Squared() - r[1].Squared() * r[4];
    }
    // Then, where that does not exclude a root, the tighter ranges of Δ's factors (BuildHopf).
    p.hopf_excluded = bound.ExcludesZero(margin) || !BuildHopf(s, margin);
  }

  // Builds the Bernstein form of Δ₄ (Δ₃ when deflated) of segment s, unless `exclusion_margin` ≥ 0
  // and the ranges of its factors' Bernstein forms (f = a₁a₂ − a₃, g = a₃a₄ − a₂a₅, e = a₁a₄ − a₅
  // of Δ₄ = fg − e²; f, a₃, a₁², a₄ of Δ₃ = f·a₃ − a₁²a₄), which the products need anyway, show that
  // it stays farther than that from 0: then false (excluded), nothing built.
  bool BuildHopf(std::size_t s, double exclusion_margin) {
    SegmentPolynomials& p = polynomials_[s];
    const auto& a = p.a;
    const BernsteinPolynomial f = a[1] * a[2] - a[3];
    if (!segments_[s].deflated) {
      const BernsteinPolynomial g = a[3] * a[4] - a[2] * a[5];
      const BernsteinPolynomial e = a[1] * a[4] - a[5];
      if (exclusion_margin >= 0 &&
          (Range::Of(f) * Range::Of(g) - Range::Of(e).Squared()).ExcludesZero(exclusion_margin)) {
        return false;
      }
      p.hopf = f * g - e * e;
    } else {
      const BernsteinPolynomial a1_squared = a[1] * a[1];
      if (exclusion_margin >= 0 && (Range::Of(f) * Range::Of(a[3]) - Range::Of(a1_squared) * Range::Of(a[4]))
                                       .ExcludesZero(exclusion_margin)) {
        return false;
      }
      p.hopf = f * a[3] - a1_squared * a[4];
    }
    p.hopf_built = true;
    return true;
  }
  const BernsteinPolynomial& Hopf(std::size_t s) {
    if (!polynomials_[s].hopf_built) BuildHopf(s, -1.0);
    return polynomials_[s].hopf;
  }

  // Refines a candidate on the exact model, checks it is a crossing, classifies it.
  // The segment of a height in candidate c's bracket (the bracket may straddle a table row).
  std::size_t SegmentOf(const Candidate& c, double h) const {
    if (h > segments_[c.segment].upper_height_m && c.segment + 1 < segments_.size()) return c.segment + 1;
    return c.segment;
  }

  // Candidate c's root of the exact criterion (TOMS 748 across the bracket) and the final bracket's
  // width; the polynomial's root, uncertified, when the exact model does not change sign there.
  std::pair<double, double> RefineRoot(const Candidate& c) {
    const MatrixSegment& segment = segments_[c.segment];
    auto f = [&](double h) { return ExactCriterion(SegmentOf(c, h), h, c.hopf, c.undeflated); };
    double lower = c.lower_m, upper = c.upper_m;
    double f_lower = f(lower), f_upper = f(upper);
    if (f_lower != 0.0 && f_upper != 0.0 && (f_lower < 0) != (f_upper < 0)) {
      std::uintmax_t iterations = 100;
      auto [low, high] = boost::math::tools::toms748_solve(
          f, lower, upper, f_lower, f_upper, boost::math::tools::eps_tolerance<double>(50), iterations);
      return {0.5 * (low + high), high - low};
    }
    if (f_lower == 0.0 || f_upper == 0.0) return {f_lower == 0.0 ? lower : upper, 0.0};
    // The exact model does not change sign where the polynomial does: ρ̂ moved a root out of a
    // bracket narrower than the interpolation error. Keep the polynomial's root and say so.
    const BernsteinPolynomial& poly = c.hopf ? Hopf(c.segment) : polynomials_[c.segment].real;
    double tl = (lower - segment.lower_height_m) / Length(c.segment);
    double tu = (upper - segment.lower_height_m) / Length(c.segment);
    const bool rising = poly(tu) > poly(tl);
    for (int i = 0; i < 60; ++i) {
      const double tm = 0.5 * (tl + tu);
      ((poly(tm) > 0) == rising ? tu : tl) = tm;
    }
    const double root = HeightAt(c.segment, 0.5 * (tl + tu));
    Uncertify("the exact model does not change sign across the polynomial's root near H = " +
              FormatMetres(root));
    return {root, upper - lower};
  }

  void Confirm(const Candidate& c) {
    const auto [root, width] = RefineRoot(c);
    const std::size_t s = SegmentOf(c, root);
    const bool deflated = segments_[s].deflated && !c.undeflated;
    const CharacteristicCoefficients a = Exact(s, root);
    const double t = (root - segments_[s].lower_height_m) / Length(s);
    const SegmentPolynomials& p = polynomials_[s];
    BoundaryCrossing crossing;
    crossing.height_m = root;
    crossing.height_over_span = root / wingspan_m_;
    crossing.bracket_width_m = width;
    crossing.deflated = deflated;
    const double dt_dH = 1.0 / Length(s);
    const BernsteinPolynomial& criterion = c.hopf ? Hopf(s) : p.a[deflated ? 4 : 5];
    crossing.criterion_height_derivative = criterion.Derivative()(t) * dt_dH;
    // dλ/dH = −(∂p/∂H)(λ) / p'(λ) with p(s, H) = det(sI − A(H)) (the quartic factor when deflated).
    const int n = deflated ? 4 : 5;
    auto polynomial_at = [&](std::complex<double> z, bool derivative_in_H, bool derivative_in_s) {
      std::complex<double> value = 0;
      for (int k = 0; k <= n; ++k) {
        double coefficient = a[static_cast<std::size_t>(k)];
        if (derivative_in_H)
          coefficient = k == 0 ? 0.0 : p.a[static_cast<std::size_t>(k)].Derivative()(t) * dt_dH;
        const int power = n - k;
        if (derivative_in_s) {
          if (power == 0) continue;
          value += coefficient * static_cast<double>(power) * std::pow(z, power - 1);
        } else {
          value += coefficient * std::pow(z, power);
        }
      }
      return value;
    };
    std::complex<double> lambda = 0.0;
    if (c.hopf) {
      const double omega2 = deflated ? DeflatedHopfFrequencySquared(a) : HopfFrequencySquared(a);
      if (!(omega2 > 0.0)) return;  // two real roots ±r: Δ vanishes, nothing crosses
      lambda = {0.0, std::sqrt(omega2)};
      crossing.kind = CrossingKind::kHopf;
    } else {
      crossing.kind = CrossingKind::kReal;
    }
    crossing.eigenvalue_height_derivative =
        -polynomial_at(lambda, true, false) / polynomial_at(lambda, false, true);
    crossing.mode_stable_above = crossing.eigenvalue_height_derivative.real() < 0.0;
    // One eigen-analysis at the root names the mode.
    ++result_.eigen_analyses;
    const ModalAnalysis modal = AnalyzeModes(segments_[s].exact_matrix(root), solver_);
    int slot = -1;
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 5; ++i) {
      const std::complex<double> z = modal.eigenvalues[static_cast<std::size_t>(i)];
      if (c.hopf && z.imag() <= 0.0) continue;
      if (!c.hopf && z.imag() != 0.0) continue;
      const double distance = std::abs(z - lambda);
      if (distance < best) {
        best = distance;
        slot = i;
      }
    }
    if (slot < 0) {
      Uncertify("the eigenvalues at H = " + FormatMetres(root) + " show no " +
                (c.hopf ? std::string("complex pair") : std::string("real root")) + " on the axis");
      return;
    }
    crossing.eigenvalue = modal.eigenvalues[static_cast<std::size_t>(slot)];
    crossing.mode = slot < 2 ? "short_period" : (slot < 4 ? "phugoid" : "height");
    result_.crossings.push_back(crossing);
  }

  // The stability of the airplane at an end of segment s from the end coefficients of its fitted
  // aₖ (their values there), when every Liénard–Chipart quantity (aₖ, Δ₂ and Δ₄; a₁…a₄ and Δ₃ when
  // deflated) is farther from 0 than its rounding allowance, or some aₖ is certainly negative;
  // nullopt when that is undecided (e.g. a crossing at the end).
  std::optional<bool> StableAtEnd(std::size_t s, bool upper) const {
    const SegmentPolynomials& p = polynomials_[s];
    const bool deflated = segments_[s].deflated;
    const int n = deflated ? 4 : 5;
    CharacteristicCoefficients a{};
    a[0] = 1.0;
    for (int k = 1; k <= 5; ++k) {
      const BernsteinPolynomial& ak = p.a[static_cast<std::size_t>(k)];
      a[static_cast<std::size_t>(k)] = ak.coefficient(upper ? ak.degree() : 0);
    }
    const auto& S = p.scale;
    bool all_positive = true;
    for (int k = 1; k <= n; ++k) {
      const double allowance = kRoundingAllowance * S[static_cast<std::size_t>(k)];
      if (a[static_cast<std::size_t>(k)] < -allowance) return false;
      if (!(a[static_cast<std::size_t>(k)] > allowance)) all_positive = false;
    }
    if (!all_positive) return std::nullopt;
    auto certain = [](double value, double allowance) { return std::abs(value) > allowance; };
    if (deflated) {
      if (!certain(HurwitzDelta3(a), kRoundingAllowance * p.hopf_scale)) return std::nullopt;
      return DeflatedHurwitzStable(a);
    }
    const double delta2 = a[1] * a[2] - a[3];
    if (!certain(delta2, kRoundingAllowance * (S[1] * S[2] + S[3]))) return std::nullopt;
    if (!certain(HurwitzDelta4(a), kRoundingAllowance * p.hopf_scale)) return std::nullopt;
    return HurwitzStable(a);
  }

  // Stability just inside each end, between crossings and across every table row; a change of
  // stability at a table row without a crossing there is a crossing of kind kDiscontinuity.
  void AssignStability() {
    std::vector<double> breaks{segments_.front().lower_height_m};
    for (const auto& crossing : result_.crossings) breaks.push_back(crossing.height_m);
    for (std::size_t s = 0; s + 1 < segments_.size(); ++s) breaks.push_back(segments_[s].upper_height_m);
    breaks.push_back(segments_.back().upper_height_m);
    std::sort(breaks.begin(), breaks.end());
    breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
    std::vector<bool> stable(breaks.size() - 1);
    for (std::size_t i = 0; i + 1 < breaks.size(); ++i) {
      const double mid = 0.5 * (breaks[i] + breaks[i + 1]);
      std::size_t s = 0;
      while (s + 1 < segments_.size() && mid > segments_[s].upper_height_m) ++s;
      // No eigenvalue reaches the axis inside the interval, so the stability of any point of it, or
      // of an end where none is on the axis either, is the interval's: from the fitted coefficients
      // at a segment end when their signs are certain there, else from the exact model at the middle.
      std::optional<bool> decided;
      if (breaks[i] == segments_[s].lower_height_m) decided = StableAtEnd(s, /*upper=*/false);
      if (!decided && breaks[i + 1] == segments_[s].upper_height_m) decided = StableAtEnd(s, /*upper=*/true);
      stable[i] = decided ? *decided : StableBy(Exact(s, mid), segments_[s].deflated);
    }
    auto interval_below = [&](double h) {
      const auto it = std::lower_bound(breaks.begin(), breaks.end(), h);
      return static_cast<std::size_t>(it - breaks.begin()) - 1;
    };
    for (auto& crossing : result_.crossings) {
      const std::size_t i = interval_below(crossing.height_m);
      crossing.stable_below = stable[i];
      crossing.stable_above = stable[i + 1];
    }
    for (std::size_t s = 0; s + 1 < segments_.size(); ++s) {
      const double knot = segments_[s].upper_height_m;
      const std::size_t i = interval_below(knot);
      if (stable[i] == stable[i + 1]) continue;
      const bool crossing_here = std::any_of(result_.crossings.begin(), result_.crossings.end(),
                                             [&](const auto& c) { return c.height_m == knot; });
      if (crossing_here) continue;
      BoundaryCrossing jump;
      jump.kind = CrossingKind::kDiscontinuity;
      jump.height_m = knot;
      jump.height_over_span = knot / wingspan_m_;
      jump.stable_below = stable[i];
      jump.stable_above = stable[i + 1];
      jump.mode_stable_above = stable[i + 1];
      jump.deflated = segments_[s + 1].deflated;
      result_.crossings.push_back(jump);
    }
    std::sort(result_.crossings.begin(), result_.crossings.end(),
              [](const auto& x, const auto& y) { return x.height_m < y.height_m; });
    result_.stable_at_lower = stable.front();
    result_.stable_at_upper = stable.back();
  }

  static const std::vector<double>& Nodes(int m) {
    static const std::vector<std::vector<double>> nodes = [] {
      std::vector<std::vector<double>> all;
      for (int i = 0; i <= BernsteinPolynomial::kMaxDegree + 1; ++i) {
        all.push_back(i == 0 ? std::vector<double>{} : BernsteinPolynomial::ChebyshevNodes(i));
      }
      return all;
    }();
    return nodes[static_cast<std::size_t>(m)];
  }

  const std::vector<MatrixSegment>& segments_;
  double wingspan_m_;
  EigenvalueSolver solver_;
  std::vector<SegmentPolynomials> polynomials_;
  // Per segment and criterion, where the criterion is ~0 at an end (within the rounding allowance,
  // or exactly, divided out): the t up to which the undecided region reaches (−1: not ~0 there).
  std::vector<std::array<double, 2>> lower_zone_, upper_zone_;
  CrossingSearchResult result_;
};

// ρ(z) = ρ₀ θⁿ, θ = 1 − L z/T₀ (IsaDensity): |ρ'''| ≤ ρ₀ n(n−1)(n−2) (L/T₀)³ θ^{n−3}, largest at the
// lowest altitude. Quadratic interpolation at the ends and the middle of a segment of length ℓ errs
// by at most max|ρ'''| δ³/(9√3), δ = ℓ/2 (the nodal polynomial of −δ, 0, δ peaks at 2δ³/(3√3)).
double QuadraticDensityErrorBound(double lower_altitude_m, double length_m) {
  constexpr double n = kGravity_mps2 / (kAirGasConstant_JpkgK * kTroposphereLapseRate_Kpm) - 1.0;
  constexpr double r = kTroposphereLapseRate_Kpm / kSeaLevelTemperature_K;
  const double theta = 1.0 - r * lower_altitude_m;
  const double third = kSeaLevelDensity_kgpm3 * n * (n - 1) * (n - 2) * r * r * r * std::pow(theta, n - 3);
  const double delta = 0.5 * length_m;
  return third * delta * delta * delta / (9.0 * std::sqrt(3.0));
}

// ρ·((1 − t)·a + t·b), derivative by derivative.
DimensionalDerivatives InterpolatedDerivatives(const DimensionalDerivatives& a,
                                               const DimensionalDerivatives& b, double t, double density) {
  auto lerp = [&](double x, double y) { return density * (x + t * (y - x)); };
  DimensionalDerivatives d;
  d.Xu = lerp(a.Xu, b.Xu);
  d.Xw = lerp(a.Xw, b.Xw);
  d.Xh = lerp(a.Xh, b.Xh);
  d.Xde = lerp(a.Xde, b.Xde);
  d.Zu = lerp(a.Zu, b.Zu);
  d.Zw = lerp(a.Zw, b.Zw);
  d.Zh = lerp(a.Zh, b.Zh);
  d.Zde = lerp(a.Zde, b.Zde);
  d.Mu = lerp(a.Mu, b.Mu);
  d.Mw = lerp(a.Mw, b.Mw);
  d.Mw_dot = lerp(a.Mw_dot, b.Mw_dot);
  d.Mq = lerp(a.Mq, b.Mq);
  d.Mh = lerp(a.Mh, b.Mh);
  d.Mde = lerp(a.Mde, b.Mde);
  return d;
}

/// Which coefficients a segment's rows come from: the first row held below the table, the table, the
/// free-flight row above it.
enum class CoefficientSource { kHeld, kTable, kFreeFlight };

/// The coefficients at height H (m) of a segment whose rows come from `source`.
auto CoefficientsOf(const CoefficientTable& table, CoefficientSource source) {
  return [&table, source](double h) {
    switch (source) {
      case CoefficientSource::kHeld:
        return table.rows().front();
      case CoefficientSource::kFreeFlight:
        return table.free_flight();
      case CoefficientSource::kTable:
        return table.At(h);
    }
    return table.At(h);
  };
}

/// The degree bound of each aₖ of a segment whose coefficients C(H) have degree coefficient_degree.
void SetDegreeBounds(MatrixSegment& segment, int coefficient_degree) {
  // The expansion of det(sI − A) (hurwitz.cc) makes aₖ a sum of products of at most min(k, 3)
  // factors ∝ ρ·C(H) (in a₅ the terms with four cancel exactly: Zw·Mh − Zh·Mw is what remains of
  // Zw·(Mh + Mẇ Zh) − Zh·(Mw + Mẇ Zw)), each of degree 2 (ρ̂) + that of C(H). The Chebyshev tail
  // of each fit checks the bound.
  for (int k = 1; k <= 5; ++k) {
    segment.coefficient_degrees[static_cast<std::size_t>(k)] = std::min(k, 3) * (2 + coefficient_degree);
  }
}

/// Where a₅ has a root by construction: column 4 (ΔH) of A, ρ·(Xh, Zh, Mh + ρ·Mẇ·Zh, 0, 0) per unit
/// density, is zero at an end exactly where Xh = Zh = Mh = 0 there (ρ > 0); zero at both ends, it is
/// zero throughout (entries affine in the coefficients, `affine`), and the segment is deflated.
void SetRealRoots(MatrixSegment& segment, const DimensionalDerivatives& d_lo,
                  const DimensionalDerivatives& d_hi, bool affine) {
  auto column_zero = [](const DimensionalDerivatives& d) {
    return d.Xh == 0.0 && d.Zh == 0.0 && d.Mh == 0.0;
  };
  const double lo = segment.lower_height_m, hi = segment.upper_height_m;
  const bool zero_lo = column_zero(d_lo);
  const bool zero_hi = column_zero(d_hi);
  segment.real_root_at_lower = zero_lo;
  segment.real_root_at_upper = zero_hi;
  segment.deflated =
      zero_lo && zero_hi &&
      (affine || segment.exact_matrix(0.5 * (lo + hi)).col(kDeltaH).cwiseAbs().maxCoeff() == 0.0);
  if (segment.deflated) segment.real_root_at_lower = segment.real_root_at_upper = false;
}

/// The segment [lo, hi] (m) of an aircraft's model at speed u (m/s), ρ there rho_lo and rho_hi: its
/// degree bounds, its polynomial matrix (on ρ̂) and exact one (on ρ), its roots by construction; ρ̂'s
/// relative error bound raises *density_bound.
MatrixSegment AircraftSegment(const LongitudinalModel& model, double speed_mps, double lo, double hi,
                              double rho_lo, double rho_hi, double* density_bound) {
  const CoefficientTable& table = model.table();
  const std::vector<double>& rows = table.heights_m();
  const int interpolation_degree = table.interpolation() == Interpolation::kPchip ? 3 : 1;
  const bool h_derivatives = model.options().h_derivatives;
  MatrixSegment segment;
  segment.lower_height_m = lo;
  segment.upper_height_m = hi;
  CoefficientSource source = CoefficientSource::kTable;
  if (hi <= rows.front()) source = CoefficientSource::kHeld;
  if (lo >= rows.back()) source = CoefficientSource::kFreeFlight;
  const int coefficient_degree = source == CoefficientSource::kTable ? interpolation_degree : 0;
  SetDegreeBounds(segment, coefficient_degree);
  const auto coefficients = CoefficientsOf(table, source);
  const double altitude = model.aircraft().field_elevation_m;
  const double rho_mid = model.DensityAt(0.5 * (lo + hi));
  const double bound = QuadraticDensityErrorBound(altitude + lo, hi - lo) / std::min(rho_lo, rho_hi);
  *density_bound = std::max(*density_bound, bound);
  const MassGeometry mg = model.mass_geometry();
  auto matrix = [=](double h, double density) {
    DimensionalDerivatives d = ComputeDerivatives(coefficients(h), mg, density, speed_mps);
    if (!h_derivatives) d.Xh = d.Zh = d.Mh = 0.0;
    return AssembleStateMatrix(d, speed_mps);
  };
  // ρ̂: the Lagrange form on t = 0, ½, 1.
  auto density = [=](double t) {
    return rho_lo * (2 * t - 1) * (t - 1) + rho_mid * 4 * t * (1 - t) + rho_hi * t * (2 * t - 1);
  };
  // Every derivative of Table 1 is ρ times a function of the coefficients that is affine in them.
  auto unit_derivatives = [&](double h) {
    DimensionalDerivatives d = ComputeDerivatives(coefficients(h), mg, 1.0, speed_mps);
    if (!h_derivatives) d.Xh = d.Zh = d.Mh = 0.0;
    return d;
  };
  const DimensionalDerivatives d_lo = unit_derivatives(lo), d_hi = unit_derivatives(hi);
  if (coefficient_degree <= 1) {
    // The coefficients are affine in H here: the derivatives per unit density at the two ends,
    // linearly interpolated and times ρ̂, are the same derivatives up to rounding (which the fit's
    // faithfulness check against the exact model covers), without a table lookup per node.
    segment.polynomial_matrix = [=](double h) {
      const double t = (h - lo) / (hi - lo);
      return AssembleStateMatrix(InterpolatedDerivatives(d_lo, d_hi, t, density(t)), speed_mps);
    };
  } else {
    segment.polynomial_matrix = [=](double h) { return matrix(h, density((h - lo) / (hi - lo))); };
  }
  const LongitudinalModel* m = &model;
  // The density at the ends is the knots' (the ISA's pow is most of an exact evaluation).
  segment.exact_matrix = [=](double h) {
    const double density = h == lo ? rho_lo : (h == hi ? rho_hi : m->DensityAt(h));
    return matrix(h, density);
  };
  SetRealRoots(segment, d_lo, d_hi, source != CoefficientSource::kTable || interpolation_degree == 1);
  return segment;
}

/// The segments of an aircraft's model between lower and upper (m) at speed u (m/s), split at the
/// table's rows; *density_bound the largest relative error bound of their ρ̂.
std::vector<MatrixSegment> AircraftSegments(const LongitudinalModel& model, double speed_mps, double lower,
                                            double upper, double* density_bound) {
  const std::vector<double>& rows = model.table().heights_m();
  std::vector<double> knots{lower};
  for (double h : rows) {
    if (h > lower && h < upper) knots.push_back(h);
  }
  knots.push_back(upper);
  std::vector<double> knot_density(knots.size());
  for (std::size_t i = 0; i < knots.size(); ++i) knot_density[i] = model.DensityAt(knots[i]);
  *density_bound = 0;
  std::vector<MatrixSegment> segments;
  segments.reserve(knots.size() - 1);
  for (std::size_t i = 0; i + 1 < knots.size(); ++i) {
    segments.push_back(AircraftSegment(model, speed_mps, knots[i], knots[i + 1], knot_density[i],
                                       knot_density[i + 1], density_bound));
  }
  return segments;
}

}  // namespace

SampledSearchResult SampledCrossingSearch(const std::function<Matrix5d(double)>& matrix,
                                          const std::vector<double>& knots, int samples_per_segment,
                                          double tolerance_m, EigenvalueSolver solver) {
  GESWEEP_DEMAND(knots.size() >= 2 && samples_per_segment >= 0);
  SampledSearchResult result;
  auto sigma = [&](double height_m) {
    ++result.margin_evaluations;
    return AnalyzeModes(matrix(height_m), solver).stability_margin_per_s;
  };
  std::vector<double> heights;
  for (std::size_t i = 0; i + 1 < knots.size(); ++i) {
    for (int j = 0; j <= samples_per_segment; ++j) {
      heights.push_back(knots[i] + (knots[i + 1] - knots[i]) * j / (samples_per_segment + 1.0));
    }
  }
  heights.push_back(knots.back());
  result.margins.reserve(heights.size());
  for (double h : heights) {
    const double s = sigma(h);
    if (!std::isfinite(s)) {
      result.finite = false;
      result.non_finite_reason = "stability margin is not finite at H = " + FormatMetres(h);
      result.margins.clear();
      return result;
    }
    result.margins.push_back(s);
  }
  for (std::size_t i = 0; i + 1 < heights.size(); ++i) {
    const double a = heights[i], b = heights[i + 1];
    const double sa = result.margins[i], sb = result.margins[i + 1];
    if ((sa < 0) == (sb < 0)) continue;
    BoundaryCrossing crossing;
    crossing.kind = CrossingKind::kSigma;
    crossing.stable_above = sb < 0;
    crossing.stable_below = sa < 0;
    crossing.mode_stable_above = crossing.stable_above;
    if (sa == 0.0 || sb == 0.0) {
      crossing.height_m = sa == 0.0 ? a : b;
    } else {
      std::uintmax_t max_iterations = 200;
      auto [low, high] = boost::math::tools::toms748_solve(
          sigma, a, b, sa, sb, [tolerance_m](double x, double y) { return std::abs(y - x) <= tolerance_m; },
          max_iterations);
      crossing.height_m = 0.5 * (low + high);
      crossing.bracket_width_m = high - low;
    }
    result.crossings.push_back(crossing);
  }
  return result;
}

CrossingSearchResult CrossingSearch(const std::vector<MatrixSegment>& segments, double wingspan_m,
                                    EigenvalueSolver solver) {
  GESWEEP_DEMAND(!segments.empty());
  return Search(segments, wingspan_m, solver).Run();
}

namespace {

/// The certificate of a certified Hurwitz search over `segments` segments: the range, the isolation
/// and the bound on ρ̂'s relative error.
std::string HurwitzCertificate(const BoundaryResult& result, std::size_t segments) {
  // std::to_chars, not printf: the formatting was 3 % of a search.
  auto general = [](double value, int precision) {
    char text[32];
    const auto end =
        std::to_chars(text, text + sizeof text, value, std::chars_format::general, precision).ptr;
    return std::string(text, end);
  };
  return "every root of Delta4 and a5 in " + general(result.lower_height_m, 7) + " m to " +
         general(result.upper_height_m, 7) + " m isolated on " + std::to_string(segments) +
         " segments (Descartes' rule on the Bernstein basis); rho(H) by its quadratic "
         "interpolant per segment, relative error <= " +
         general(result.density_interpolation_bound, 2);
}

/// The Hurwitz search into `result`: its counts, certificate and crossings (highest first, each
/// bracket at most the tolerance), and whether the range is stable or unstable throughout; false
/// when the state matrix is not finite somewhere (result.reason says where).
bool HurwitzSearch(const LongitudinalModel& model, double speed_mps, const BoundaryOptions& options,
                   BoundaryResult& result, bool& all_stable, bool& all_unstable) {
  const std::vector<MatrixSegment> segments = AircraftSegments(
      model, speed_mps, result.lower_height_m, result.upper_height_m, &result.density_interpolation_bound);
  result.segments = static_cast<int>(segments.size());
  CrossingSearchResult search =
      CrossingSearch(segments, model.aircraft().wingspan_m, options.eigenvalue_solver);
  result.polynomial_evaluations = search.polynomial_evaluations;
  result.margin_evaluations = search.eigen_analyses;
  if (!search.finite) {
    result.reason = search.non_finite_reason;
    result.certificate = "none: " + search.non_finite_reason;
    return false;
  }
  result.certified = search.certified;
  result.certificate = search.certified ? HurwitzCertificate(result, segments.size())
                                        : "not certified: " + search.uncertified_reason;
  for (auto& crossing : search.crossings) {
    if (options.tolerance_m < crossing.bracket_width_m) crossing.bracket_width_m = options.tolerance_m;
  }
  result.crossings.assign(search.crossings.rbegin(), search.crossings.rend());
  all_stable = result.crossings.empty() && search.stable_at_lower;
  all_unstable = result.crossings.empty() && !search.stable_at_lower;
  if (!result.crossings.empty()) {
    all_stable = std::all_of(result.crossings.begin(), result.crossings.end(),
                             [](const auto& c) { return c.stable_above && c.stable_below; });
    all_unstable = std::all_of(result.crossings.begin(), result.crossings.end(),
                               [](const auto& c) { return !c.stable_above && !c.stable_below; });
  }
  return true;
}

/// H*: the highest crossing unstable below and stable above, with every crossing's H/b; else the
/// reason there is none (the range stable or unstable throughout, or neither).
void SetBoundaryHeight(double wingspan_m, bool all_stable, bool all_unstable, BoundaryResult& result) {
  for (auto& crossing : result.crossings) crossing.height_over_span = crossing.height_m / wingspan_m;
  for (const auto& crossing : result.crossings) {
    if (crossing.stable_above && !crossing.stable_below) {
      result.height_m = crossing.height_m;
      result.height_over_span = crossing.height_m / wingspan_m;
      break;
    }
  }
  if (!result.height_m) {
    const std::string range =
        FormatMetres(result.lower_height_m) + " to " + FormatMetres(result.upper_height_m);
    if (all_stable) {
      result.reason = "stable at every height from " + range;
    } else if (all_unstable) {
      result.reason = "unstable at every height from " + range;
    } else {
      result.reason = "no height in " + range + " has unstable below and stable above";
    }
  }
}

}  // namespace

BoundaryResult FindBoundary(const LongitudinalModel& model, double speed_mps,
                            const BoundaryOptions& options) {
  const Aircraft& aircraft = model.aircraft();
  BoundaryResult result;
  result.speed_mps = speed_mps;
  result.method = options.method;
  result.lower_height_m =
      std::isnan(options.lower_height_m) ? aircraft.wheel_contact_height_m : options.lower_height_m;
  result.upper_height_m =
      std::isnan(options.upper_height_m) ? aircraft.table_heights_m.back() : options.upper_height_m;
  GESWEEP_DEMAND(result.upper_height_m > result.lower_height_m);

  bool all_stable = false, all_unstable = false;
  if (options.method == BoundaryMethod::kSampled) {
    std::vector<double> margins;
    SampledSearch(model, speed_mps, options, result, margins);
    if (margins.empty()) return result;
    all_stable = std::all_of(margins.begin(), margins.end(), [](double s) { return s < 0; });
    all_unstable = std::all_of(margins.begin(), margins.end(), [](double s) { return s >= 0; });
  } else if (!HurwitzSearch(model, speed_mps, options, result, all_stable, all_unstable)) {
    return result;
  }
  SetBoundaryHeight(aircraft.wingspan_m, all_stable, all_unstable, result);
  return result;
}

}  // namespace gesweep
