// The fixed-size 5×5 eigenvalue kernel (engine/modal/eigenvalues5.h) against independent oracles:
// LAPACK's dgebal for the balancing (the same D, bit for bit), Eigen's EigenSolver on 10⁵ table and
// random matrices (the 1e-12), and matrices whose eigenvalues are known in closed form
// (companion matrices of chosen roots, orthogonal similarities of block-diagonal matrices, Jordan
// blocks, triangular and nilpotent matrices, exact power-of-two scalings, 2×2 blocks of every branch
// of dlanv2, the cyclic shift that needs an exceptional shift). The fallback to Eigen's solver is
// exercised with an iteration limit of zero.
#include "engine/modal/eigenvalues5.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/modal/modal_analysis.h"
#include "tests/testing/test_paths.h"

extern "C" void dgebal_(const char* job, const int* n, double* a, const int* lda, int* ilo, int* ihi,
                        double* scale, int* info, std::size_t job_length);

namespace gesweep {
namespace {

using Complex = std::complex<double>;
using Spectrum = std::array<Complex, 5>;

// The criterion: |λ − μ| ≤ 1e-12·max(1, |λ|) against Eigen's EigenSolver. Both solvers are
// backward stable; on matrices with well-conditioned eigenvalues they agree far inside it.
constexpr double kAgreement = 1e-12;
// Normwise agreement for matrices whose eigenvalues are perfectly conditioned (normal matrices) or
// known exactly: 100 ulp of the spectral radius covers the QR's backward error (a few ulp of ‖A‖).
constexpr double kNormwise = 1e-13;

// The smallest over all pairings of a and b of the largest |aᵢ − b_π(i)|/scaleᵢ: a distance between
// spectra that counts multiplicities (120 permutations of 5).
template <typename Scale>
double SpectrumDistance(const Spectrum& a, const Spectrum& b, Scale scale) {
  std::array<int, 5> p{0, 1, 2, 3, 4};
  double best = INFINITY;
  do {
    double worst = 0;
    for (int i = 0; i < 5 && worst < best; ++i) {
      worst = std::max(worst, std::abs(a[static_cast<std::size_t>(i)] -
                                       b[static_cast<std::size_t>(p[static_cast<std::size_t>(i)])]) /
                                  scale(b[static_cast<std::size_t>(p[static_cast<std::size_t>(i)])]));
    }
    best = std::min(best, worst);
  } while (std::next_permutation(p.begin(), p.end()));
  return best;
}

double RelativeToMaxOneAbs(const Spectrum& a, const Spectrum& b) {
  return SpectrumDistance(a, b, [](Complex z) { return std::max(1.0, std::abs(z)); });
}

double SpectralRadius(const Spectrum& s) {
  double r = 0;
  for (const Complex& z : s) r = std::max(r, std::abs(z));
  return r;
}

double Normwise(const Spectrum& a, const Spectrum& b) {
  const double radius = std::max(SpectralRadius(b), 1e-300);
  return SpectrumDistance(a, b, [radius](Complex) { return radius; });
}

Spectrum Kernel(const Matrix5d& A) {
  const FrancisResult result = BalancedFrancisEigenvalues5(A);
  EXPECT_TRUE(result.converged);
  return result.values;
}

Spectrum EigenSolverOf(const Matrix5d& A) {
  const Eigen::EigenSolver<Matrix5d> solver(A, /*computeEigenvectors=*/false);
  Spectrum s;
  for (int i = 0; i < 5; ++i) s[static_cast<std::size_t>(i)] = solver.eigenvalues()[i];
  return s;
}

// The kernel's own promises: real eigenvalues with Im exactly 0, a pair as adjacent entries with
// exactly opposite imaginary parts, Im > 0 first.
void ExpectStandardised(const Spectrum& s) {
  for (std::size_t i = 0; i < 5; ++i) {
    if (s[i].imag() == 0.0) continue;
    ASSERT_GT(s[i].imag(), 0.0) << "a pair starts with Im > 0, entry " << i;
    ASSERT_LT(i + 1, 5u);
    EXPECT_EQ(s[i + 1].imag(), -s[i].imag());
    ++i;
  }
}

Matrix5d RandomOrthogonal(std::mt19937_64& random) {
  std::normal_distribution<double> normal;
  Matrix5d G;
  for (int i = 0; i < 25; ++i) G.data()[i] = normal(random);
  return Eigen::HouseholderQR<Matrix5d>(G).householderQ() * Matrix5d::Identity();
}

// A matrix with a prescribed, well-conditioned spectrum: S·D·S⁻¹, D block diagonal with one of three
// patterns (two pairs and a real root; a pair and three reals; five reals), S near the identity.
Matrix5d WellConditioned(std::mt19937_64& random, Spectrum* exact = nullptr) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> pattern(0, 2);
  Matrix5d D = Matrix5d::Zero();
  Spectrum values;
  auto pair = [&](int k, double re, double im) {
    D(k, k) = D(k + 1, k + 1) = re;
    D(k, k + 1) = im;
    D(k + 1, k) = -im;
    values[static_cast<std::size_t>(k)] = {re, im};
    values[static_cast<std::size_t>(k + 1)] = {re, -im};
  };
  auto real = [&](int k, double re) {
    D(k, k) = re;
    values[static_cast<std::size_t>(k)] = re;
  };
  switch (pattern(random)) {
    case 0:
      pair(0, 2 * u(random), 1 + 3 * std::abs(u(random)));
      pair(2, u(random), 0.1 + std::abs(u(random)));
      real(4, 0.01 * u(random));
      break;
    case 1:
      pair(0, 2 * u(random), 0.5 + 2 * std::abs(u(random)));
      real(2, -3 + 0.5 * u(random));
      real(3, 1 + 0.5 * u(random));
      real(4, 0.05 * u(random));
      break;
    default:
      for (int k = 0; k < 5; ++k) real(k, (k - 2) + 0.3 * u(random));
      break;
  }
  Matrix5d S = Matrix5d::Identity();
  for (int i = 0; i < 25; ++i) S.data()[i] += 0.3 * u(random);
  if (exact) *exact = values;
  return S * D * S.inverse();
}

// The companion matrix of ∏(s − rᵢ) (the roots come in conjugate pairs): eigenvalues exactly rᵢ.
Matrix5d Companion(const Spectrum& roots) {
  std::vector<Complex> poly{1.0};
  for (const Complex& r : roots) {
    std::vector<Complex> next(poly.size() + 1, 0.0);
    for (std::size_t i = 0; i < poly.size(); ++i) {
      next[i] += poly[i];
      next[i + 1] -= r * poly[i];
    }
    poly = next;
  }
  Matrix5d A = Matrix5d::Zero();
  for (int j = 0; j < 5; ++j) A(0, j) = -poly[static_cast<std::size_t>(j + 1)].real();
  for (int i = 1; i < 5; ++i) A(i, i - 1) = 1.0;
  return A;
}

// --- Balancing: LAPACK's dgebal (job 'S') is the oracle, bit for bit ---

TEST(Balance5, IsLapackDgebalBitForBit) {
  std::mt19937_64 random(5);
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> exponent(-20, 20);
  const Aircraft ance = LoadAircraftFile(testing::AnceAircraftPath());
  const LongitudinalModel model(ance, ModelOptions{});
  std::uniform_real_distribution<double> height(0.79, 14.0), speed(24.0, 60.0);
  int identical = 0, total = 0;
  for (int n = 0; n < 100000; ++n) {
    Matrix5d A;
    if (n % 10 == 0) {
      A = model.StateMatrix(height(random), speed(random));
    } else {
      // Entries spread over 2^±20 (what balancing is for), a third of the matrices with zeros.
      for (int i = 0; i < 25; ++i) A.data()[i] = normal(random) * std::ldexp(1.0, exponent(random));
      if (n % 3 == 0) {
        for (int i = 0; i < 25; ++i)
          if (random() % 3 == 0) A.data()[i] = 0.0;
      }
    }
    Matrix5d lapack = A;
    const int size = 5;
    int ilo = 0, ihi = 0, info = 0;
    double scale[5];
    dgebal_("S", &size, lapack.data(), &size, &ilo, &ihi, scale, &info, 1);
    const BalancedMatrix5 ours = Balance5(A);
    bool same = (ours.matrix.array() == lapack.array()).all();
    for (int i = 0; i < 5; ++i) same = same && ours.scale[static_cast<std::size_t>(i)] == scale[i];
    identical += same ? 1 : 0;
    ++total;
    // D is a diagonal of powers of two: D⁻¹AD exactly.
    for (int i = 0; i < 5; ++i) {
      int e = 0;
      EXPECT_EQ(std::frexp(ours.scale[static_cast<std::size_t>(i)], &e), 0.5);
    }
  }
  EXPECT_EQ(identical, total);
}

// --- Agreement with Eigen's EigenSolver on 10⁵ table and random matrices, classification unchanged ---

TEST(FixedSizeKernel, AgreesWithEigenSolverOn100000TableAndRandomMatrices) {
  const Aircraft ance = LoadAircraftFile(testing::AnceAircraftPath());
  std::mt19937_64 random(16);
  std::uniform_real_distribution<double> factor(0.5, 1.5), height(0.79, 14.0), speed(24.0, 60.0);
  std::normal_distribution<double> normal;
  const std::uint64_t fallbacks_before = FixedSizeSolverFallbacks();
  double worst_table = 0, worst_random = 0, worst_similar = 0;
  int matrices = 0, classification_changes = 0, margin_changes = 0;
  auto compare = [&](const Matrix5d& A, double& worst) {
    const Spectrum ours = Eigenvalues5(A, EigenvalueSolver::kFixedSize);
    const Spectrum eigen = Eigenvalues5(A, EigenvalueSolver::kEigen);
    ExpectStandardised(ours);
    worst = std::max(worst, RelativeToMaxOneAbs(ours, eigen));
    const ModalAnalysis a = AnalyzeModes(A, EigenvalueSolver::kFixedSize);
    const ModalAnalysis b = AnalyzeModes(A, EigenvalueSolver::kEigen);
    classification_changes += a.classification != b.classification ? 1 : 0;
    margin_changes += a.stable != b.stable ? 1 : 0;
    ++matrices;
  };
  // 20,000 table matrices: 200 aircraft with every coefficient scaled by U(0.5, 1.5), linear and
  // PCHIP, a quarter without the h-derivatives (an exactly neutral height root), heights from wheel
  // contact to above the table and speeds 24-60 m/s.
  for (int n = 0; n < 200; ++n) {
    ModelOptions options;
    for (int c = 0; c < kCoefficientCount; ++c)
      options.coefficient_scale[static_cast<std::size_t>(c)] = factor(random);
    options.interpolation = n % 2 == 0 ? Interpolation::kLinear : Interpolation::kPchip;
    options.h_derivatives = n % 4 != 3;
    const LongitudinalModel model(ance, options);
    for (int i = 0; i < 100; ++i) compare(model.StateMatrix(height(random), speed(random)), worst_table);
  }
  // 40,000 matrices with independent N(0, 1) entries.
  for (int n = 0; n < 40000; ++n) {
    Matrix5d A;
    for (int i = 0; i < 25; ++i) A.data()[i] = normal(random);
    compare(A, worst_random);
  }
  // 40,000 matrices S·D·S⁻¹ with prescribed pairs and real roots (some splits).
  for (int n = 0; n < 40000; ++n) compare(WellConditioned(random), worst_similar);
  EXPECT_EQ(matrices, 100000);
  EXPECT_LT(worst_table, kAgreement);
  EXPECT_LT(worst_random, kAgreement);
  EXPECT_LT(worst_similar, kAgreement);
  EXPECT_EQ(classification_changes, 0);
  EXPECT_EQ(margin_changes, 0);
  EXPECT_EQ(FixedSizeSolverFallbacks(), fallbacks_before) << "the kernel fell back to Eigen's solver";
  std::printf("worst |mu - lambda|/max(1,|lambda|): table %.2e, N(0,1) %.2e, S D S^-1 %.2e\n", worst_table,
              worst_random, worst_similar);
}

TEST(FixedSizeKernel, TheAnceModesTableIsUnchanged) {
  // Every row of `gesweep modes --table-heights` (and free flight) at the paper's two speeds, with
  // and without h-derivatives, linear and PCHIP: the same classification, σ, stability and mode
  // properties as with Eigen's solver.
  constexpr double kPropertyAgreement = 1e-12;  // relative; derived from eigenvalues within kAgreement
  const Aircraft ance = LoadAircraftFile(testing::AnceAircraftPath());
  std::vector<double> heights = ance.table_heights_m;
  heights.push_back(std::numeric_limits<double>::infinity());
  auto near = [](double x, double y) {
    if (std::isnan(x) || std::isnan(y)) return std::isnan(x) && std::isnan(y);
    if (std::isinf(x) || std::isinf(y)) return x == y;
    return std::abs(x - y) <= kPropertyAgreement * std::max(1.0, std::abs(y));
  };
  int rows = 0;
  for (bool h_derivatives : {true, false}) {
    for (Interpolation interpolation : {Interpolation::kLinear, Interpolation::kPchip}) {
      ModelOptions options;
      options.h_derivatives = h_derivatives;
      options.interpolation = interpolation;
      const LongitudinalModel model(ance, options);
      for (double u : {32.0208, 52.21}) {
        for (double h : heights) {
          const Matrix5d A = model.StateMatrix(h, u);
          const ModalAnalysis a = AnalyzeModes(A), b = AnalyzeModes(A, EigenvalueSolver::kEigen);
          SCOPED_TRACE("H = " + std::to_string(h) + ", u = " + std::to_string(u));
          EXPECT_EQ(a.classification, b.classification);
          EXPECT_EQ(a.stable, b.stable);
          EXPECT_FALSE(a.solver_fallback);
          EXPECT_TRUE(near(a.stability_margin_per_s, b.stability_margin_per_s));
          for (std::size_t i = 0; i < 5; ++i) {
            EXPECT_LE(std::abs(a.eigenvalues[i] - b.eigenvalues[i]),
                      kAgreement * std::max(1.0, std::abs(b.eigenvalues[i])));
          }
          for (const auto& [x, y] : {std::pair{a.short_period, b.short_period},
                                     std::pair{a.phugoid, b.phugoid}, std::pair{a.height, b.height}}) {
            EXPECT_EQ(x.oscillatory, y.oscillatory);
            EXPECT_EQ(x.neutral, y.neutral);
            EXPECT_TRUE(near(x.natural_frequency_radps, y.natural_frequency_radps));
            EXPECT_TRUE(near(x.damping_ratio, y.damping_ratio));
            EXPECT_TRUE(near(x.period_s, y.period_s));
            // ln2/|Re λ| is as sensitive as 1/Re λ: compare Re λ instead.
            EXPECT_TRUE(near(x.eigenvalue.real(), y.eigenvalue.real()));
          }
          ++rows;
        }
      }
    }
  }
  EXPECT_EQ(rows, 8 * static_cast<int>(heights.size()));
}

// --- Independent oracles: spectra known in closed form ---

TEST(FixedSizeKernel, CompanionMatricesGiveTheirRoots) {
  // 2000 root sets of the three patterns, |r| from 0.05 to 20, pairwise separated by at least 20 % of
  // the larger. Balanced, these companion matrices are well conditioned: the 1e-12 of
  // max(1, |r|) holds against the roots themselves (measured 5e-14; Eigen's solver 3e-12).
  constexpr double kRootTolerance = 1e-12;
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> log_magnitude(std::log(0.05), std::log(20.0)),
      angle(0.15, std::numbers::pi - 0.15);
  std::uniform_int_distribution<int> pattern(0, 2), sign(0, 1);
  double worst = 0, worst_eigen = 0;
  int sets = 0;
  while (sets < 2000) {
    Spectrum roots;
    auto real = [&](int k) {
      roots[static_cast<std::size_t>(k)] = (sign(random) ? 1.0 : -1.0) * std::exp(log_magnitude(random));
    };
    auto pair = [&](int k) {
      const Complex z = std::polar(std::exp(log_magnitude(random)), angle(random));
      roots[static_cast<std::size_t>(k)] = z;
      roots[static_cast<std::size_t>(k + 1)] = std::conj(z);
    };
    const int p = pattern(random);
    if (p == 0) {
      pair(0);
      pair(2);
      real(4);
    }
    if (p == 1) {
      pair(0);
      real(2);
      real(3);
      real(4);
    }
    if (p == 2) {
      for (int k = 0; k < 5; ++k) real(k);
    }
    bool separated = true;
    for (std::size_t i = 0; i < 5; ++i)
      for (std::size_t j = i + 1; j < 5; ++j)
        separated = separated &&
                    std::abs(roots[i] - roots[j]) >= 0.2 * std::max(std::abs(roots[i]), std::abs(roots[j]));
    if (!separated) continue;
    const Matrix5d A = Companion(roots);
    const Spectrum ours = Kernel(A);
    ExpectStandardised(ours);
    worst = std::max(worst, RelativeToMaxOneAbs(ours, roots));
    worst_eigen = std::max(worst_eigen, RelativeToMaxOneAbs(EigenSolverOf(A), roots));
    ++sets;
  }
  EXPECT_LT(worst, kRootTolerance);
  std::printf("companion roots: worst error / max(1,|r|) %.2e (Eigen's solver %.2e)\n", worst, worst_eigen);
}

TEST(FixedSizeKernel, OrthogonalSimilaritiesOfKnownBlocksIncludingRepeatedAndImaginaryRoots) {
  // Q·B·Qᵀ with Q random orthogonal: a normal matrix, whose eigenvalues are perfectly conditioned,
  // repeated or not. Repeated reals, a repeated complex pair, and a skew-symmetric matrix (±iω₁,
  // ±iω₂, 0 on the imaginary axis).
  std::mt19937_64 random(9);
  auto block = [](Matrix5d& B, int k, double re, double im) {
    B(k, k) = B(k + 1, k + 1) = re;
    B(k, k + 1) = im;
    B(k + 1, k) = -im;
  };
  for (int n = 0; n < 300; ++n) {
    const Matrix5d Q = RandomOrthogonal(random);
    Matrix5d B = Matrix5d::Zero();
    Spectrum exact;
    switch (n % 3) {
      case 0:
        B.diagonal() << 2.0, 2.0, -1.0, -1.0, 0.5;
        exact = {2.0, 2.0, -1.0, -1.0, 0.5};
        break;
      case 1:
        block(B, 0, -0.3, 1.7);
        block(B, 2, -0.3, 1.7);
        B(4, 4) = -0.02;
        exact = {Complex{-0.3, 1.7}, Complex{-0.3, -1.7}, Complex{-0.3, 1.7}, Complex{-0.3, -1.7}, -0.02};
        break;
      default:
        block(B, 0, 0.0, 3.0);
        block(B, 2, 0.0, 0.25);
        exact = {Complex{0, 3.0}, Complex{0, -3.0}, Complex{0, 0.25}, Complex{0, -0.25}, 0.0};
        break;
    }
    const Spectrum ours = Kernel(Q * B * Q.transpose());
    ExpectStandardised(ours);
    EXPECT_LT(Normwise(ours, exact), kNormwise) << "case " << n % 3;
  }
}

TEST(FixedSizeKernel, DefectiveEigenvaluesStayWithinTheirPerturbationBound) {
  // A Jordan block of size k moves under a perturbation ε·‖A‖ by about (ε·‖A‖)^(1/k): no solver can
  // do better, so Eigen's solver is no oracle here. The roots are known: the companion matrix of
  // (s + 1)⁵ (one block of size 5; its coefficients are exact), and S·J·S⁻¹ with J = J₂(−0.5) ⊕
  // J₃(0.25). The mean of the computed roots of each block is its root to rounding (the trace of
  // the block is preserved), each root within ten times the perturbation bound.
  constexpr double kEpsilon = 0x1p-52;
  {
    const Spectrum ours = Kernel(Companion({-1.0, -1.0, -1.0, -1.0, -1.0}));
    Complex mean = 0;
    for (const Complex& z : ours) mean += z / 5.0;
    EXPECT_LT(std::abs(mean + 1.0), 1e-13);
    for (const Complex& z : ours) EXPECT_LT(std::abs(z + 1.0), 10 * std::pow(kEpsilon * 10, 1.0 / 5)) << z;
  }
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int n = 0; n < 200; ++n) {
    Matrix5d J = Matrix5d::Zero();
    J.diagonal() << -0.5, -0.5, 0.25, 0.25, 0.25;
    J(0, 1) = J(2, 3) = J(3, 4) = 1.0;
    Matrix5d S = Matrix5d::Identity();
    for (int i = 0; i < 25; ++i) S.data()[i] += 0.2 * u(random);
    const Spectrum ours = Kernel(S * J * S.inverse());
    Complex sum_near_half = 0, sum_near_quarter = 0;
    int count_half = 0, count_quarter = 0;
    for (const Complex& z : ours) {
      if (std::abs(z + 0.5) < std::abs(z - 0.25)) {
        sum_near_half += z;
        ++count_half;
        EXPECT_LT(std::abs(z + 0.5), 10 * std::pow(kEpsilon * 10, 1.0 / 2));
      } else {
        sum_near_quarter += z;
        ++count_quarter;
        EXPECT_LT(std::abs(z - 0.25), 10 * std::pow(kEpsilon * 10, 1.0 / 3));
      }
    }
    ASSERT_EQ(count_half, 2);
    ASSERT_EQ(count_quarter, 3);
    // The sum of a cluster is far better conditioned than its members.
    EXPECT_LT(std::abs(sum_near_half / 2.0 + 0.5), 1e-10);
    EXPECT_LT(std::abs(sum_near_quarter / 3.0 - 0.25), 1e-10);
  }
}

TEST(FixedSizeKernel, ZeroTriangularAndNilpotentMatricesAreExact) {
  {
    const FrancisResult zero = BalancedFrancisEigenvalues5(Matrix5d::Zero());
    EXPECT_TRUE(zero.converged);
    EXPECT_EQ(zero.iterations, 0);
    for (const Complex& z : zero.values) EXPECT_EQ(z, Complex(0.0));
  }
  {
    // The nilpotent Jordan block: already Hessenberg with a zero subdiagonal: exact zeros, no sweep.
    Matrix5d N = Matrix5d::Zero();
    for (int i = 0; i < 4; ++i) N(i, i + 1) = 1.0;
    const FrancisResult nilpotent = BalancedFrancisEigenvalues5(N);
    EXPECT_EQ(nilpotent.iterations, 0);
    for (const Complex& z : nilpotent.values) EXPECT_EQ(z, Complex(0.0));
  }
  std::mt19937_64 random(4);
  std::normal_distribution<double> normal;
  for (int n = 0; n < 100; ++n) {
    // Upper triangular: the eigenvalues are the diagonal, exactly (balancing and the reduction leave
    // the diagonal alone, and nothing is left to iterate on).
    Matrix5d T = Matrix5d::Zero();
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i <= j; ++i) T(i, j) = normal(random);
    const FrancisResult triangular = BalancedFrancisEigenvalues5(T);
    EXPECT_EQ(triangular.iterations, 0);
    for (int i = 0; i < 5; ++i) EXPECT_EQ(triangular.values[static_cast<std::size_t>(i)], Complex(T(i, i)));
  }
}

TEST(FixedSizeKernel, ScalesFromTwoToTheMinus1000ToTwoToThe1000) {
  // 2^k·A has the eigenvalues of A times 2^k exactly; the oracle is Eigen's solver on A itself.
  // Beyond 2^±459 the kernel scales A into range first (as dgeev does); inside, the squares are
  // summed with scaling where plain sums would over- or underflow.
  std::mt19937_64 random(12);
  for (int n = 0; n < 200; ++n) {
    const Matrix5d A = WellConditioned(random);
    const Spectrum reference = EigenSolverOf(A);
    for (int k : {-1000, -600, -460, -300, -100, 100, 300, 460, 600, 1000}) {
      const Spectrum ours = Kernel(std::ldexp(1.0, k) * A);
      Spectrum back;
      for (std::size_t i = 0; i < 5; ++i) back[i] = ours[i] * std::ldexp(1.0, -k);
      EXPECT_LT(Normwise(back, reference), kAgreement) << "2^" << k;
    }
  }
}

TEST(FixedSizeKernel, BadlyScaledSimilaritiesAreBalancedBack) {
  // D·B·D⁻¹ with D = diag(2^eᵢ), eᵢ up to ±30: exactly B's eigenvalues, which balancing recovers.
  std::mt19937_64 random(13);
  std::uniform_int_distribution<int> exponent(-30, 30);
  double worst = 0;
  for (int n = 0; n < 2000; ++n) {
    const Matrix5d B = WellConditioned(random);
    Matrix5d D = Matrix5d::Zero();
    for (int i = 0; i < 5; ++i) D(i, i) = std::ldexp(1.0, exponent(random));
    const Matrix5d A = D * B * D.inverse();
    worst = std::max(worst, RelativeToMaxOneAbs(Kernel(A), EigenSolverOf(B)));
  }
  EXPECT_LT(worst, kAgreement);
}

TEST(FixedSizeKernel, EveryBranchOfTheTwoByTwoStandardisation) {
  // blockdiag(T, [a b; c d]) with T upper triangular: the block splits off before any sweep and goes
  // straight to dlanv2's standardisation. Its eigenvalues in closed form (long double).
  struct Case {
    const char* what;
    double a, b, c, d;
  };
  const Case cases[] = {
      {"c = 0: already triangular", 3.0, 5.0, 0.0, -2.0},
      {"b = 0: rows and columns swapped", 3.0, 0.0, 4.0, -2.0},
      {"a = d, bc < 0: already standard", 1.0, 2.0, -8.0, 1.0},
      {"distinct real", 1.0, 2.0, 3.0, 4.0},
      {"complex", 1.0, -5.0, 2.0, 3.0},
      {"complex, a = d after rotation needs sigma scaling", 1e-3, 1e-1, -1e-1, 2e-3},
      {"nearly equal real: decided after the rotation", 1.0, 1e-10, 1e-10, 1.0},
      {"nearly equal complex", 1.0, 1e-10, -1e-10, 1.0},
  };
  for (const Case& c : cases) {
    Matrix5d A = Matrix5d::Zero();
    A(0, 0) = 7.0;
    A(0, 1) = 0.5;
    A(1, 1) = -6.0;
    A(0, 2) = -0.25;
    A(1, 2) = 0.75;
    A(2, 2) = 5.0;
    A(0, 3) = A(1, 4) = A(2, 3) = 0.125;
    A(3, 3) = c.a;
    A(3, 4) = c.b;
    A(4, 3) = c.c;
    A(4, 4) = c.d;
    const long double mean = 0.5L * (static_cast<long double>(c.a) + c.d);
    const long double half = 0.5L * (static_cast<long double>(c.a) - c.d);
    const long double discriminant = half * half + static_cast<long double>(c.b) * c.c;
    Complex first, second;
    if (discriminant >= 0) {
      first = static_cast<double>(mean + std::sqrt(discriminant));
      second = static_cast<double>(mean - std::sqrt(discriminant));
    } else {
      first = {static_cast<double>(mean), static_cast<double>(std::sqrt(-discriminant))};
      second = std::conj(first);
    }
    const FrancisResult result = BalancedFrancisEigenvalues5(A);
    SCOPED_TRACE(c.what);
    EXPECT_TRUE(result.converged);
    EXPECT_EQ(result.iterations, 0);
    ExpectStandardised(result.values);
    const Spectrum exact{7.0, -6.0, 5.0, first, second};
    EXPECT_LT(Normwise(result.values, exact), kNormwise);
    // The imaginary parts are exactly zero for real roots.
    if (discriminant >= 0) {
      for (const Complex& z : result.values) EXPECT_EQ(z.imag(), 0.0);
    }
  }
}

TEST(FixedSizeKernel, TheCyclicShiftNeedsAndGetsAnExceptionalShift) {
  // The cyclic permutation (companion of s⁵ − 1) is orthogonal and its trailing 2×2 gives two zero
  // shifts: a standard Francis step returns the same matrix. dlahqr's exceptional shift after 10
  // sweeps without a deflation breaks the cycle. Eigenvalues: the fifth roots of unity.
  Matrix5d P = Matrix5d::Zero();
  P(0, 4) = 1.0;
  for (int i = 1; i < 5; ++i) P(i, i - 1) = 1.0;
  const FrancisResult result = BalancedFrancisEigenvalues5(P);
  EXPECT_TRUE(result.converged);
  EXPECT_GE(result.iterations, 10);
  Spectrum roots;
  for (int k = 0; k < 5; ++k)
    roots[static_cast<std::size_t>(k)] = std::polar(1.0, 2 * std::numbers::pi * k / 5);
  EXPECT_LT(Normwise(result.values, roots), kNormwise);
  ExpectStandardised(result.values);
}

TEST(FixedSizeKernel, WithoutConvergenceEigenvalues5FallsBackToEigenAndSaysSo) {
  std::mt19937_64 random(21);
  const Matrix5d A = WellConditioned(random);
  EXPECT_FALSE(BalancedFrancisEigenvalues5(A, /*max_iterations=*/0).converged);
  const std::uint64_t before = FixedSizeSolverFallbacks();
  EigenvalueReport report;
  const Spectrum values = Eigenvalues5(A, EigenvalueSolver::kFixedSize, &report, /*max_iterations=*/0);
  EXPECT_TRUE(report.solver_fallback);
  EXPECT_EQ(FixedSizeSolverFallbacks(), before + 1);
  EXPECT_EQ(values, Eigenvalues5(A, EigenvalueSolver::kEigen));
  // With the default limit: no fallback, and AnalyzeModes says so.
  EigenvalueReport normal;
  Eigenvalues5(A, EigenvalueSolver::kFixedSize, &normal);
  EXPECT_FALSE(normal.solver_fallback);
  EXPECT_GT(normal.iterations, 0);
  EXPECT_FALSE(AnalyzeModes(A).solver_fallback);
  EXPECT_EQ(FixedSizeSolverFallbacks(), before + 1);
}

}  // namespace
}  // namespace gesweep
