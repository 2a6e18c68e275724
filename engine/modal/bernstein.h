#pragma once
/// Polynomials on t ∈ [0, 1] in the Bernstein basis, and the certified isolation of their real roots
/// by Descartes' rule of signs with de Casteljau subdivision (Lane & Riesenfeld 1981; Mourrain,
/// Rouillier & Roy 2005). The boundary finder (engine/modal/boundary.h) builds the Hurwitz criteria of
/// each table segment in this form (docs/model.md, "The boundary by the Hurwitz criterion").

#include <array>
#include <vector>

namespace gesweep {

/// p(t) = Σₖ bₖ C(n,k) tᵏ (1−t)ⁿ⁻ᵏ, degree n ≤ kMaxDegree.
class BernsteinPolynomial {
 public:
  static constexpr int kMaxDegree = 63;

  /// The zero polynomial of degree 0. Only the coefficients up to the degree are stored and copied.
  BernsteinPolynomial() { b_[0] = 0.0; }
  BernsteinPolynomial(const BernsteinPolynomial& other) : degree_(other.degree_) { CopyFrom(other); }
  BernsteinPolynomial& operator=(const BernsteinPolynomial& other) {
    degree_ = other.degree_;
    CopyFrom(other);
    return *this;
  }
  /// The constant c as a degree-0 polynomial.
  static BernsteinPolynomial Constant(double c);
  /// From its Bernstein coefficients b₀…bₙ (n ≤ kMaxDegree).
  static BernsteinPolynomial FromCoefficients(const std::vector<double>& b);
  /// From values at the n+1 Chebyshev points of BernsteinPolynomial::ChebyshevNodes(n + 1), for a
  /// polynomial known to have degree ≤ `degree` ≤ n: the Chebyshev interpolant (exact for such a
  /// polynomial, up to rounding) truncated to `degree` and converted to the Bernstein basis.
  /// `tail` receives |the first Chebyshev coefficient| dropped by the truncation (rounding-level
  /// when the degree bound holds).
  static BernsteinPolynomial FromChebyshevSamples(const std::vector<double>& values, int degree,
                                                  double* tail);
  /// The same from m values in an array.
  static BernsteinPolynomial FromChebyshevSamples(const double* values, int m, int degree, double* tail);
  /// The m Chebyshev points of the first kind on [0, 1], ascending.
  static std::vector<double> ChebyshevNodes(int m);

  int degree() const { return degree_; }
  double coefficient(int k) const { return b_[static_cast<std::size_t>(k)]; }
  /// max |bₖ|: a bound on max |p| over [0, 1] (the basis is a partition of unity).
  double MaxAbsCoefficient() const;

  /// p(t) for t ∈ [0, 1] in O(n): Horner's rule in t/(1 − t) (or (1 − t)/t above ½) on the
  /// binomially scaled coefficients (Schumaker & Volk 1986); the error is of order n·ε·max |bₖ|, as
  /// de Casteljau's.
  double operator()(double t) const;
  BernsteinPolynomial Derivative() const;
  BernsteinPolynomial Elevated(int degree) const;  ///< the same polynomial in a higher degree
  /// The two halves [0, ½] and [½, 1], each re-parametrised to [0, 1].
  void Split(BernsteinPolynomial& left, BernsteinPolynomial& right) const;

  /// p(t)/t when p(0) = 0 and p(t)/(1 − t) when p(1) = 0 (the end coefficient is dropped).
  BernsteinPolynomial DividedByT() const;
  BernsteinPolynomial DividedByOneMinusT() const;

  friend BernsteinPolynomial operator*(const BernsteinPolynomial& p, const BernsteinPolynomial& q);
  friend BernsteinPolynomial operator+(const BernsteinPolynomial& p, const BernsteinPolynomial& q);
  friend BernsteinPolynomial operator-(const BernsteinPolynomial& p, const BernsteinPolynomial& q);

 private:
  void CopyFrom(const BernsteinPolynomial& other) {
    for (int k = 0; k <= degree_; ++k)
      b_[static_cast<std::size_t>(k)] = other.b_[static_cast<std::size_t>(k)];
  }
  int degree_ = 0;
  std::array<double, kMaxDegree + 1> b_;  // b_[0…degree_] are meaningful, the rest undefined
};

/// One interval of an isolation.
struct RootInterval {
  double lower_t = 0, upper_t = 0;
  /// true: exactly one root, simple, where p changes sign (certified by Descartes' rule: one sign
  /// variation). false: the interval reached `resolution` undecided; `sign_change` says whether p
  /// changes sign across it (an odd number of roots) or not (an even number, possibly none).
  bool certified = true;
  bool sign_change = true;
};

/// The isolation of the roots of p in [0, 1].
struct RootIsolation {
  std::vector<RootInterval> intervals;  ///< ascending, disjoint
  /// The sign of p at t = 0 and t = 1: +1, −1, or 0 when |p| ≤ the rounding allowance there.
  int sign_at_lower = 0, sign_at_upper = 0;
  int subdivisions = 0;
};

/// Isolates every real root of p in (0, 1). A coefficient with |bₖ| ≤ `allowance` (the rounding of
/// the coefficients) counts as of unknown sign, so the count of sign variations is an upper bound for
/// every polynomial within `allowance` of p. Subdivision stops at intervals of width `resolution`
/// (or after `max_subdivisions`; then the rest is returned uncertified). An interval touching t = 0
/// or t = 1 where |p| ≤ allowance is returned uncertified without a sign change: the caller decides
/// what a root at a segment's end means.
RootIsolation IsolateRoots(const BernsteinPolynomial& p, double allowance, double resolution = 0x1p-40,
                           int max_subdivisions = 400);

}  // namespace gesweep
