// The forming filters of DisturbanceField over long records in the engine's integrator (RK4 with
// the field's breakpoints): their outputs have the Dryden variances and spectra of docs/model.md §9.
// The oracle is the specification's formula, written out here by hand, and Boost quadrature.
#include <gtest/gtest.h>

#include <algorithm>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <cmath>
#include <complex>
#include <numbers>
#include <unsupported/Eigen/FFT>
#include <vector>

#include "engine/disturbance/disturbance_field.h"
#include "engine/simulation/integrator.h"

namespace gesweep {
namespace {

constexpr double kFt = 0.3048;
constexpr double kPi = std::numbers::pi;

// The airplane held at a height and inertial speed; only the field's states are integrated.
struct FieldOnly {
  static constexpr int kDimension = DisturbanceField::kStateCount;
  static constexpr int kEventCount = 0;
  using State = OdeState<kDimension>;
  const DisturbanceField* field;
  const std::vector<DisturbanceField::Segment>* table;
  double height_m;
  double speed_mps;
  std::vector<double> u, w;
  void Derivative(double, const State& x, int segment, State& dxdt) {
    field->Evaluate((*table)[segment], height_m, speed_mps, x, dxdt);
  }
  void EventValues(double, const State&, int, std::array<double, 0>&) const {}
  EventAction OnEvent(int, double, const State&, int) { return EventAction::kContinue; }
  void OnStep(double, const State&, int) {}
  void OnOutput(double, const State& x, int segment) {
    State unused;
    const AirMotion m = field->Evaluate((*table)[segment], height_m, speed_mps, x, unused);
    u.push_back(m.turbulence_u_mps);
    w.push_back(m.turbulence_w_mps);
  }
};

struct Record {
  std::vector<double> u, w;
  double output_interval_s;
  double airspeed_mps;
};

Record Fly(double height_m, double speed_mps, double sample_interval_s, double duration_s,
           double output_interval_s, double sigma_w_mps, std::uint64_t run) {
  DisturbanceOptions options;
  options.turbulence = TurbulenceModel::kDryden;
  options.turbulence_sigma_w_mps = sigma_w_mps;
  options.turbulence_sample_interval_s = sample_interval_s;
  const DisturbanceField field(options, 17, run);
  const std::vector<double> breakpoints = field.Breakpoints(0.0, duration_s);
  const std::vector<DisturbanceField::Segment> table = field.SegmentTable(breakpoints, 0.0);
  FieldOnly problem{&field, &table, height_m, speed_mps, {}, {}};
  IntegratorOptions io;
  io.step_s = sample_interval_s;
  io.output_interval_s = output_interval_s;
  const auto result = Integrate(problem, field.InitialState(), 0.0, duration_s, breakpoints, io);
  EXPECT_EQ(result.status, IntegrationStatus::kReachedEnd);
  return {std::move(problem.u), std::move(problem.w), output_interval_s, speed_mps};
}

// The specification's spectra (docs/model.md §9), one-sided in time: Φ(ω/V)/V.
struct HandScales {
  double sigma_u, sigma_w, length_u, length_w;
};
HandScales Hand(double height_m, double sigma_w) {
  const double h_ft = std::max(height_m / kFt, 10.0);
  const double base = 0.177 + 0.000823 * h_ft;
  return {sigma_w / std::pow(base, 0.4), sigma_w, h_ft / std::pow(base, 1.2) * kFt, h_ft * kFt};
}
double TimeSpectrumU(double omega, const HandScales& s, double v) {
  const double lo = s.length_u * omega / v;
  return s.sigma_u * s.sigma_u * 2 * s.length_u / kPi / (1 + lo * lo) / v;
}
double TimeSpectrumW(double omega, const HandScales& s, double v) {
  const double lo2 = std::pow(s.length_w * omega / v, 2);
  return s.sigma_w * s.sigma_w * s.length_w / kPi * (1 + 3 * lo2) / ((1 + lo2) * (1 + lo2)) / v;
}
// Noise held over Δt has the time-averaged spectrum of white noise times sinc²(ωΔt/2).
double HoldFactor(double omega, double dt) {
  const double x = 0.5 * omega * dt;
  return x == 0 ? 1.0 : std::pow(std::sin(x) / x, 2);
}
template <class F>
double VarianceWithHold(F spectrum, double dt) {
  return boost::math::quadrature::gauss_kronrod<double, 61>::integrate(
      [&](double omega) { return spectrum(omega) * HoldFactor(omega, dt); }, 0.0,
      std::numeric_limits<double>::infinity(), 20, 1e-10);
}

double Variance(const std::vector<double>& x) {
  double mean = 0, s = 0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  for (double v : x) s += (v - mean) * (v - mean);
  return s / static_cast<double>(x.size());
}

// Welch's estimate (periodic Hann window, half overlap, mean removed per segment), one-sided, per rad/s.
struct Welch {
  std::vector<double> omega, psd;
  int segments = 0;
};
Welch WelchEstimate(const std::vector<double>& x, double dt, int n) {
  std::vector<double> window(n);
  double window_power = 0;
  for (int i = 0; i < n; ++i) {
    window[i] = 0.5 - 0.5 * std::cos(2 * kPi * i / n);
    window_power += window[i] * window[i];
  }
  Welch out;
  out.psd.assign(n / 2 + 1, 0.0);
  Eigen::FFT<double> fft;
  std::vector<double> segment(n);
  std::vector<std::complex<double>> spectrum;
  for (std::size_t start = 0; start + n <= x.size(); start += n / 2) {
    double mean = 0;
    for (int i = 0; i < n; ++i) mean += x[start + i];
    mean /= n;
    for (int i = 0; i < n; ++i) segment[i] = (x[start + i] - mean) * window[i];
    fft.fwd(spectrum, segment);
    for (int k = 0; k <= n / 2; ++k) out.psd[k] += std::norm(spectrum[k]);
    ++out.segments;
  }
  const double fs = 1 / dt;
  for (int k = 0; k <= n / 2; ++k) {
    // per Hz one-sided: 2|X|²/(fs Σw²); per rad/s: divide by 2π.
    out.psd[k] *= 2.0 / (fs * window_power * out.segments) / (2 * kPi);
    out.omega.push_back(2 * kPi * k * fs / n);
  }
  return out;
}

// Compares the Welch estimate with the spectrum in logarithmic bins from 4 resolutions to omega_max.
// Tolerance per bin: a Welch ordinate over K half-overlapping Hann segments has relative sd
// √(1.06/K) (the overlap correlation of Hann, Welch 1967); m adjacent ordinates are correlated by
// the window, counted as m/1.5 independent ones; 5 sd, plus 3 % for the window's smoothing of the
// spectrum's curvature at 4 resolutions from zero (≈ ¼(δω/a)² at the corner a, below 1 % here).
template <class F>
void ExpectSpectrum(const Welch& welch, F expected, double omega_max, const char* name) {
  const double resolution = welch.omega[1];
  const double low = 4 * resolution;
  const int bins = 8;
  const double ratio = std::pow(omega_max / low, 1.0 / bins);
  for (int b = 0; b < bins; ++b) {
    const double lo = low * std::pow(ratio, b), hi = lo * ratio;
    double sum_est = 0, sum_exp = 0;
    int m = 0;
    for (std::size_t k = 1; k < welch.omega.size(); ++k) {
      if (welch.omega[k] >= lo && welch.omega[k] < hi) {
        sum_est += welch.psd[k];
        sum_exp += expected(welch.omega[k]);
        ++m;
      }
    }
    ASSERT_GT(m, 0);
    const double sd = std::sqrt(1.06 / welch.segments) / std::sqrt(std::max(1.0, m / 1.5));
    EXPECT_NEAR(sum_est / sum_exp, 1.0, 5 * sd + 0.03)
        << name << " bin " << lo << "-" << hi << " rad/s, " << m << " ordinates";
  }
}

// Relative sd of the variance of a record of length T: √(2∫ρ²dτ/T), with ∫ρ² dτ over the whole line
// = L_u/V for u (ρ = e^{−a|τ|}) and 0.625·L_w/V for w (Parseval on Φ_w: ∫(1+3x²)²/(1+x²)⁴ dx = 5π/4).
double VarianceSd(double integral_rho2_s, double duration_s) {
  return std::sqrt(2 * integral_rho2_s / duration_s);
}

void CheckRecord(double height_m, double dt, double duration, double output_dt, int welch_length) {
  constexpr double kSigmaW = 0.1;  // small: the turbulence modulates the filters' airspeed by < 0.5 %
  constexpr double kV = 50.0;
  const Record r = Fly(height_m, kV, dt, duration, output_dt, kSigmaW, 3);
  const HandScales s = Hand(height_m, kSigmaW);
  const auto phi_u = [&](double omega) { return TimeSpectrumU(omega, s, kV); };
  const auto phi_w = [&](double omega) { return TimeSpectrumW(omega, s, kV); };
  // Expected variances: σ² reduced by the hold (the w filter's Φ ~ ω⁻² tail reaches past 1/Δt).
  const double var_u = VarianceWithHold(phi_u, dt);
  const double var_w = VarianceWithHold(phi_w, dt);
  // The hold keeps tanh(aΔt/2)/(aΔt/2) of σ_u² (docs/disturbance.md), above 0.999999 at these steps; the
  // quadrature of the ω⁻² tail to infinity adds its own error (measured 2e-4 at 100 ft, 7e-4 at the
  // floor). 1 % bounds both; a lost factor 2 or π in the spectrum or the hold is far outside.
  constexpr double kHeldUVarianceTolerance = 0.01;
  EXPECT_NEAR(var_u / (s.sigma_u * s.sigma_u), 1.0, kHeldUVarianceTolerance);
  const double sd_u = VarianceSd(s.length_u / kV, duration);
  const double sd_w = VarianceSd(0.625 * s.length_w / kV, duration);
  // 4 sd: the records are fixed by the seed; a lost factor π or a wrong gain is many sd away.
  EXPECT_NEAR(Variance(r.u) / var_u, 1.0, 4 * sd_u) << "u at " << height_m << " m, sd " << sd_u;
  EXPECT_NEAR(Variance(r.w) / var_w, 1.0, 4 * sd_w) << "w at " << height_m << " m, sd " << sd_w;
  // Spectra up to a tenth of the output's Nyquist frequency (aliasing of the ω⁻² tail < 1 %).
  const double omega_max = 0.1 * kPi / output_dt;
  ExpectSpectrum(
      WelchEstimate(r.u, output_dt, welch_length),
      [&](double omega) { return phi_u(omega) * HoldFactor(omega, dt); }, omega_max, "u");
  ExpectSpectrum(
      WelchEstimate(r.w, output_dt, welch_length),
      [&](double omega) { return phi_w(omega) * HoldFactor(omega, dt); }, omega_max, "w");
}

TEST(TurbulenceStatistics, VarianceAndSpectrumAt100Feet) {
  // L_u = 154 m, L_w = 30.5 m at 50 m/s: 4000 s is 1300 u correlation times.
  CheckRecord(100 * kFt, 0.002, 4000.0, 0.01, 16384);
}

TEST(TurbulenceStatistics, VarianceAndSpectrumAtTheTenFootFloor) {
  // Below 10 ft the scales stay at 10 ft: L_u = 23.05 m, L_w = 3.048 m (a_w = 16.4 s⁻¹ at 50 m/s).
  CheckRecord(2.0, 0.001, 1000.0, 0.005, 8192);
}

TEST(TurbulenceStatistics, HoldLossOfTheWVarianceAsDocumented) {
  // docs/disturbance.md quotes the w variance kept at the 10 ft floor and 52.21 m/s for Δt_n:
  // 0.958 at 5 ms, 0.882 at 15 ms (the quadrature of Φ_w·sinc², independent of the field).
  const HandScales s = Hand(2.0, 1.0);
  // The table prints 3 decimals: rounding is half a unit of the last one, and one unit leaves the other
  // half for this quadrature's error (SciPy's quad gives 0.95837 and 0.88186).
  constexpr double kPrintedDigit = 0.001;
  const auto phi_w = [&](double omega) { return TimeSpectrumW(omega, s, 52.21); };
  EXPECT_NEAR(VarianceWithHold(phi_w, 0.005), 0.958, kPrintedDigit);
  EXPECT_NEAR(VarianceWithHold(phi_w, 0.015), 0.882, kPrintedDigit);
}

}  // namespace
}  // namespace gesweep
