#include "engine/modal/boundary.h"

#include <algorithm>
#include <boost/math/tools/toms748_solve.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
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
  SampledSearchResult search = SampledCrossingSearch([&](double h) { return model.StateMatrix(h, speed_mps); },
                                                     knots, options.samples_per_segment, options.tolerance_m);
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
  bool hopf_excluded = false;  // interval arithmetic showed Δ has no root here
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
  Search(const std::vector<MatrixSegment>& segments, double wingspan_m)
      : segments_(segments), wingspan_m_(wingspan_m) {}

  CrossingSearchResult Run() {
    polynomials_.resize(segments_.size());
    std::vector<Candidate> candidates;
    // Per segment and criterion, where the criterion is ~0 at an end (within the rounding allowance,
    // or exactly, divided out): the t up to which the undecided region reaches (−1: not ~0 there).
    std::vector<std::array<double, 2>> lower_zone(segments_.size()), upper_zone(segments_.size());
    for (std::size_t s = 0; s < segments_.size(); ++s) {
      if (!BuildPolynomials(s)) return result_;
      for (int c = 0; c < 2; ++c) {
        const bool hopf = c == 0;
        const SegmentPolynomials& p = polynomials_[s];
        lower_zone[s][c] = (!hopf && segments_[s].real_root_at_lower) ? 0.0 : -1.0;
        upper_zone[s][c] = (!hopf && segments_[s].real_root_at_upper) ? 1.0 : -1.0;
        if (hopf && p.hopf_excluded) continue;
        const BernsteinPolynomial& poly = hopf ? p.hopf : p.real;
        const double allowance = kRoundingAllowance * (hopf ? p.hopf_scale : p.real_scale);
        const RootIsolation isolation = IsolateRoots(poly, allowance);
        for (const RootInterval& interval : isolation.intervals) {
          if (interval.lower_t == 0.0 && isolation.sign_at_lower == 0) {
            lower_zone[s][c] = interval.upper_t;  // decided with the segment below
            continue;
          }
          if (interval.upper_t == 1.0 && isolation.sign_at_upper == 0) {
            upper_zone[s][c] = interval.lower_t;  // decided with the segment above
            continue;
          }
          if (!interval.certified) {
            Uncertify("an unresolved cluster of roots of " + CriterionName(hopf, s) + " within " +
                      FormatMetres((interval.upper_t - interval.lower_t) * Length(s)) + " of H = " +
                      FormatMetres(HeightAt(s, interval.lower_t)) +
                      (interval.sign_change ? " (an odd number: one crossing reported)"
                                            : " (an even number: a tangency or a close pair, none reported)"));
            if (!interval.sign_change) continue;
          }
          candidates.push_back({HeightAt(s, interval.lower_t), HeightAt(s, interval.upper_t), hopf, s,
                                interval.certified});
        }
      }
    }
    // Where a criterion is ~0 at a table row or an end of the range: the region the isolation left
    // undecided there is decided by the signs of the exact criterion at its two sides (an odd number
    // of roots when they differ). Wider than kKnotOffset, it may hide an even number: not certified.
    auto check_zone_width = [&](std::size_t s, int c, double width_t, double end_m) {
      if (width_t > kKnotOffset * 1.0000001) {
        Uncertify(CriterionName(c == 0, s) + " is indistinguishable from 0 within " +
                  FormatMetres(width_t * Length(s)) + " of H = " + FormatMetres(end_m) +
                  "; a close pair of crossings there cannot be excluded");
      }
    };
    for (std::size_t s = 0; s < segments_.size(); ++s) {
      for (int c = 0; c < 2; ++c) {
        if (lower_zone[s][c] >= 0) check_zone_width(s, c, lower_zone[s][c], segments_[s].lower_height_m);
        if (upper_zone[s][c] >= 0) check_zone_width(s, c, 1.0 - upper_zone[s][c], segments_[s].upper_height_m);
      }
    }
    for (std::size_t s = 0; s + 1 < segments_.size(); ++s) {
      if (!Continuous(s)) continue;
      for (int c = 0; c < 2; ++c) {
        if (upper_zone[s][c] < 0 && lower_zone[s + 1][c] < 0) continue;
        const bool hopf = c == 0;
        // Where a₅ becomes identically 0 at the row, the neutral root arrives there and stays (the
        // stability comparison reports it); Δ₄ = a₄Δ₃ continues Δ₃ across the row.
        const bool mixed = segments_[s].deflated != segments_[s + 1].deflated;
        if (mixed && !hopf) continue;
        const double below_t = std::min(upper_zone[s][c] < 0 ? 1.0 : upper_zone[s][c], 1.0 - kKnotOffset);
        const double above_t = std::max(lower_zone[s + 1][c] < 0 ? 0.0 : lower_zone[s + 1][c], kKnotOffset);
        const double below = HeightAt(s, below_t), above = HeightAt(s + 1, above_t);
        const double fb = ExactCriterion(s, below, hopf, mixed), fa = ExactCriterion(s + 1, above, hopf, mixed);
        if ((fb < 0) != (fa < 0) && fb != 0 && fa != 0) candidates.push_back({below, above, hopf, s, true, mixed});
      }
    }

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

  bool BuildPolynomials(std::size_t s) {
    const MatrixSegment& segment = segments_[s];
    int degree = 0;
    for (int k = 1; k <= 5; ++k) degree = std::max(degree, segment.coefficient_degrees[static_cast<std::size_t>(k)]);
    // One node more than the degree needs: the tail of every coefficient checks its degree bound.
    const int m = degree + 2;
    const std::vector<double>& nodes = Nodes(m);
    std::array<std::array<double, BernsteinPolynomial::kMaxDegree + 2>, 6> values;
    double entry_scale = 0;
    for (int i = 0; i < m; ++i) {
      const double h = HeightAt(s, nodes[static_cast<std::size_t>(i)]);
      const Matrix5d A = segment.polynomial_matrix(h);
      ++result_.polynomial_evaluations;
      if (!A.allFinite()) {
        result_.finite = false;
        result_.non_finite_reason = "the state matrix is not finite at H = " + FormatMetres(h);
        return false;
      }
      entry_scale = std::max(entry_scale, A.cwiseAbs().maxCoeff());
      const CharacteristicCoefficients a = CharacteristicPolynomial(A);
      for (int k = 1; k <= 5; ++k) values[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)] = a[static_cast<std::size_t>(k)];
    }
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
        Uncertify("segment " + FormatMetres(segment.lower_height_m) + " to " + FormatMetres(segment.upper_height_m) +
                  ": a" + std::to_string(k) + " is not a polynomial of degree " + std::to_string(dk) +
                  " (Chebyshev tail " + std::to_string(tail) + ")");
      }
      scale[static_cast<std::size_t>(k)] = std::max(scale[static_cast<std::size_t>(k)], floor);
    }
    const auto& a = p.a;
    const auto& S = scale;
    // Faithfulness: each fitted coefficient against the exact one (true ρ) at a point that is no node.
    constexpr double kCheckT = 0.3819660112501051;  // 2 − φ
    const CharacteristicCoefficients exact = Exact(s, HeightAt(s, kCheckT));
    double worst = 0;
    for (int k = 1; k <= 5; ++k) {
      const double error = std::abs(a[static_cast<std::size_t>(k)](kCheckT) - exact[static_cast<std::size_t>(k)]);
      worst = std::max(worst, error / S[static_cast<std::size_t>(k)]);
    }
    if (!(worst <= kFaithfulness)) {
      Uncertify("segment " + FormatMetres(segment.lower_height_m) + " to " + FormatMetres(segment.upper_height_m) +
                ": the fitted coefficients do not reproduce the exact model (relative error " +
                std::to_string(worst) + ")");
    }
    // Interval bounds of each aₖ over the segment (the range of its Bernstein coefficients).
    std::array<Range, 6> r;
    for (int k = 1; k <= 5; ++k) r[static_cast<std::size_t>(k)] = Range::Of(a[static_cast<std::size_t>(k)]);
    if (!segment.deflated) {
      p.hopf_scale = (S[1] * S[2] + S[3]) * (S[3] * S[4] + S[2] * S[5]) + (S[1] * S[4] + S[5]) * (S[1] * S[4] + S[5]);
      p.real_scale = S[5];
      // An exact zero of a₅ at an end (column 4 of A vanishes there) is divided out: the quotient
      // has the other roots, and its sign at that end is a₅'s just inside.
      p.real = a[5];
      if (segment.real_root_at_lower) p.real = p.real.DividedByT();
      if (segment.real_root_at_upper) p.real = p.real.DividedByOneMinusT();
      // Δ₄ by interval arithmetic first: most segments are far from any root, and then the degree-27
      // products are not needed.
      const Range e = r[1] * r[4] - r[5];
      const Range bound = (r[1] * r[2] - r[3]) * (r[3] * r[4] - r[2] * r[5]) - e.Squared();
      p.hopf_excluded = bound.ExcludesZero(kRoundingAllowance * p.hopf_scale);
    } else {
      p.hopf_scale = S[1] * S[2] * S[3] + S[3] * S[3] + S[1] * S[1] * S[4];
      p.real_scale = S[4];
      p.real = a[4];
      const Range bound = r[1] * r[2] * r[3] - r[3].Squared() - r[1].Squared() * r[4];
      p.hopf_excluded = bound.ExcludesZero(kRoundingAllowance * p.hopf_scale);
    }
    if (!p.hopf_excluded) BuildHopf(s);
    return true;
  }

  // The Bernstein form of Δ₄ (Δ₃ when deflated) of segment s.
  const BernsteinPolynomial& BuildHopf(std::size_t s) {
    SegmentPolynomials& p = polynomials_[s];
    if (p.hopf_built) return p.hopf;
    const auto& a = p.a;
    if (!segments_[s].deflated) {
      const BernsteinPolynomial e = a[1] * a[4] - a[5];
      p.hopf = (a[1] * a[2] - a[3]) * (a[3] * a[4] - a[2] * a[5]) - e * e;
    } else {
      p.hopf = a[1] * a[2] * a[3] - a[3] * a[3] - a[1] * a[1] * a[4];
    }
    p.hopf_built = true;
    return p.hopf;
  }

  // Refines a candidate on the exact model, checks it is a crossing, classifies it.
  void Confirm(const Candidate& c) {
    const MatrixSegment& segment = segments_[c.segment];
    // The exact criterion across the bracket (it may straddle a table row: then each side's segment).
    auto segment_of = [&](double h) {
      if (h > segment.upper_height_m && c.segment + 1 < segments_.size()) return c.segment + 1;
      return c.segment;
    };
    auto f = [&](double h) { return ExactCriterion(segment_of(h), h, c.hopf, c.undeflated); };
    double lower = c.lower_m, upper = c.upper_m;
    double f_lower = f(lower), f_upper = f(upper);
    double root = 0.5 * (lower + upper);
    double width = upper - lower;
    if (f_lower != 0.0 && f_upper != 0.0 && (f_lower < 0) != (f_upper < 0)) {
      std::uintmax_t iterations = 100;
      auto [low, high] = boost::math::tools::toms748_solve(f, lower, upper, f_lower, f_upper,
                                                           boost::math::tools::eps_tolerance<double>(50), iterations);
      root = 0.5 * (low + high);
      width = high - low;
    } else if (f_lower == 0.0 || f_upper == 0.0) {
      root = f_lower == 0.0 ? lower : upper;
      width = 0.0;
    } else {
      // The exact model does not change sign where the polynomial does: ρ̂ moved a root out of a
      // bracket narrower than the interpolation error. Keep the polynomial's root and say so.
      const BernsteinPolynomial& poly = c.hopf ? BuildHopf(c.segment) : polynomials_[c.segment].real;
      double tl = (lower - segment.lower_height_m) / Length(c.segment);
      double tu = (upper - segment.lower_height_m) / Length(c.segment);
      const bool rising = poly(tu) > poly(tl);
      for (int i = 0; i < 60; ++i) {
        const double tm = 0.5 * (tl + tu);
        ((poly(tm) > 0) == rising ? tu : tl) = tm;
      }
      root = HeightAt(c.segment, 0.5 * (tl + tu));
      Uncertify("the exact model does not change sign across the polynomial's root near H = " + FormatMetres(root));
    }
    const std::size_t s = segment_of(root);
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
    const BernsteinPolynomial& criterion = c.hopf ? BuildHopf(s) : p.a[deflated ? 4 : 5];
    crossing.criterion_height_derivative = criterion.Derivative()(t) * dt_dH;
    // dλ/dH = −(∂p/∂H)(λ) / p'(λ) with p(s, H) = det(sI − A(H)) (the quartic factor when deflated).
    const int n = deflated ? 4 : 5;
    auto polynomial_at = [&](std::complex<double> z, bool derivative_in_H, bool derivative_in_s) {
      std::complex<double> value = 0;
      for (int k = 0; k <= n; ++k) {
        double coefficient = a[static_cast<std::size_t>(k)];
        if (derivative_in_H) coefficient = k == 0 ? 0.0 : p.a[static_cast<std::size_t>(k)].Derivative()(t) * dt_dH;
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
    crossing.eigenvalue_height_derivative = -polynomial_at(lambda, true, false) / polynomial_at(lambda, false, true);
    crossing.mode_stable_above = crossing.eigenvalue_height_derivative.real() < 0.0;
    // One eigen-analysis at the root names the mode.
    ++result_.eigen_analyses;
    const ModalAnalysis modal = AnalyzeModes(segments_[s].exact_matrix(root));
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
      stable[i] = StableBy(Exact(s, mid), segments_[s].deflated);
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
  std::vector<SegmentPolynomials> polynomials_;
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

// The segments of an aircraft's model between lower and upper at speed u.
std::vector<MatrixSegment> AircraftSegments(const LongitudinalModel& model, double speed_mps, double lower,
                                            double upper, double* density_bound) {
  const CoefficientTable& table = model.table();
  const std::vector<double>& rows = table.heights_m();
  std::vector<double> knots{lower};
  for (double h : rows) {
    if (h > lower && h < upper) knots.push_back(h);
  }
  knots.push_back(upper);
  const int interpolation_degree = table.interpolation() == Interpolation::kPchip ? 3 : 1;
  const bool h_derivatives = model.options().h_derivatives;
  *density_bound = 0;
  std::vector<MatrixSegment> segments;
  for (std::size_t i = 0; i + 1 < knots.size(); ++i) {
    MatrixSegment segment;
    const double lo = knots[i], hi = knots[i + 1];
    segment.lower_height_m = lo;
    segment.upper_height_m = hi;
    // Which coefficients apply: the first row held below the table, the free-flight row above it.
    enum class Source { kHeld, kTable, kFreeFlight } source = Source::kTable;
    if (hi <= rows.front()) source = Source::kHeld;
    if (lo >= rows.back()) source = Source::kFreeFlight;
    const int coefficient_degree = source == Source::kTable ? interpolation_degree : 0;
    // The expansion of det(sI − A) (hurwitz.cc) makes aₖ a sum of products of at most min(k, 3)
    // factors ∝ ρ·C(H) (in a₅ the terms with four cancel exactly: Zw·Mh − Zh·Mw is what remains of
    // Zw·(Mh + Mẇ Zh) − Zh·(Mw + Mẇ Zw)), each of degree 2 (ρ̂) + that of C(H). The Chebyshev tail
    // of each fit checks the bound.
    for (int k = 1; k <= 5; ++k) {
      segment.coefficient_degrees[static_cast<std::size_t>(k)] = std::min(k, 3) * (2 + coefficient_degree);
    }
    auto coefficients = [&table, source](double h) {
      switch (source) {
        case Source::kHeld: return table.rows().front();
        case Source::kFreeFlight: return table.free_flight();
        case Source::kTable: return table.At(h);
      }
      return table.At(h);
    };
    const double altitude = model.aircraft().field_elevation_m;
    const double rho_lo = model.DensityAt(lo), rho_mid = model.DensityAt(0.5 * (lo + hi)), rho_hi = model.DensityAt(hi);
    const double bound = QuadraticDensityErrorBound(altitude + lo, hi - lo) / std::min(rho_lo, rho_hi);
    *density_bound = std::max(*density_bound, bound);
    const MassGeometry mg = model.mass_geometry();
    auto matrix = [=](double h, double density) {
      DimensionalDerivatives d = ComputeDerivatives(coefficients(h), mg, density, speed_mps);
      if (!h_derivatives) d.Xh = d.Zh = d.Mh = 0.0;
      return AssembleStateMatrix(d, speed_mps);
    };
    segment.polynomial_matrix = [=](double h) {
      const double t = (h - lo) / (hi - lo);
      // Lagrange form on t = 0, ½, 1.
      const double rho = rho_lo * (2 * t - 1) * (t - 1) + rho_mid * 4 * t * (1 - t) + rho_hi * t * (2 * t - 1);
      return matrix(h, rho);
    };
    const LongitudinalModel* m = &model;
    segment.exact_matrix = [=](double h) { return matrix(h, m->DensityAt(h)); };
    // Column 4 (ΔH) of A is zero at both ends, hence throughout (entries affine in the coefficients).
    const Matrix5d A_lo = segment.exact_matrix(lo), A_hi = segment.exact_matrix(hi);
    const bool zero_lo = A_lo.col(kDeltaH).cwiseAbs().maxCoeff() == 0.0;
    const bool zero_hi = A_hi.col(kDeltaH).cwiseAbs().maxCoeff() == 0.0;
    segment.real_root_at_lower = zero_lo;
    segment.real_root_at_upper = zero_hi;
    segment.deflated = zero_lo && zero_hi &&
                       (source != Source::kTable || interpolation_degree == 1 ||
                        segment.exact_matrix(0.5 * (lo + hi)).col(kDeltaH).cwiseAbs().maxCoeff() == 0.0);
    if (segment.deflated) segment.real_root_at_lower = segment.real_root_at_upper = false;
    segments.push_back(std::move(segment));
  }
  return segments;
}

}  // namespace

SampledSearchResult SampledCrossingSearch(const std::function<Matrix5d(double)>& matrix,
                                          const std::vector<double>& knots, int samples_per_segment,
                                          double tolerance_m) {
  GESWEEP_DEMAND(knots.size() >= 2 && samples_per_segment >= 0);
  SampledSearchResult result;
  auto sigma = [&](double height_m) {
    ++result.margin_evaluations;
    return AnalyzeModes(matrix(height_m)).stability_margin_per_s;
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

std::string_view ToString(CrossingKind kind) {
  switch (kind) {
    case CrossingKind::kHopf: return "hopf";
    case CrossingKind::kReal: return "real";
    case CrossingKind::kDiscontinuity: return "table_row";
    case CrossingKind::kSigma: return "sigma";
  }
  GESWEEP_UNREACHABLE();
}

CrossingSearchResult CrossingSearch(const std::vector<MatrixSegment>& segments, double wingspan_m) {
  GESWEEP_DEMAND(!segments.empty());
  return Search(segments, wingspan_m).Run();
}

BoundaryResult FindBoundary(const LongitudinalModel& model, double speed_mps, const BoundaryOptions& options) {
  const Aircraft& aircraft = model.aircraft();
  BoundaryResult result;
  result.speed_mps = speed_mps;
  result.method = options.method;
  result.lower_height_m = std::isnan(options.lower_height_m) ? aircraft.wheel_contact_height_m : options.lower_height_m;
  result.upper_height_m = std::isnan(options.upper_height_m) ? aircraft.table_heights_m.back() : options.upper_height_m;
  GESWEEP_DEMAND(result.upper_height_m > result.lower_height_m);

  bool all_stable = false, all_unstable = false;
  if (options.method == BoundaryMethod::kSampled) {
    std::vector<double> margins;
    SampledSearch(model, speed_mps, options, result, margins);
    if (margins.empty()) return result;
    all_stable = std::all_of(margins.begin(), margins.end(), [](double s) { return s < 0; });
    all_unstable = std::all_of(margins.begin(), margins.end(), [](double s) { return s >= 0; });
  } else {
    const std::vector<MatrixSegment> segments = AircraftSegments(
        model, speed_mps, result.lower_height_m, result.upper_height_m, &result.density_interpolation_bound);
    result.segments = static_cast<int>(segments.size());
    CrossingSearchResult search = CrossingSearch(segments, aircraft.wingspan_m);
    result.polynomial_evaluations = search.polynomial_evaluations;
    result.margin_evaluations = search.eigen_analyses;
    if (!search.finite) {
      result.reason = search.non_finite_reason;
      result.certificate = "none: " + search.non_finite_reason;
      return result;
    }
    result.certified = search.certified;
    if (search.certified) {
      char text[320];
      std::snprintf(text, sizeof text,
                    "every root of Delta4 and a5 in %.7g m to %.7g m isolated on %zu segments (Descartes' rule on "
                    "the Bernstein basis); rho(H) by its quadratic interpolant per segment, relative error <= %.2g",
                    result.lower_height_m, result.upper_height_m, segments.size(),
                    result.density_interpolation_bound);
      result.certificate = text;
    } else {
      result.certificate = "not certified: " + search.uncertified_reason;
    }
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
  }
  for (auto& crossing : result.crossings) crossing.height_over_span = crossing.height_m / aircraft.wingspan_m;
  for (const auto& crossing : result.crossings) {
    if (crossing.stable_above && !crossing.stable_below) {
      result.height_m = crossing.height_m;
      result.height_over_span = crossing.height_m / aircraft.wingspan_m;
      break;
    }
  }
  if (!result.height_m) {
    const std::string range = FormatMetres(result.lower_height_m) + " to " + FormatMetres(result.upper_height_m);
    if (all_stable) {
      result.reason = "stable at every height from " + range;
    } else if (all_unstable) {
      result.reason = "unstable at every height from " + range;
    } else {
      result.reason = "no height in " + range + " has unstable below and stable above";
    }
  }
  return result;
}

}  // namespace gesweep
