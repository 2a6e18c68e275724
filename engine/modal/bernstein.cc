#include "engine/modal/bernstein.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

constexpr int kMax = BernsteinPolynomial::kMaxDegree;
// Chebyshev-to-Bernstein conversion is tabulated up to this degree (the characteristic coefficients
// of a PCHIP segment reach 15).
constexpr int kMaxConversionDegree = 24;

struct Binomials {
  double c[kMax + 1][kMax + 1] = {};
  double inverse[kMax + 1][kMax + 1] = {};  // 1/C(n, k): products divide by them
  Binomials() {
    for (int n = 0; n <= kMax; ++n) {
      c[n][0] = c[n][n] = 1.0;
      for (int k = 1; k < n; ++k) c[n][k] = c[n - 1][k - 1] + c[n - 1][k];
      for (int k = 0; k <= n; ++k) inverse[n][k] = 1.0 / c[n][k];
    }
  }
};
const Binomials& Binomial() {
  static const Binomials table;
  return table;
}

// conversion[D][m][k]: the k-th Bernstein coefficient (degree D) of T_m(2t − 1), m ≤ D.
struct ChebyshevToBernstein {
  std::vector<std::vector<std::vector<double>>> conversion;
  ChebyshevToBernstein() {
    conversion.resize(kMaxConversionDegree + 1);
    // T_m at its own degree m, by T_{m+1} = 2x T_m − T_{m−1} with x = 2t − 1 = [−1, 1] in degree 1.
    std::vector<BernsteinPolynomial> T;
    T.push_back(BernsteinPolynomial::Constant(1.0));
    const BernsteinPolynomial x = BernsteinPolynomial::FromCoefficients({-1.0, 1.0});
    T.push_back(x);
    for (int m = 1; m < kMaxConversionDegree; ++m) {
      T.push_back(BernsteinPolynomial::Constant(2.0) * x * T[static_cast<std::size_t>(m)] -
                  T[static_cast<std::size_t>(m - 1)]);
    }
    for (int D = 0; D <= kMaxConversionDegree; ++D) {
      conversion[static_cast<std::size_t>(D)].resize(static_cast<std::size_t>(D) + 1);
      for (int m = 0; m <= D; ++m) {
        const BernsteinPolynomial e = T[static_cast<std::size_t>(m)].Elevated(D);
        auto& row = conversion[static_cast<std::size_t>(D)][static_cast<std::size_t>(m)];
        for (int k = 0; k <= D; ++k) row.push_back(e.coefficient(k));
      }
    }
  }
};

// cos(kπ(i + ½)/m) for the Chebyshev transforms of m ≤ kMaxConversionDegree + 2 nodes.
struct CosineTables {
  std::vector<std::vector<double>> table;  // table[m][k·m + i]
  CosineTables() {
    table.resize(kMaxConversionDegree + 3);
    for (std::size_t m = 1; m < table.size(); ++m) {
      auto& t = table[m];
      t.resize(m * m);
      for (std::size_t k = 0; k < m; ++k)
        for (std::size_t i = 0; i < m; ++i) t[k * m + i] = std::cos(k * std::numbers::pi * (i + 0.5) / m);
    }
  }
};
const CosineTables& Cosines() {
  static const CosineTables tables;
  return tables;
}

// The linear map from the values at m Chebyshev nodes to the Bernstein coefficients (degree d) of
// the Chebyshev interpolant truncated to degree d — the discrete cosine transform and the
// Chebyshev-to-Bernstein conversion in one (d+1)×m matrix — and the row that gives the Chebyshev
// coefficient d + 1 (the first one dropped; empty when d + 1 = m). Built once per (m, d), on first use.
struct FitMatrix {
  std::vector<double> bernstein;  // row j: coefficient b_j
  std::vector<double> tail;
};

constexpr int kMaxNodes = kMaxConversionDegree + 2;

const FitMatrix& Fit(int m, int d) {
  struct Slot {
    std::once_flag built;
    FitMatrix matrix;
  };
  static Slot slots[kMaxNodes + 1][kMaxConversionDegree + 1];
  Slot& slot = slots[m][d];
  std::call_once(slot.built, [&] {
    static const ChebyshevToBernstein table;
    const auto nodes = static_cast<std::size_t>(m);
    const auto terms = static_cast<std::size_t>(d) + 1;  // the coefficients 0…d
    const double* cosines = Cosines().table[nodes].data();
    // Node i is x_i = −cos θ_i, θ_i = π(i + ½)/m, so T_k(x_i) = (−1)^k cos(k θ_i), and the
    // interpolant's Chebyshev coefficient is c_k = w_k Σ_i v_i (−1)^k cos(k θ_i), w_k = 2/m (1/m for k = 0).
    auto weight = [m](std::size_t k) { return (k % 2 == 0 ? 2.0 : -2.0) / m * (k == 0 ? 0.5 : 1.0); };
    const auto& conversion = table.conversion[terms - 1];
    slot.matrix.bernstein.assign(terms * nodes, 0.0);
    for (std::size_t k = 0; k < terms; ++k) {
      const auto& row = conversion[k];
      for (std::size_t j = 0; j < terms; ++j) {
        for (std::size_t i = 0; i < nodes; ++i)
          slot.matrix.bernstein[j * nodes + i] += row[j] * weight(k) * cosines[k * nodes + i];
      }
    }
    if (terms < nodes) {
      slot.matrix.tail.reserve(nodes);
      for (std::size_t i = 0; i < nodes; ++i)
        slot.matrix.tail.push_back(weight(terms) * cosines[terms * nodes + i]);
    }
  });
  return slot.matrix;
}

int SignOf(double value, double allowance) {
  if (value > allowance) return 1;
  if (value < -allowance) return -1;
  return 0;
}

// The largest number of sign variations of any sequence within `allowance` of b: coefficients of
// unknown sign (0) are free.
int MaxSignVariations(const BernsteinPolynomial& p, double allowance) {
  int variations = 0;
  int last = 0;     // last certain sign, 0 before the first
  int unknown = 0;  // unknown signs since it
  for (int k = 0; k <= p.degree(); ++k) {
    const int s = SignOf(p.coefficient(k), allowance);
    if (s == 0) {
      ++unknown;
      continue;
    }
    if (last == 0) {
      variations += unknown;
    } else {
      const int gaps = unknown + 1;
      const bool must_differ = s != last;
      variations += ((gaps % 2 == 1) == must_differ) ? gaps : gaps - 1;
    }
    last = s;
    unknown = 0;
  }
  return last == 0 ? p.degree() : variations + unknown;
}

}  // namespace

BernsteinPolynomial BernsteinPolynomial::FromCoefficients(const std::vector<double>& b) {
  GESWEEP_DEMAND(!b.empty() && b.size() <= kMax + 1);
  BernsteinPolynomial p;
  p.degree_ = static_cast<int>(b.size()) - 1;
  std::copy(b.begin(), b.end(), p.b_.begin());
  return p;
}

BernsteinPolynomial BernsteinPolynomial::Constant(double c) {
  BernsteinPolynomial p;
  p.degree_ = 0;
  p.b_[0] = c;
  return p;
}

std::vector<double> BernsteinPolynomial::ChebyshevNodes(int m) {
  std::vector<double> t(static_cast<std::size_t>(m));
  for (int i = 0; i < m; ++i) {
    t[static_cast<std::size_t>(i)] = 0.5 * (1.0 - std::cos(std::numbers::pi * (i + 0.5) / m));
  }
  return t;
}

BernsteinPolynomial BernsteinPolynomial::FromChebyshevSamples(const std::vector<double>& values, int degree,
                                                              double* tail) {
  return FromChebyshevSamples(values.data(), static_cast<int>(values.size()), degree, tail);
}

BernsteinPolynomial BernsteinPolynomial::FromChebyshevSamples(const double* values, int m, int degree,
                                                              double* tail) {
  GESWEEP_DEMAND(m >= 1 && degree >= 0 && degree < m && degree <= kMaxConversionDegree && m <= kMaxNodes);
  const FitMatrix& fit = Fit(m, degree);
  BernsteinPolynomial p;
  p.degree_ = degree;
  const auto nodes = static_cast<std::size_t>(m);
  for (std::size_t j = 0; j <= static_cast<std::size_t>(degree); ++j) {
    const double* row = fit.bernstein.data() + j * nodes;
    double sum = 0;
    for (std::size_t i = 0; i < nodes; ++i) sum += row[i] * values[i];
    p.b_[j] = sum;
  }
  if (tail) {
    double dropped = 0;
    for (std::size_t i = 0; i < fit.tail.size(); ++i) dropped += fit.tail[i] * values[i];
    *tail = std::abs(dropped);
  }
  return p;
}

double BernsteinPolynomial::MaxAbsCoefficient() const {
  double largest = 0;
  for (int k = 0; k <= degree_; ++k) largest = std::max(largest, std::abs(b_[static_cast<std::size_t>(k)]));
  return largest;
}

double BernsteinPolynomial::operator()(double t) const {
  const int n = degree_;
  if (n == 0) return b_[0];
  const auto& C = Binomial().c[n];
  if (t <= 0.5) {
    // (1 − t)ⁿ Σ bₖ C(n,k) sᵏ, s = t/(1 − t) ≤ 1
    const double s = t / (1.0 - t);
    double value = b_[static_cast<std::size_t>(n)];
    for (int k = n - 1; k >= 0; --k) value = value * s + b_[static_cast<std::size_t>(k)] * C[k];
    double power = 1.0;
    for (int k = 0; k < n; ++k) power *= 1.0 - t;
    return value * power;
  }
  // tⁿ Σ bₖ C(n,k) rⁿ⁻ᵏ, r = (1 − t)/t < 1
  const double r = (1.0 - t) / t;
  double value = b_[0];
  for (int k = 1; k <= n; ++k) value = value * r + b_[static_cast<std::size_t>(k)] * C[k];
  double power = 1.0;
  for (int k = 0; k < n; ++k) power *= t;
  return value * power;
}

BernsteinPolynomial BernsteinPolynomial::Derivative() const {
  BernsteinPolynomial d;
  if (degree_ == 0) return Constant(0.0);
  d.degree_ = degree_ - 1;
  for (std::size_t k = 0; k < static_cast<std::size_t>(degree_); ++k) d.b_[k] = degree_ * (b_[k + 1] - b_[k]);
  return d;
}

BernsteinPolynomial BernsteinPolynomial::Elevated(int degree) const {
  GESWEEP_DEMAND(degree >= degree_ && degree <= kMax);
  if (degree == degree_) return *this;
  BernsteinPolynomial ones;
  ones.degree_ = degree - degree_;
  for (int k = 0; k <= ones.degree_; ++k) ones.b_[static_cast<std::size_t>(k)] = 1.0;
  return *this * ones;
}

BernsteinPolynomial BernsteinPolynomial::DividedByT() const {
  if (degree_ == 0) return Constant(0.0);
  // t·q(t) in degree n has coefficients q_{j−1}·j/n (j ≥ 1) and 0.
  BernsteinPolynomial q;
  q.degree_ = degree_ - 1;
  for (int j = 1; j <= degree_; ++j)
    q.b_[static_cast<std::size_t>(j - 1)] = b_[static_cast<std::size_t>(j)] * degree_ / j;
  return q;
}

BernsteinPolynomial BernsteinPolynomial::DividedByOneMinusT() const {
  if (degree_ == 0) return Constant(0.0);
  // (1 − t)·q(t) in degree n has coefficients q_j·(n − j)/n (j < n) and 0.
  BernsteinPolynomial q;
  q.degree_ = degree_ - 1;
  for (int j = 0; j < degree_; ++j)
    q.b_[static_cast<std::size_t>(j)] = b_[static_cast<std::size_t>(j)] * degree_ / (degree_ - j);
  return q;
}

void BernsteinPolynomial::Split(BernsteinPolynomial& left, BernsteinPolynomial& right) const {
  std::array<double, kMax + 1> work;
  std::copy(b_.begin(), b_.begin() + degree_ + 1, work.begin());
  left.degree_ = right.degree_ = degree_;
  const auto n = static_cast<std::size_t>(degree_);
  left.b_[0] = work[0];
  right.b_[n] = work[n];
  for (std::size_t r = 1; r <= n; ++r) {
    for (std::size_t k = 0; k <= n - r; ++k) work[k] = 0.5 * (work[k] + work[k + 1]);
    left.b_[r] = work[0];
    right.b_[n - r] = work[n - r];
  }
}

BernsteinPolynomial operator*(const BernsteinPolynomial& p, const BernsteinPolynomial& q) {
  const int m = p.degree_, n = q.degree_;
  GESWEEP_DEMAND(m + n <= BernsteinPolynomial::kMaxDegree);
  const auto& C = Binomial().c;
  std::array<double, kMax + 1> ps, qs;
  const auto p_count = static_cast<std::size_t>(m) + 1, q_count = static_cast<std::size_t>(n) + 1;
  for (std::size_t i = 0; i < p_count; ++i) ps[i] = p.b_[i] * C[m][i];
  for (std::size_t j = 0; j < q_count; ++j) qs[j] = q.b_[j] * C[n][j];
  BernsteinPolynomial r;
  r.degree_ = m + n;
  const std::size_t r_count = p_count + q_count - 1;
  for (std::size_t k = 0; k < r_count; ++k) r.b_[k] = 0.0;
  for (std::size_t i = 0; i < p_count; ++i) {
    for (std::size_t j = 0; j < q_count; ++j) r.b_[i + j] += ps[i] * qs[j];
  }
  const auto& inverse = Binomial().inverse[m + n];
  for (std::size_t k = 0; k < r_count; ++k) r.b_[k] *= inverse[k];
  return r;
}

BernsteinPolynomial operator+(const BernsteinPolynomial& p, const BernsteinPolynomial& q) {
  const int n = std::max(p.degree_, q.degree_);
  BernsteinPolynomial a = p.Elevated(n), b = q.Elevated(n);
  for (int k = 0; k <= n; ++k) a.b_[static_cast<std::size_t>(k)] += b.b_[static_cast<std::size_t>(k)];
  return a;
}

BernsteinPolynomial operator-(const BernsteinPolynomial& p, const BernsteinPolynomial& q) {
  const int n = std::max(p.degree_, q.degree_);
  BernsteinPolynomial a = p.Elevated(n), b = q.Elevated(n);
  for (int k = 0; k <= n; ++k) a.b_[static_cast<std::size_t>(k)] -= b.b_[static_cast<std::size_t>(k)];
  return a;
}

RootIsolation IsolateRoots(const BernsteinPolynomial& p, double allowance, double resolution,
                           int max_subdivisions) {
  RootIsolation result;
  const int n = p.degree();
  result.sign_at_lower = SignOf(p.coefficient(0), allowance);
  result.sign_at_upper = SignOf(p.coefficient(n), allowance);
  // No sign variation (the usual case of a segment far from any root): no root, nothing to subdivide.
  if (MaxSignVariations(p, allowance) == 0) return result;
  struct Piece {
    BernsteinPolynomial poly;
    double lower, upper;
  };
  // Depth first, left half on top of the stack, so intervals come out ascending.
  std::vector<Piece> stack;
  stack.push_back({p, 0.0, 1.0});
  struct Undecided {
    double lower, upper;
    int sign_lower, sign_upper;
  };
  std::vector<Undecided> undecided;
  while (!stack.empty()) {
    Piece piece = std::move(stack.back());
    stack.pop_back();
    const int variations = MaxSignVariations(piece.poly, allowance);
    if (variations == 0) continue;
    const int s0 = SignOf(piece.poly.coefficient(0), allowance);
    const int s1 = SignOf(piece.poly.coefficient(n), allowance);
    const bool ends_differ = s0 != 0 && s1 != 0 && s0 != s1;
    if (variations == 1 && ends_differ) {
      result.intervals.push_back({piece.lower, piece.upper, true, true});
      continue;
    }
    const bool at_end_of_range = (piece.lower == 0.0 && s0 == 0) || (piece.upper == 1.0 && s1 == 0);
    const double width = piece.upper - piece.lower;
    // Next to an end where p ~ 0 nothing more can be decided: stop well before `resolution`.
    const double stop_width = at_end_of_range ? std::max(resolution, 0x1p-24) : resolution;
    // Where every coefficient is within the allowance of 0, p is indistinguishable from 0: stop.
    bool all_unknown = true;
    for (int k = 0; k <= n && all_unknown; ++k)
      all_unknown = SignOf(piece.poly.coefficient(k), allowance) == 0;
    if (width <= stop_width || all_unknown || result.subdivisions >= max_subdivisions) {
      undecided.push_back({piece.lower, piece.upper, s0, s1});
      continue;
    }
    ++result.subdivisions;
    Piece left{{}, piece.lower, 0.5 * (piece.lower + piece.upper)};
    Piece right{{}, left.upper, piece.upper};
    piece.poly.Split(left.poly, right.poly);
    stack.push_back(std::move(right));
    stack.push_back(std::move(left));
  }
  // Adjacent undecided pieces form one undecided interval; its sign change is that of its ends.
  std::sort(undecided.begin(), undecided.end(),
            [](const auto& a, const auto& b) { return a.lower < b.lower; });
  for (std::size_t i = 0; i < undecided.size();) {
    Undecided merged = undecided[i];
    std::size_t j = i + 1;
    while (j < undecided.size() && undecided[j].lower == merged.upper) {
      merged.upper = undecided[j].upper;
      merged.sign_upper = undecided[j].sign_upper;
      ++j;
    }
    const bool differ =
        merged.sign_lower != 0 && merged.sign_upper != 0 && merged.sign_lower != merged.sign_upper;
    result.intervals.push_back({merged.lower, merged.upper, false, differ});
    i = j;
  }
  std::sort(result.intervals.begin(), result.intervals.end(),
            [](const auto& a, const auto& b) { return a.lower_t < b.lower_t; });
  return result;
}

}  // namespace gesweep
