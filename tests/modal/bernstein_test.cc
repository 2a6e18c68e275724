#include "engine/modal/bernstein.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace gesweep {
namespace {

// Values of a polynomial of degree ≤ 12 with coefficients of order 1 are reproduced to rounding.
constexpr double kRounding = 1e-12;

double Monomial(const std::vector<double>& c, double t) {
  double v = 0;
  for (std::size_t k = c.size(); k-- > 0;) v = v * t + c[k];
  return v;
}

TEST(BernsteinPolynomial, FromChebyshevSamplesReproducesAPolynomial) {
  const std::vector<double> c = {0.3, -1.2, 2.0, 0.5, -0.7, 0.1, 0.05, -0.3, 0.2};  // degree 8
  for (int extra : {0, 1, 4}) {
    const int m = 9 + extra;
    std::vector<double> values;
    for (double t : BernsteinPolynomial::ChebyshevNodes(m)) values.push_back(Monomial(c, t));
    double tail = -1;
    const BernsteinPolynomial p = BernsteinPolynomial::FromChebyshevSamples(values, 8, &tail);
    EXPECT_EQ(p.degree(), 8);
    EXPECT_LE(tail, kRounding);
    for (double t : {0.0, 0.13, 0.5, 0.77, 1.0}) EXPECT_NEAR(p(t), Monomial(c, t), kRounding) << t;
  }
}

TEST(BernsteinPolynomial, TailRevealsAWrongDegreeBound) {
  std::vector<double> values;
  for (double t : BernsteinPolynomial::ChebyshevNodes(6)) values.push_back(std::pow(t, 5));
  double tail = 0;
  BernsteinPolynomial::FromChebyshevSamples(values, 3, &tail);
  EXPECT_GT(tail, 1e-3);  // t⁵ is not cubic: T₄, T₅ terms of order 0.03
}

TEST(BernsteinPolynomial, ArithmeticMatchesPointwise) {
  const BernsteinPolynomial p = BernsteinPolynomial::FromCoefficients({1.0, -2.0, 0.5});
  const BernsteinPolynomial q = BernsteinPolynomial::FromCoefficients({0.2, 0.7, -1.0, 3.0});
  for (double t : {0.0, 0.25, 0.6, 1.0}) {
    EXPECT_NEAR((p * q)(t), p(t) * q(t), kRounding);
    EXPECT_NEAR((p - q)(t), p(t) - q(t), kRounding);
    EXPECT_NEAR((p + q)(t), p(t) + q(t), kRounding);
    EXPECT_NEAR(p.Elevated(7)(t), p(t), kRounding);
    // p = 1·B0 − 2·B1 + 0.5·B2: p' = 2(−3 B0 + 2.5 B1) in degree 1.
    EXPECT_NEAR(p.Derivative()(t), 2 * (-3.0 * (1 - t) + 2.5 * t), kRounding);
  }
}

TEST(BernsteinPolynomial, DividesOutARootAtAnEnd) {
  // p(t) = (1 − t)(t − 0.3)(t + 1) and t(t − 0.6).
  const auto q = [](double t) { return (t - 0.3) * (t + 1); };
  std::vector<double> values;
  for (double t : BernsteinPolynomial::ChebyshevNodes(4)) values.push_back((1 - t) * q(t));
  const BernsteinPolynomial p = BernsteinPolynomial::FromChebyshevSamples(values, 3, nullptr);
  for (double t : {0.0, 0.4, 1.0}) EXPECT_NEAR(p.DividedByOneMinusT()(t), q(t), kRounding);
  values.clear();
  for (double t : BernsteinPolynomial::ChebyshevNodes(3)) values.push_back(t * (t - 0.6));
  const BernsteinPolynomial r = BernsteinPolynomial::FromChebyshevSamples(values, 2, nullptr);
  for (double t : {0.0, 0.4, 1.0}) EXPECT_NEAR(r.DividedByT()(t), t - 0.6, kRounding);
}

// A polynomial with known roots (some outside [0, 1], two of them 1e-7 apart).
BernsteinPolynomial WithRoots(const std::vector<double>& roots) {
  BernsteinPolynomial p = BernsteinPolynomial::Constant(1.0);
  for (double r : roots) p = p * BernsteinPolynomial::FromCoefficients({-r, 1.0 - r});  // t − r
  return p;
}

TEST(IsolateRoots, EnclosesEveryRootInTheIntervalOnceAndNoOther) {
  const std::vector<double> roots = {-0.4, 0.1, 0.35, 0.3500001, 0.8, 1.3, 2.0};
  const BernsteinPolynomial p = WithRoots(roots);
  const RootIsolation isolation = IsolateRoots(p, 1e-15 * p.MaxAbsCoefficient());
  std::vector<double> inside = {0.1, 0.35, 0.3500001, 0.8};
  ASSERT_EQ(isolation.intervals.size(), inside.size());
  for (std::size_t i = 0; i < inside.size(); ++i) {
    EXPECT_TRUE(isolation.intervals[i].certified);
    EXPECT_LE(isolation.intervals[i].lower_t, inside[i]);
    EXPECT_GE(isolation.intervals[i].upper_t, inside[i]);
  }
}

TEST(IsolateRoots, RandomPolynomialsAgainstTheirRoots) {
  std::mt19937_64 random(17);
  std::uniform_real_distribution<double> u(-0.5, 1.5);
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<double> roots;
    const int degree = 1 + trial % 12;
    for (int i = 0; i < degree; ++i) roots.push_back(u(random));
    const BernsteinPolynomial p = WithRoots(roots);
    const RootIsolation isolation = IsolateRoots(p, 1e-14 * p.MaxAbsCoefficient());
    int inside = 0;
    for (double r : roots) inside += r > 0 && r < 1;
    int found = 0;
    for (const auto& interval : isolation.intervals) {
      // Each certified interval holds exactly one root.
      int in = 0;
      for (double r : roots) in += r >= interval.lower_t && r <= interval.upper_t;
      if (interval.certified) {
        EXPECT_EQ(in, 1) << trial;
      }
      found += in;
    }
    EXPECT_EQ(found, inside) << trial;
  }
}

TEST(IsolateRoots, ADoubleRootStaysUndecidedWithoutASignChange) {
  const BernsteinPolynomial p = WithRoots({0.4, 0.4, 0.9});
  const RootIsolation isolation = IsolateRoots(p, 1e-14);
  ASSERT_EQ(isolation.intervals.size(), 2u);
  EXPECT_FALSE(isolation.intervals[0].certified);
  EXPECT_FALSE(isolation.intervals[0].sign_change);
  EXPECT_LE(isolation.intervals[0].lower_t, 0.4);
  EXPECT_GE(isolation.intervals[0].upper_t, 0.4);
  EXPECT_TRUE(isolation.intervals[1].certified);
}

}  // namespace
}  // namespace gesweep
