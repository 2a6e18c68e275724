#pragma once
/// Analytic limit states with closed-form failure probabilities, written here from their formulas so
/// that the checks of engine/rare do not depend on the code under test:
///   linear:     g(u) = beta - a.u / |a| with a = (1, ..., 1): a.u / |a| ~ N(0, 1), so P = Phi(-beta);
///   chi-square: g(u) = c - |u|^2: |u|^2 ~ chi-square with d degrees of freedom, so
///               P = Q(d / 2, c / 2), the regularised upper incomplete gamma function;
///   series:     g(u) = beta - max_k s_k / sqrt(L), s_k the sum of window k of L coordinates (K
///               disjoint windows from coordinate 0): the s_k / sqrt(L) are K independent N(0, 1), so
///               P = 1 - (1 - Phi(-beta))^K. A union of K families of failures, one per window: a gust
///               that may come at any of K times.

#include <algorithm>
#include <boost/math/special_functions/erf.hpp>
#include <boost/math/special_functions/gamma.hpp>
#include <cmath>
#include <span>

namespace gesweep::rare::testing {

/// Phi(-beta) = erfc(beta / sqrt(2)) / 2.
inline double LinearTruth(double beta) { return 0.5 * boost::math::erfc(beta / std::sqrt(2.0)); }

inline double LinearLimitState(std::span<const double> u, double beta) {
  double sum = 0;
  for (const double v : u) sum += v;
  return beta - sum / std::sqrt(static_cast<double>(u.size()));
}

inline double ChiSquareTruth(int dimension, double c) {
  return boost::math::gamma_q(dimension / 2.0, c / 2.0);
}

/// The c for which P(|u|^2 > c) = p in d dimensions.
inline double ChiSquareThreshold(int dimension, double p) {
  return 2.0 * boost::math::gamma_q_inv(dimension / 2.0, p);
}

inline double ChiSquareLimitState(std::span<const double> u, double c) {
  double sum = 0;
  for (const double v : u) sum += v * v;
  return c - sum;
}

inline double SeriesTruth(int windows, double beta) {
  // 1 - (1 - q)^K without cancellation: -expm1(K log1p(-q)).
  return -std::expm1(windows * std::log1p(-LinearTruth(beta)));
}

inline double SeriesLimitState(std::span<const double> u, int windows, int length, double beta) {
  double largest = -1e300;
  for (int k = 0; k < windows; ++k) {
    double sum = 0;
    for (int i = 0; i < length; ++i) sum += u[static_cast<std::size_t>(k * length + i)];
    largest = std::max(largest, sum / std::sqrt(static_cast<double>(length)));
  }
  return beta - largest;
}

}  // namespace gesweep::rare::testing
