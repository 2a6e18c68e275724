// The Dryden low-altitude model (docs/model.md §9): scales worked by hand, spectra that integrate to
// σ², and forming filters whose frequency response and stationary covariance are the spectra's.
#include "engine/disturbance/dryden.h"

#include <gtest/gtest.h>

#include <boost/math/quadrature/exp_sinh.hpp>
#include <cmath>
#include <complex>
#include <numbers>

namespace gesweep {
namespace {

constexpr double kFt = 0.3048;
// Tolerances: each says where it comes from.
/// Closed forms evaluated two ways: rounding only, relative to the size of the terms compared.
constexpr double kRelativeTolerance = 1e-12;
/// exp_sinh on a smooth algebraic tail.
constexpr double kQuadratureTolerance = 1e-9;

TEST(DrydenScales, LowAltitudeFormulasByHand) {
  // L_w = h: the height converted to feet and back, rounding of lengths of 3 to 30 m (ulp ≤ 3.6e-15 m).
  constexpr double kLengthRounding_m = 1e-12;
  // L_u = h/base^1.2: the engine's b⁶ with b = base^0.2 against one pow here, a few roundings of a
  // 154 m length (~1e-13 m).
  constexpr double kPowerRounding_m = 1e-10;
  // At and above the 1000 ft ceiling both lengths are the clamped 304.8 m: rounding of the conversion
  // to feet and back (ulp 5.7e-14 m), with a wide margin.
  constexpr double kCeilingRounding_m = 1e-9;
  // docs/model.md §9 prints the floor's L_u = 23.05 m and σ_u = 1.963·σ_w: half a unit of each
  // printed value's last digit (the formula gives 23.0548 m and 1.96298).
  constexpr double kPrintedLength_m = 0.005;
  constexpr double kPrintedRatio = 5e-4;
  const double sigma_w = 1.543;  // 30 kt: 0.1 · 15.433 m/s
  // h = 100 ft: 0.177 + 0.0823 = 0.2593.
  const DrydenScales s = LowAltitudeDrydenScales(100 * kFt, sigma_w);
  EXPECT_EQ(s.sigma_w_mps, sigma_w);  // passed through
  EXPECT_NEAR(s.sigma_u_mps, sigma_w / std::pow(0.2593, 0.4), sigma_w * kRelativeTolerance);
  EXPECT_NEAR(s.length_w_m, 100 * kFt, kLengthRounding_m);
  EXPECT_NEAR(s.length_u_m, 100 * kFt / std::pow(0.2593, 1.2), kPowerRounding_m);
  // The 10 ft floor: docs/model.md §9 quotes L_u = 23.05 m and σ_u = 1.963 σ_w there.
  for (double h : {-1.0, 0.0, 0.788, 2.5935, 10 * kFt}) {
    const DrydenScales f = LowAltitudeDrydenScales(h, sigma_w);
    EXPECT_NEAR(f.length_w_m, 3.048, kLengthRounding_m) << h;
    EXPECT_NEAR(f.length_u_m, 23.05, kPrintedLength_m) << h;
    EXPECT_NEAR(f.sigma_u_mps / sigma_w, 1.963, kPrintedRatio) << h;
  }
  // At 1000 ft the denominator is exactly 1; above, held.
  for (double h : {1000 * kFt, 500.0}) {
    const DrydenScales t = LowAltitudeDrydenScales(h, sigma_w);
    EXPECT_NEAR(t.sigma_u_mps, sigma_w, sigma_w * kRelativeTolerance);
    EXPECT_NEAR(t.length_u_m, 304.8, kCeilingRounding_m);
    EXPECT_NEAR(t.length_w_m, 304.8, kCeilingRounding_m);
  }
}

TEST(DrydenSpectra, OneSidedIntegralsAreTheVariances) {
  // The spectra at Ω = 1/L below are about 92 (u) and 6.1 (w): a few roundings (ulp ≤ 1.4e-14).
  constexpr double kSpectrumRounding = 1e-12;
  boost::math::quadrature::exp_sinh<double> integrator;
  for (double h : {3.0, 30.0, 200.0}) {
    const DrydenScales s = LowAltitudeDrydenScales(h, 0.8);
    const double iu = integrator.integrate([&](double omega) { return DrydenSpectrumU(omega, s); });
    const double iw = integrator.integrate([&](double omega) { return DrydenSpectrumW(omega, s); });
    EXPECT_NEAR(iu, s.sigma_u_mps * s.sigma_u_mps, kQuadratureTolerance) << h;
    EXPECT_NEAR(iw, s.sigma_w_mps * s.sigma_w_mps, kQuadratureTolerance) << h;
  }
  // Values by hand at Ω = 1/L: Φ_u = σ²·(2L/π)/2, Φ_w = σ²·(L/π)·4/4.
  const DrydenScales s = LowAltitudeDrydenScales(30.0, 0.8);
  EXPECT_NEAR(DrydenSpectrumU(1 / s.length_u_m, s),
              s.sigma_u_mps * s.sigma_u_mps * s.length_u_m / std::numbers::pi, kSpectrumRounding);
  EXPECT_NEAR(DrydenSpectrumW(1 / s.length_w_m, s), 0.64 * s.length_w_m / std::numbers::pi,
              kSpectrumRounding);
}

// The filters as linear systems ẋ = A x + B ξ, read off the derivative functions with unit vectors.
struct Linear2 {
  double a11, a12, a21, a22, b1, b2;
};
Linear2 WFilter(double a) {
  Linear2 m{};
  double d1, d2;
  DrydenWDerivative(a, 1, 0, 0, &d1, &d2);
  m.a11 = d1;
  m.a21 = d2;
  DrydenWDerivative(a, 0, 1, 0, &d1, &d2);
  m.a12 = d1;
  m.a22 = d2;
  DrydenWDerivative(a, 0, 0, 1, &d1, &d2);
  m.b1 = d1;
  m.b2 = d2;
  return m;
}

TEST(DrydenFilters, FrequencyResponseIsTheSpectrum) {
  // Unit-intensity noise: the one-sided temporal spectrum of the output is |H(iω)|²/π, and it
  // must equal Φ(ω/V)/V/σ² (docs/model.md §9).
  const double v = 52.21;
  for (double h : {2.0, 30.0, 250.0}) {
    const DrydenScales s = LowAltitudeDrydenScales(h, 1.0);
    const DrydenFilterRates r = DrydenRates(s, v);
    const Linear2 m = WFilter(r.a_w_per_s);
    for (double omega : {0.01, 0.3, 1.0, 5.0, 40.0, 300.0}) {
      const std::complex<double> iw(0.0, omega);
      // u: H = b/(iω − a11) with b = ∂ż/∂ξ.
      const double bu = DrydenUDerivative(r.a_u_per_s, 0.0, 1.0);
      const double au = DrydenUDerivative(r.a_u_per_s, 1.0, 0.0);
      // The normalised filter has unit variance; u_g = σ_u·z (σ_u ≠ σ_w = 1 here).
      const double hu2 = s.sigma_u_mps * s.sigma_u_mps * std::norm(bu / (iw - au));
      EXPECT_NEAR(hu2 / std::numbers::pi, DrydenSpectrumU(omega / v, s) / v, kRelativeTolerance * (1 + hu2))
          << h << " " << omega;
      // w: H = C (iωI − A)⁻¹ B, C = [√3, 1 − √3].
      const std::complex<double> det = (iw - m.a11) * (iw - m.a22) - m.a12 * m.a21;
      const std::complex<double> x1 = ((iw - m.a22) * m.b1 + m.a12 * m.b2) / det;
      const std::complex<double> x2 = (m.a21 * m.b1 + (iw - m.a11) * m.b2) / det;
      const double hw2 = std::norm(std::sqrt(3.0) * x1 + (1.0 - std::sqrt(3.0)) * x2);
      EXPECT_NEAR(hw2 / std::numbers::pi, DrydenSpectrumW(omega / v, s) / v, kRelativeTolerance * (1 + hw2))
          << h << " " << omega;
    }
  }
}

TEST(DrydenFilters, StationaryCovarianceDoesNotDependOnTheRate) {
  // A P + P Aᵀ + B Bᵀ = 0 with P = [[1/2, 1/4], [1/4, 1/4]] for every a (w), and 2·a_u·1 = b² (u):
  // so a height or airspeed that varies leaves the variance at σ(h)².
  // Sums of order-one terms (√3, 1 − √3 and quarters): a few roundings, an ulp of 1 being 2.2e-16.
  constexpr double kUnitRounding = 1e-15;
  const double p11 = 0.5, p12 = 0.25, p22 = 0.25;
  for (double a : {0.05, 1.0, 17.0, 400.0}) {
    const Linear2 m = WFilter(a);
    const double r11 = 2 * (m.a11 * p11 + m.a12 * p12) + m.b1 * m.b1;
    const double r12 = m.a11 * p12 + m.a12 * p22 + p11 * m.a21 + p12 * m.a22 + m.b1 * m.b2;
    const double r22 = 2 * (m.a21 * p12 + m.a22 * p22) + m.b2 * m.b2;
    EXPECT_NEAR(r11, 0.0, kRelativeTolerance * a);
    EXPECT_NEAR(r12, 0.0, kRelativeTolerance * a);
    EXPECT_NEAR(r22, 0.0, kRelativeTolerance * a);
    // Output variance C P Cᵀ = 1.
    const double c1 = std::sqrt(3.0), c2 = 1 - std::sqrt(3.0);
    EXPECT_NEAR(c1 * c1 * p11 + 2 * c1 * c2 * p12 + c2 * c2 * p22, 1.0, kUnitRounding);
    EXPECT_NEAR(DrydenWOutput(1.0, 0.0), c1, kUnitRounding);
    const double bu = DrydenUDerivative(a, 0.0, 1.0);
    EXPECT_NEAR(2 * DrydenUDerivative(a, 1.0, 0.0) * 1.0 + bu * bu, 0.0, kRelativeTolerance * a);
  }
}

}  // namespace
}  // namespace gesweep
