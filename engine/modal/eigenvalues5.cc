#include "engine/modal/eigenvalues5.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <utility>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

// The kernel works on a row-major copy: h[i][j] is row i, column j.
using Square = double[5][5];
constexpr int kN = 5;

// LAPACK's machine constants (dlamch) for IEEE double.
constexpr double kSafeMinimum = 0x1p-1022;  // dlamch('S')
constexpr double kPrecision = 0x1p-52;      // dlamch('P') = eps·base
constexpr double kEpsilon = 0x1p-53;        // dlamch('E')

// A sum of squares in this range is neither overflowed nor so small that its rounding is lost.
constexpr double kPlainSquaresLow = 0x1p-1000;
constexpr double kPlainSquaresHigh = 0x1p+1000;

// The 2-norm of x[0..n): the plain sum of squares, in order, as BLAS dnrm2 computes it for entries
// in its middle range; scaled by the largest entry when that sum would over- or underflow.
template <int n>
double Norm2(const double* x, std::ptrdiff_t stride) {
  double sum = 0;
  for (int i = 0; i < n; ++i) sum += x[i * stride] * x[i * stride];
  if (sum >= kPlainSquaresLow && sum <= kPlainSquaresHigh) return std::sqrt(sum);
  double largest = 0;
  for (int i = 0; i < n; ++i) largest = std::max(largest, std::abs(x[i * stride]));
  if (largest == 0.0) return 0.0;
  double scaled = 0;
  for (int i = 0; i < n; ++i) {
    const double y = x[i * stride] / largest;
    scaled += y * y;
  }
  return largest * std::sqrt(scaled);
}

// sqrt(x² + y²) without destructive over- or underflow (dlapy2).
double Hypot2(double x, double y) {
  const double sum = x * x + y * y;
  if (sum >= kPlainSquaresLow && sum <= kPlainSquaresHigh) return std::sqrt(sum);
  return std::hypot(x, y);
}

// ---------------------------------------------------------------------------------------------
// dgebal, job 'S'.

void BalanceInPlace(Square a, double scale[kN]) {
  constexpr double kRadix = 2.0;
  constexpr double kFactor = 0.95;
  constexpr double kSfmin1 = kSafeMinimum / kPrecision;
  constexpr double kSfmax1 = 1.0 / kSfmin1;
  constexpr double kSfmin2 = kSfmin1 * kRadix;
  constexpr double kSfmax2 = 1.0 / kSfmin2;
  // dgebal iterates until no step is taken; every step cuts a row-and-column norm sum by 5 %, so
  // this bound (never reached in the tests) only guards against a broken invariant.
  constexpr int kMaxSweeps = 1000;
  constexpr double kQuarterAndRounding = 0.25 * (1.0 + 1e-12), kFourLessRounding = 4.0 * (1.0 - 1e-12);
  constexpr double kModerateRatio = 0x1p+100;  // of the squared norms
  for (int i = 0; i < kN; ++i) scale[i] = 1.0;
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    bool changed = false;
    for (int i = 0; i < kN; ++i) {
      double cs[kN], rs[kN];
      for (int j = 0; j < kN; ++j) {
        cs[j] = a[j][i] * a[j][i];
        rs[j] = a[i][j] * a[i][j];
      }
      // The filter below in a short chain of additions; dnrm2's order further down.
      const double c2_filter = ((cs[0] + cs[1]) + (cs[2] + cs[3])) + cs[4];
      const double r2_filter = ((rs[0] + rs[1]) + (rs[2] + rs[3])) + rs[4];
      // r/2 ≤ c < 2r with room for the rounding of the sums and roots: neither loop below would move
      // f from 1, so there is no step (most rows of most sweeps, and every row of the last one).
      if (c2_filter >= kPlainSquaresLow && c2_filter <= kPlainSquaresHigh && r2_filter >= kPlainSquaresLow &&
          r2_filter <= kPlainSquaresHigh && c2_filter >= kQuarterAndRounding * r2_filter &&
          c2_filter <= kFourLessRounding * r2_filter) {
        continue;
      }
      double c2 = 0, r2 = 0;
      for (int j = 0; j < kN; ++j) {
        c2 += cs[j];
        r2 += rs[j];
      }
      const bool plain = c2 >= kPlainSquaresLow && c2 <= kPlainSquaresHigh && r2 >= kPlainSquaresLow &&
                         r2 <= kPlainSquaresHigh;
      double c = plain ? std::sqrt(c2) : Norm2<kN>(&a[0][i], kN);
      double r = plain ? std::sqrt(r2) : Norm2<kN>(&a[i][0], 1);
      if (c == 0.0 || r == 0.0) continue;
      double g = r / kRadix;
      double f = 1.0;
      const double s = c + r;
      if (plain && c2 <= kModerateRatio * r2 && r2 <= kModerateRatio * c2) {
        // Norms within 2^±50 of each other and of 1 within 2^±500: every scaled quantity stays far
        // inside dgebal's guards [2^−969, 2^969], which therefore cannot stop the loops.
        while (c < g) {
          f *= kRadix;
          c *= kRadix;
          r /= kRadix;
          g /= kRadix;
        }
        g = c / kRadix;
        while (g >= r) {
          f /= kRadix;
          c /= kRadix;
          g /= kRadix;
          r *= kRadix;
        }
      } else {
        double ca = 0, ra = 0;
        for (int j = 0; j < kN; ++j) {
          ca = std::max(ca, std::abs(a[j][i]));
          ra = std::max(ra, std::abs(a[i][j]));
        }
        while (c < g && std::max({f, c, ca}) < kSfmax2 && std::min({r, g, ra}) > kSfmin2) {
          f *= kRadix;
          c *= kRadix;
          ca *= kRadix;
          r /= kRadix;
          g /= kRadix;
          ra /= kRadix;
        }
        g = c / kRadix;
        while (g >= r && std::max(r, ra) < kSfmax2 && std::min({f, c, g, ca}) > kSfmin2) {
          f /= kRadix;
          c /= kRadix;
          g /= kRadix;
          ca /= kRadix;
          r *= kRadix;
          ra *= kRadix;
        }
      }
      if (c + r >= kFactor * s) continue;
      if (f < 1.0 && scale[i] < 1.0 && f * scale[i] <= kSfmin1) continue;
      if (f > 1.0 && scale[i] > 1.0 && scale[i] >= kSfmax1 / f) continue;
      const double inverse = 1.0 / f;
      scale[i] *= f;
      changed = true;
      for (int j = 0; j < kN; ++j) a[i][j] *= inverse;
      for (int j = 0; j < kN; ++j) a[j][i] *= f;
    }
    if (!changed) return;
  }
}

// ---------------------------------------------------------------------------------------------
// dlarfg: the Householder reflector I − τ·[1; v][1; v]ᵀ that maps (alpha, x) to (β, 0). On return
// alpha = β and x = v. n − 1 = the length of x (1 or 2 here, 1 to 3 in the reduction).

template <int m>  // m = length of x
[[gnu::always_inline]] inline double Reflector(double& alpha, double* x, std::ptrdiff_t stride) {
  double squares = alpha * alpha;
  bool x_zero = true;
  for (int i = 0; i < m; ++i) {
    squares += x[i * stride] * x[i * stride];
    x_zero = x_zero && x[i * stride] == 0.0;
  }
  if (x_zero) return 0.0;
  double beta;
  int rescalings = 0;
  constexpr double kSafeMin = kSafeMinimum / kEpsilon;
  if (squares >= kPlainSquaresLow && squares <= kPlainSquaresHigh) {
    // |β| ≥ 2⁻⁵⁰⁰, far above dlarfg's rescaling threshold: one square root.
    beta = -std::copysign(std::sqrt(squares), alpha);
  } else {
    beta = -std::copysign(Hypot2(alpha, Norm2<m>(x, stride)), alpha);
    if (std::abs(beta) < kSafeMin) {
      // β may be inaccurate: scale x and alpha up and recompute (at most 20 times, as dlarfg).
      constexpr double kInverse = 1.0 / kSafeMin;
      do {
        ++rescalings;
        for (int i = 0; i < m; ++i) x[i * stride] *= kInverse;
        beta *= kInverse;
        alpha *= kInverse;
      } while (std::abs(beta) < kSafeMin && rescalings < 20);
      beta = -std::copysign(Hypot2(alpha, Norm2<m>(x, stride)), alpha);
    }
  }
  const double tau = (beta - alpha) / beta;
  const double scale = 1.0 / (alpha - beta);
  for (int i = 0; i < m; ++i) x[i * stride] *= scale;
  for (int j = 0; j < rescalings; ++j) beta *= kSafeMin;
  alpha = beta;
  return tau;
}

// ---------------------------------------------------------------------------------------------
// dgehd2: H = QᵀAQ upper Hessenberg, by three reflectors (columns 0, 1, 2).

template <int k>
void ReduceColumn(Square h) {
  constexpr int m = kN - k - 2;  // entries below the subdiagonal in column k
  double v[m];
  for (int i = 0; i < m; ++i) v[i] = h[k + 2 + i][k];
  double alpha = h[k + 1][k];
  const double tau = Reflector<m>(alpha, v, 1);
  h[k + 1][k] = alpha;
  for (int i = 0; i < m; ++i) h[k + 2 + i][k] = 0.0;
  if (tau == 0.0) return;
  // From the right, on columns k+1…4 of every row: h ← h − τ (h u) uᵀ, u = [1; v].
  for (int i = 0; i < kN; ++i) {
    double w = h[i][k + 1];
    for (int j = 0; j < m; ++j) w += h[i][k + 2 + j] * v[j];
    w *= tau;
    h[i][k + 1] -= w;
    for (int j = 0; j < m; ++j) h[i][k + 2 + j] -= w * v[j];
  }
  // From the left, on rows k+1…4 of columns k+1…4: h ← h − τ u (uᵀ h).
  for (int j = k + 1; j < kN; ++j) {
    double w = h[k + 1][j];
    for (int i = 0; i < m; ++i) w += v[i] * h[k + 2 + i][j];
    w *= tau;
    h[k + 1][j] -= w;
    for (int i = 0; i < m; ++i) h[k + 2 + i][j] -= w * v[i];
  }
}

void HessenbergInPlace(Square h) {
  ReduceColumn<0>(h);
  ReduceColumn<1>(h);
  ReduceColumn<2>(h);
}

// ---------------------------------------------------------------------------------------------
// dlanv2: the eigenvalues of the 2×2 block [a b; c d] after its standardisation (real pair: made
// upper triangular; complex pair: equal diagonal entries and b·c < 0).

void StandardisedPair(double a, double b, double c, double d, std::complex<double>& first,
                      std::complex<double>& second) {
  constexpr double kMultiple = 4.0;
  constexpr double kEps = kPrecision;
  constexpr double kSafmn2 = 0x1p-485;  // base^int(log(safmin/eps)/log(base)/2)
  constexpr double kSafmx2 = 1.0 / kSafmn2;
  if (c == 0.0) {
    // already triangular
  } else if (b == 0.0) {
    // swap rows and columns
    std::swap(a, d);
    b = -c;
    c = 0.0;
  } else if (a - d != 0.0 || std::signbit(b) == std::signbit(c)) {
    // not yet standard (a = d with b·c < 0 is a standard complex pair already: nothing to do)
    double temp = a - d;
    double p = 0.5 * temp;
    const double bcmax = std::max(std::abs(b), std::abs(c));
    const double bcmis = std::min(std::abs(b), std::abs(c)) * std::copysign(1.0, b) * std::copysign(1.0, c);
    double scale = std::max(std::abs(p), bcmax);
    double z = (p / scale) * p + (bcmax / scale) * bcmis;
    if (z >= kMultiple * kEps) {
      // Real eigenvalues.
      z = p + std::copysign(std::sqrt(scale) * std::sqrt(z), p);
      a = d + z;
      d = d - (bcmax / z) * bcmis;
      b = b - c;
      c = 0.0;
    } else {
      // Complex or nearly equal real eigenvalues: make the diagonal entries equal.
      double sigma = b + c;
      for (int count = 1; count <= 20; ++count) {
        scale = std::max(std::abs(temp), std::abs(sigma));
        if (scale >= kSafmx2) {
          sigma *= kSafmn2;
          temp *= kSafmn2;
          continue;
        }
        if (scale <= kSafmn2) {
          sigma *= kSafmx2;
          temp *= kSafmx2;
          continue;
        }
        break;
      }
      p = 0.5 * temp;
      double tau = Hypot2(sigma, temp);
      double cs = std::sqrt(0.5 * (1.0 + std::abs(sigma) / tau));
      double sn = -(p / (tau * cs)) * std::copysign(1.0, sigma);
      // [aa bb; cc dd] = [a b; c d] [cs −sn; sn cs]
      const double aa = a * cs + b * sn, bb = -a * sn + b * cs;
      const double cc = c * cs + d * sn, dd = -c * sn + d * cs;
      // [a b; c d] = [cs sn; −sn cs] [aa bb; cc dd]
      b = bb * cs + dd * sn;
      c = -aa * sn + cc * cs;
      temp = 0.5 * ((aa * cs + cc * sn) + (-bb * sn + dd * cs));
      a = d = temp;
      if (c != 0.0) {
        if (b != 0.0) {
          if (std::signbit(b) == std::signbit(c)) {
            // Real eigenvalues: reduce to upper triangular form.
            const double sab = std::sqrt(std::abs(b)), sac = std::sqrt(std::abs(c));
            p = std::copysign(sab * sac, c);
            a = temp + p;
            d = temp - p;
            b = b - c;
            c = 0.0;
          }
        } else {
          b = -c;
          c = 0.0;
        }
      }
    }
  }
  if (c == 0.0) {
    first = {a, 0.0};
    second = {d, 0.0};
  } else {
    const double imaginary = std::sqrt(std::abs(b)) * std::sqrt(std::abs(c));
    first = {a, imaginary};
    second = {d, -imaginary};
  }
}

// ---------------------------------------------------------------------------------------------
// One double-shift sweep of dlahqr on the active block l…i, the bulge started at row m with the
// first column v of the shift polynomial: reflector k (m ≤ k < i) acts on rows and columns k…k+2
// (k…k+1 for the last). With l, i and m template parameters every loop has constant bounds and
// unrolls; the ten blocks and starting rows of a 5×5 are dispatched by a table.

// The reflector of dlarfg in unnormalised form, I − factor·w·wᵀ, mapping (alpha, x) to (β, 0):
// w = (alpha − β, x), factor = 1/(β(β − alpha)). The dot products with w can start before the one
// division is done, which shortens the chain of dependent operations of a sweep. Outside the range
// where the squares are plain, dlarfg itself (w = (1, v), factor = τ).
template <int m>
struct Householder {
  double w[m + 1];
  double factor;
  double beta;
};

template <int m>
[[gnu::always_inline]] inline Householder<m> UnnormalisedReflector(double alpha, const double* x) {
  Householder<m> h;
  double squares = alpha * alpha;
  bool x_zero = true;
  for (int i = 0; i < m; ++i) {
    squares += x[i] * x[i];
    x_zero = x_zero && x[i] == 0.0;
  }
  if (x_zero) {
    h.w[0] = 1.0;
    for (int i = 0; i < m; ++i) h.w[i + 1] = 0.0;
    h.factor = 0.0;
    h.beta = alpha;
    return h;
  }
  if (squares >= kPlainSquaresLow && squares <= kPlainSquaresHigh) {
    h.beta = -std::copysign(std::sqrt(squares), alpha);
    h.w[0] = alpha - h.beta;
    for (int i = 0; i < m; ++i) h.w[i + 1] = x[i];
    h.factor = 1.0 / (h.beta * (h.beta - alpha));
    return h;
  }
  double v[m];
  for (int i = 0; i < m; ++i) v[i] = x[i];
  h.beta = alpha;
  h.factor = Reflector<m>(h.beta, v, 1);
  h.w[0] = 1.0;
  for (int i = 0; i < m; ++i) h.w[i + 1] = v[i];
  return h;
}

template <int L, int I, int M, int K>
[[gnu::always_inline]] inline void SweepStep(Square h, double v[3]) {
  constexpr int nr = std::min(3, I - K + 1);
  if constexpr (K > M) {
    v[0] = h[K][K - 1];
    v[1] = h[K + 1][K - 1];
    if constexpr (nr == 3) v[2] = h[K + 2][K - 1];
  }
  const Householder<nr - 1> g = UnnormalisedReflector<nr - 1>(v[0], &v[1]);
  if constexpr (K > M) {
    h[K][K - 1] = g.beta;
    h[K + 1][K - 1] = 0.0;
    if constexpr (K < I - 1) h[K + 2][K - 1] = 0.0;
  } else if constexpr (M > L) {
    // h(k, k−1)·(1 − τ), not −h(k, k−1), which fails when v(2) and v(3) underflow (dlahqr).
    h[K][K - 1] *= 1.0 - g.factor * g.w[0] * g.w[0];
  }
  double fw[nr];
  for (int r = 0; r < nr; ++r) fw[r] = g.factor * g.w[r];
  // From the left on rows K…K+nr−1, columns K…I; from the right on columns K…K+nr−1, rows L…K+3.
  for (int j = K; j <= I; ++j) {
    double sum = 0;
    for (int r = 0; r < nr; ++r) sum += g.w[r] * h[K + r][j];
    for (int r = 0; r < nr; ++r) h[K + r][j] -= sum * fw[r];
  }
  constexpr int last = std::min(K + 3, I);
  for (int j = L; j <= last; ++j) {
    double sum = 0;
    for (int r = 0; r < nr; ++r) sum += g.w[r] * h[j][K + r];
    for (int r = 0; r < nr; ++r) h[j][K + r] -= sum * fw[r];
  }
}

template <int L, int I, int M>
void SweepFrom(Square h, double v[3]) {
  [&]<int... steps>(std::integer_sequence<int, steps...>) { (SweepStep<L, I, M, M + steps>(h, v), ...); }
  (std::make_integer_sequence<int, I - M>{});
}

// kSweeps[i][l][m] = SweepFrom<l, i, m> for every l ≤ m ≤ i − 2 < kN, enumerated at compile time.
using SweepKernel = void (*)(Square, double[3]);
using SweepTable = std::array<std::array<std::array<SweepKernel, kN>, kN>, kN>;

template <int I = 2, int L = 0, int M = 0>
constexpr void AddSweeps(SweepTable& table) {
  if constexpr (I < kN) {
    if constexpr (L > I - 2) {
      AddSweeps<I + 1, 0, 0>(table);
    } else if constexpr (M > I - 2) {
      AddSweeps<I, L + 1, L + 1>(table);
    } else {
      table[I][L][M] = &SweepFrom<L, I, M>;
      AddSweeps<I, L, M + 1>(table);
    }
  }
}

constexpr SweepTable kSweeps = [] {
  SweepTable table{};
  AddSweeps(table);
  return table;
}();

void Sweep(Square h, int l, int i, int m, double v[3]) {
  GESWEEP_DEMAND(0 <= l && l <= m && m <= i - 2 && i < kN &&
                 "a double-shift sweep needs a block of at least 3 rows");
  kSweeps[static_cast<std::size_t>(i)][static_cast<std::size_t>(l)][static_cast<std::size_t>(m)](h, v);
}

// ---------------------------------------------------------------------------------------------
// dlahqr without the Schur form (wantt = wantz = false): only the active block is transformed.

void FrancisInPlace(Square h, int max_iterations, FrancisResult& result) {
  constexpr int kIlo = 0, kIhi = kN - 1;
  constexpr double kUlp = kPrecision;
  constexpr double kSmallNumber = kSafeMinimum * (kN / kUlp);
  constexpr int kExceptionalEvery = 10;  // KEXSH
  constexpr double kDat1 = 0.75, kDat2 = -0.4375;
  int kdefl = 0;
  int i = kIhi;
  while (i >= kIlo) {
    int l = kIlo;
    bool split = false;
    for (int its = 0; its <= max_iterations; ++its) {
      // A single negligible subdiagonal entry (Ahues & Kressner's conservative criterion).
      int k = i;
      for (; k > l; --k) {
        const double sub = std::abs(h[k][k - 1]);
        if (sub <= kSmallNumber) break;
        double tst = std::abs(h[k - 1][k - 1]) + std::abs(h[k][k]);
        if (tst == 0.0) {
          if (k - 2 >= kIlo) tst += std::abs(h[k - 1][k - 2]);
          if (k + 1 <= kIhi) tst += std::abs(h[k + 1][k]);
        }
        if (sub <= kUlp * tst) {
          const double super = std::abs(h[k - 1][k]);
          const double ab = std::max(sub, super), ba = std::min(sub, super);
          const double diff = std::abs(h[k - 1][k - 1] - h[k][k]);
          const double aa = std::max(std::abs(h[k][k]), diff), bb = std::min(std::abs(h[k][k]), diff);
          const double s = aa + ab;
          if (ba * (ab / s) <= std::max(kSmallNumber, kUlp * (bb * (aa / s)))) break;
        }
      }
      l = k;
      if (l > kIlo) h[l][l - 1] = 0.0;
      if (l >= i - 1) {
        split = true;
        break;
      }
      ++kdefl;
      ++result.iterations;
      // The shifts: the eigenvalues of the trailing 2×2, or an exceptional pair.
      double h11, h12, h21, h22;
      if (kdefl % (2 * kExceptionalEvery) == 0) {
        const double s = std::abs(h[i][i - 1]) + std::abs(h[i - 1][i - 2]);
        h11 = kDat1 * s + h[i][i];
        h12 = kDat2 * s;
        h21 = s;
        h22 = h11;
      } else if (kdefl % kExceptionalEvery == 0) {
        const double s = std::abs(h[l + 1][l]) + std::abs(h[l + 2][l + 1]);
        h11 = kDat1 * s + h[l][l];
        h12 = kDat2 * s;
        h21 = s;
        h22 = h11;
      } else {
        h11 = h[i - 1][i - 1];
        h21 = h[i][i - 1];
        h12 = h[i - 1][i];
        h22 = h[i][i];
      }
      double rt1r = 0, rt1i = 0, rt2r = 0, rt2i = 0;
      const double shift_scale = std::abs(h11) + std::abs(h12) + std::abs(h21) + std::abs(h22);
      if (shift_scale != 0.0) {
        // Normalised by one reciprocal: the shifts only steer the iteration, their last bit is immaterial.
        const double inverse = 1.0 / shift_scale;
        h11 *= inverse;
        h21 *= inverse;
        h12 *= inverse;
        h22 *= inverse;
        const double tr = 0.5 * (h11 + h22);
        const double det = (h11 - tr) * (h22 - tr) - h12 * h21;
        const double rtdisc = std::sqrt(std::abs(det));
        if (det >= 0.0) {
          rt1r = rt2r = tr * shift_scale;
          rt1i = rtdisc * shift_scale;
          rt2i = -rt1i;
        } else {
          // Real shifts: use the one closer to h22 twice.
          const double a = tr + rtdisc, b = tr - rtdisc;
          rt1r = rt2r = (std::abs(a - h22) <= std::abs(b - h22) ? a : b) * shift_scale;
        }
      }
      // Where to start the bulge: two consecutive small subdiagonal entries.
      double v[3];
      int m = i - 2;
      for (;; --m) {
        const double inverse_s0 = 1.0 / (std::abs(h[m][m] - rt2r) + std::abs(rt2i) + std::abs(h[m + 1][m]));
        const double h21s = h[m + 1][m] * inverse_s0;
        v[0] = h21s * h[m][m + 1] + (h[m][m] - rt1r) * ((h[m][m] - rt2r) * inverse_s0) -
               rt1i * (rt2i * inverse_s0);
        v[1] = h21s * (h[m][m] + h[m + 1][m + 1] - rt1r - rt2r);
        v[2] = h21s * h[m + 2][m + 1];
        const double inverse = 1.0 / (std::abs(v[0]) + std::abs(v[1]) + std::abs(v[2]));
        v[0] *= inverse;
        v[1] *= inverse;
        v[2] *= inverse;
        if (m == l) break;
        const double h00 = std::abs(h[m][m - 1]) * (std::abs(v[1]) + std::abs(v[2]));
        const double h01 =
            std::abs(v[0]) * (std::abs(h[m - 1][m - 1]) + std::abs(h[m][m]) + std::abs(h[m + 1][m + 1]));
        if (h00 <= kUlp * h01) break;
      }
      // The double-shift sweep on rows and columns l…i, from row m.
      Sweep(h, l, i, m, v);
    }
    if (!split) {
      result.converged = false;
      return;
    }
    if (l == i) {
      result.values[static_cast<std::size_t>(i)] = {h[i][i], 0.0};
    } else {
      StandardisedPair(h[i - 1][i - 1], h[i - 1][i], h[i][i - 1], h[i][i],
                       result.values[static_cast<std::size_t>(i - 1)],
                       result.values[static_cast<std::size_t>(i)]);
    }
    kdefl = 0;
    i = l - 1;
  }
}

void Load(const Matrix5d& A, Square h) {
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) h[i][j] = A(i, j);
}

// dgeev's guard: dlahqr's thresholds are absolute (a subdiagonal entry below 2⁻⁹⁶⁸ counts as
// negligible), so a matrix whose largest entry lies outside [2⁻⁴⁵⁹, 2⁴⁵⁹] (dgeev's SMLNUM, BIGNUM)
// is first multiplied by a power of two that brings it to [1, 2) (exact but for entries that become
// subnormal), and the eigenvalues are scaled back. Returns the factor to undo (1 when none).
double ScaleIntoRange(Square h) {
  constexpr double kSmall = 0x1p-459, kBig = 0x1p+459;
  double largest = 0;
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) largest = std::max(largest, std::abs(h[i][j]));
  if (largest == 0.0 || (largest >= kSmall && largest <= kBig)) return 1.0;
  const int exponent = std::ilogb(largest);
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) h[i][j] = std::ldexp(h[i][j], -exponent);
  return std::ldexp(1.0, exponent);
}

FrancisResult Solve(Square h, bool balance, int max_iterations) {
  const double undo = ScaleIntoRange(h);
  if (balance) {
    double scale[kN];
    BalanceInPlace(h, scale);
  }
  HessenbergInPlace(h);
  FrancisResult result;
  FrancisInPlace(h, max_iterations, result);
  if (undo != 1.0) {
    for (auto& z : result.values) z *= undo;
  }
  return result;
}

}  // namespace

BalancedMatrix5 Balance5(const Matrix5d& A) {
  Square a;
  Load(A, a);
  BalancedMatrix5 balanced;
  BalanceInPlace(a, balanced.scale.data());
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) balanced.matrix(i, j) = a[i][j];
  return balanced;
}

FrancisResult FrancisEigenvalues5(const Matrix5d& A, int max_iterations) {
  Square h;
  Load(A, h);
  return Solve(h, /*balance=*/false, max_iterations);
}

FrancisResult BalancedFrancisEigenvalues5(const Matrix5d& A, int max_iterations) {
  Square h;
  Load(A, h);
  return Solve(h, /*balance=*/true, max_iterations);
}

}  // namespace gesweep
