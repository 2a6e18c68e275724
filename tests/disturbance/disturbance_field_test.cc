// DisturbanceField inside the engine's integrator: breakpoints and segments, a turbulence that is
// the same function of time whatever the integrator, replay by (seed, run), the gust through the
// field, and the airplane of Eq. (1) in a steady headwind (docs/model.md §9).
#include "engine/disturbance/disturbance_field.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/disturbance/discrete_gust.h"
#include "engine/disturbance/mean_wind.h"
#include "engine/dynamics/longitudinal_model.h"
#include "engine/simulation/integrator.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

using Segment = DisturbanceField::Segment;

// The field alone at a fixed height and inertial speed; records the air motion at each output.
struct FieldOnly {
  static constexpr int kDimension = DisturbanceField::kStateCount;
  static constexpr int kEventCount = 0;
  using State = OdeState<kDimension>;
  const DisturbanceField* field;
  const std::vector<Segment>* table;
  double height_m;
  double speed_mps;
  std::vector<AirMotion> air;
  void Derivative(double, const State& x, int segment, State& dxdt) {
    field->Evaluate((*table)[segment], height_m, speed_mps, x, dxdt);
  }
  void EventValues(double, const State&, int, std::array<double, 0>&) const {}
  EventAction OnEvent(int, double, const State&, int) { return EventAction::kContinue; }
  void OnStep(double, const State&, int) {}
  void OnOutput(double, const State& x, int segment) {
    State unused;
    air.push_back(field->Evaluate((*table)[segment], height_m, speed_mps, x, unused));
  }
};

std::vector<AirMotion> FlyField(const DisturbanceOptions& options, std::uint64_t seed, std::uint64_t run,
                                const IntegratorOptions& io, double duration_s, double height_m = 20.0,
                                double speed_mps = 40.0) {
  const DisturbanceField field(options, seed, run);
  const std::vector<double> breakpoints = field.Breakpoints(0.0, duration_s);
  const std::vector<Segment> table = field.SegmentTable(breakpoints, 0.0);
  FieldOnly problem{&field, &table, height_m, speed_mps, {}};
  const auto result = Integrate(problem, field.InitialState(), 0.0, duration_s, breakpoints, io);
  EXPECT_EQ(result.status, IntegrationStatus::kReachedEnd);
  return problem.air;
}

DisturbanceOptions Turbulent() {
  DisturbanceOptions o;
  o.wind_20ft_mps = -15.433;  // 30 kt headwind: σ_w = 1.5433 m/s
  o.turbulence = TurbulenceModel::kDryden;
  o.turbulence_sample_interval_s = 0.01;
  return o;
}

TEST(DisturbanceField, BreakpointsAndSegments) {
  DisturbanceOptions o = Turbulent();
  o.gust_amplitude_mps = 2.0;
  o.gust_start_s = 0.035;
  const DisturbanceField field(o, 1, 2);
  const std::vector<double> b = field.Breakpoints(0.0, 0.05);
  ASSERT_EQ(b.size(), 5u);
  EXPECT_EQ(b[0], 0.01);
  EXPECT_EQ(b[2], 3 * 0.01);
  EXPECT_EQ(b[3], 0.035);
  EXPECT_EQ(b[4], 4 * 0.01);
  // A list merged with other inputs' breakpoints (an elevator pulse at 0.005 and 0.02).
  std::vector<double> merged = {0.005, 0.01, 0.02, 0.03, 0.035, 0.04};
  const std::vector<Segment> t = field.SegmentTable(merged, 0.0);
  ASSERT_EQ(t.size(), 7u);
  const std::int64_t expected_index[] = {0, 0, 1, 2, 3, 3, 4};
  const bool expected_gust[] = {false, false, false, false, false, true, true};
  for (int s = 0; s < 7; ++s) {
    EXPECT_EQ(t[s].sample_index, expected_index[s]) << s;
    EXPECT_EQ(t[s].gust_started, expected_gust[s]) << s;
  }
  EXPECT_EQ(field.SampleIndexAt(0.0), 0);
  EXPECT_EQ(field.SampleIndexAt(0.0099999), 0);
  EXPECT_EQ(field.SampleIndexAt(0.01), 1);
  EXPECT_EQ(field.SampleIndexAt(0.3), 30);  // 0.3/0.01 rounds below 30 in floating point
  // Still air: no breakpoints, zero air motion.
  const DisturbanceField still(DisturbanceOptions{}, 1, 2);
  EXPECT_FALSE(still.active());
  EXPECT_TRUE(still.Breakpoints(0.0, 100.0).empty());
  DisturbanceField::State dx;
  const AirMotion m = still.Evaluate({}, 3.0, 32.0, still.InitialState(), dx);
  EXPECT_EQ(m.u_g_mps, 0.0);
  EXPECT_EQ(m.w_g_mps, 0.0);
  EXPECT_EQ(m.airspeed_mps, 32.0);
  for (double v : dx) EXPECT_EQ(v, 0.0);
}

TEST(DisturbanceField, SameTurbulenceWhateverTheIntegrator) {
  // The held noise is a function of time; the filter outputs then differ only by integration error.
  IntegratorOptions coarse;
  coarse.step_s = 0.01;
  coarse.output_interval_s = 0.05;
  IntegratorOptions fine = coarse;
  fine.step_s = 0.0025;
  IntegratorOptions adaptive = coarse;
  adaptive.kind = IntegratorKind::kDopri5;
  adaptive.relative_tolerance = 1e-10;
  adaptive.absolute_tolerance = 1e-12;
  const auto a = FlyField(Turbulent(), 5, 11, coarse, 20.0);
  const auto b = FlyField(Turbulent(), 5, 11, fine, 20.0);
  const auto c = FlyField(Turbulent(), 5, 11, adaptive, 20.0);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), c.size());
  // At 20 m and 40 m/s a_w = V/L_w = 2 s⁻¹, so RK4's a·h ≤ 0.02 and its error is ~1e-9 of σ_w; the
  // bound 1e-4 m/s (1e-4 of σ_w = 1.54 m/s) leaves room for dopri5's error control, and a noise that
  // depended on the steps would differ by O(σ_w).
  constexpr double kIntegratorAgreement_mps = 1e-4;
  double largest = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a[i].w_g_mps, c[i].w_g_mps, kIntegratorAgreement_mps) << i;
    EXPECT_NEAR(b[i].w_g_mps, c[i].w_g_mps, kIntegratorAgreement_mps) << i;
    EXPECT_NEAR(a[i].u_g_mps, c[i].u_g_mps, kIntegratorAgreement_mps) << i;
    largest = std::max(largest, std::abs(c[i].w_g_mps));
  }
  EXPECT_GT(largest, 1.0) << "the record must carry turbulence of σ_w = 1.54 m/s";
}

TEST(DisturbanceField, ReplayedBySeedAndRunIndex) {
  IntegratorOptions io;
  io.step_s = 0.01;
  io.output_interval_s = 0.1;
  const auto a = FlyField(Turbulent(), 5, 11, io, 10.0);
  const auto again = FlyField(Turbulent(), 5, 11, io, 10.0);
  const auto other = FlyField(Turbulent(), 5, 12, io, 10.0);
  ASSERT_EQ(a.size(), again.size());
  int differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].w_g_mps, again[i].w_g_mps);
    EXPECT_EQ(a[i].u_g_mps, again[i].u_g_mps);
    differ += a[i].w_g_mps != other[i].w_g_mps;
  }
  EXPECT_EQ(differ, static_cast<int>(a.size()));
}

// The field's caches (the height's terms, the filters' rates, the noise sample) and its values at
// the clamped heights change no bit: every call of a field with a history equals the same call of a
// fresh field, and Motion equals Evaluate's air motion. At the ceiling and the floor the scales are
// checked against the specification's formulas by hand.
TEST(DisturbanceField, CachesAndClampedHeightsChangeNoBit) {
  DisturbanceOptions o = Turbulent();
  o.gust_axis = GustAxis::kW;
  o.gust_amplitude_mps = -3.0;
  o.gust_half_length_m = 20.0;
  o.pitch_rate_gust = true;
  o.wing_span_m = 12.0;
  const DisturbanceField used(o, 7, 3);
  const DisturbanceField::State x = {0.3, -0.7, 0.2, 0.05, 11.0};
  struct Call {
    double height_m, speed_mps;
    std::int64_t sample;
  };
  // Repeated heights and airspeeds with a new sample (a step's end and its restart), heights above the
  // 1000 ft ceiling, at and below the 10 ft floor, below z0, and back.
  const std::vector<Call> calls = {{50.0, 45.0, 0},  {50.0, 45.0, 1}, {50.0, 46.0, 1},  {400.0, 45.0, 1},
                                   {304.8, 45.0, 2}, {1e6, 45.0, 2},  {3.048, 45.0, 2}, {1.0, 45.0, 3},
                                   {0.01, 45.0, 3},  {50.0, 45.0, 0}, {-1.0, 45.0, 4},  {400.0, 45.0, 4},
                                   {50.0, -5.0, 4},  {50.0, 45.0, 4}};
  for (const Call& c : calls) {
    const DisturbanceField fresh(o, 7, 3);
    const Segment segment{c.sample, true};
    DisturbanceField::State d_used, d_fresh;
    const AirMotion a = used.Evaluate(segment, c.height_m, c.speed_mps, x, d_used);
    const AirMotion b = fresh.Evaluate(segment, c.height_m, c.speed_mps, x, d_fresh);
    const AirMotion m = used.Motion(segment, c.height_m, c.speed_mps, x);
    for (const AirMotion* other : {&b, &m}) {
      EXPECT_EQ(a.u_g_mps, other->u_g_mps) << c.height_m;
      EXPECT_EQ(a.w_g_mps, other->w_g_mps) << c.height_m;
      EXPECT_EQ(a.q_g_radps, other->q_g_radps) << c.height_m;
      EXPECT_EQ(a.airspeed_mps, other->airspeed_mps) << c.height_m;
      EXPECT_EQ(a.mean_wind_mps, other->mean_wind_mps) << c.height_m;
      EXPECT_EQ(a.turbulence_u_mps, other->turbulence_u_mps) << c.height_m;
      EXPECT_EQ(a.turbulence_w_mps, other->turbulence_w_mps) << c.height_m;
      EXPECT_EQ(a.gust_mps, other->gust_mps) << c.height_m;
    }
    EXPECT_EQ(a.w_g_dot_mps2, b.w_g_dot_mps2) << c.height_m;
    EXPECT_TRUE(std::isnan(m.w_g_dot_mps2)) << "Motion does not compute the rate of w_g";
    for (int i = 0; i < DisturbanceField::kStateCount; ++i) EXPECT_EQ(d_used[i], d_fresh[i]) << c.height_m;
  }
  // By hand (MIL-F-8785C low altitude, h in ft clamped to [10, 1000]): at 1000 ft the base
  // 0.177 + 0.000823·1000 is 1, so σ_u = σ_w; at 10 ft it is 0.18523, σ_u = σ_w/0.18523^0.4; the
  // mean wind above 1000 ft is W20·ln(1000/0.15)/ln(20/0.15).
  constexpr double kRelativeTolerance = 1e-14;  // a few roundings of the formulas
  const double sigma_w = 0.1 * 15.433;
  DisturbanceField::State unused;
  const AirMotion high = used.Evaluate({5, true}, 1e4, 45.0, x, unused);
  EXPECT_NEAR(high.turbulence_u_mps, sigma_w * x[0], kRelativeTolerance * sigma_w);
  EXPECT_NEAR(high.mean_wind_mps, -15.433 * std::log(1000.0 / 0.15) / std::log(20.0 / 0.15),
              kRelativeTolerance * 15.433 * 2);
  const AirMotion low = used.Evaluate({5, true}, 0.5, 45.0, x, unused);
  EXPECT_NEAR(low.turbulence_u_mps, sigma_w / std::pow(0.18523, 0.4) * x[0], kRelativeTolerance * sigma_w);
}

TEST(DisturbanceField, GustThroughTheField) {
  DisturbanceOptions o;
  o.gust_axis = GustAxis::kW;
  o.gust_amplitude_mps = -3.0;  // an up gust
  o.gust_half_length_m = 20.0;
  o.gust_start_s = 1.0;
  IntegratorOptions io;
  io.step_s = 0.01;
  io.output_interval_s = 0.02;
  const double v = 40.0;
  const auto air = FlyField(o, 0, 0, io, 4.0, 20.0, v);
  // Closed form: the distance into the gust is V·(t − t_s) at a constant airspeed.
  constexpr double kTolerance = 1e-9;  // RK4 integrates the constant-rate distance exactly; rounding only
  // ẇ_g is the same closed form's slope at that distance, values up to 9.4 m/s²: rounding only (the
  // largest difference is 1.5e-13 m/s²); the bound is generous.
  constexpr double kRateTolerance_mps2 = 1e-7;
  for (std::size_t i = 0; i < air.size(); ++i) {
    const double t = 0.02 * static_cast<double>(i);
    const double x = std::max(0.0, v * (t - 1.0));
    EXPECT_NEAR(air[i].w_g_mps, -1.5 * (1 - std::cos(std::numbers::pi * std::min(x, 40.0) / 20.0)),
                kTolerance)
        << t;
    const double slope =
        x < 40.0 ? -1.5 * std::numbers::pi / 20.0 * std::sin(std::numbers::pi * x / 20.0) : 0.0;
    EXPECT_NEAR(air[i].w_g_dot_mps2, slope * v, kRateTolerance_mps2) << t;
    EXPECT_EQ(air[i].u_g_mps, 0.0);
  }
  EXPECT_NEAR(air[75].w_g_mps, -3.0, kTolerance) << "peak at d_m: t = 1 + 20/40 s";
}

TEST(DisturbanceField, PitchRateGustIsTheLaggedGradientOfAWGust) {
  // q_g = −(w_g − p)·π/(4b), ṗ = (w_g − p)/τ, τ = 4b/(πV). For w_g = (v/2)(1 − cos ωt') (ω = πV/d_m,
  // t' = t − t_s) and p(t_s) = 0 the lag has the closed form
  //   p = (v/2)[(1 − e^{−t'/τ}) − (cos ωt' + ωτ sin ωt' − e^{−t'/τ})/(1 + ω²τ²)].
  DisturbanceOptions o;
  o.gust_amplitude_mps = 2.5;
  o.gust_half_length_m = 30.0;
  o.gust_start_s = 0.5;
  o.pitch_rate_gust = true;
  o.wing_span_m = 5.187;
  IntegratorOptions io;
  io.step_s = 0.001;
  io.output_interval_s = 0.01;
  const double v = 40.0;
  const auto air = FlyField(o, 0, 0, io, 2.0, 20.0, v);
  const double tau = 4 * o.wing_span_m / (std::numbers::pi * v);
  const double omega = std::numbers::pi * v / o.gust_half_length_m;
  constexpr double kTolerance = 1e-8;  // RK4 at ω·h, h/τ ≤ 0.01: local error ~ 1e-12 per step
  for (std::size_t i = 0; i < air.size(); ++i) {
    const double t = 0.01 * static_cast<double>(i) - o.gust_start_s;
    if (t < 0 || t > 2 * o.gust_half_length_m / v) continue;
    const double e = std::exp(-t / tau);
    const double p = 1.25 * ((1 - e) - (std::cos(omega * t) + omega * tau * std::sin(omega * t) - e) /
                                           (1 + omega * omega * tau * tau));
    const double w = 1.25 * (1 - std::cos(omega * t));
    EXPECT_NEAR(air[i].w_g_mps, w, kTolerance) << t;
    EXPECT_NEAR(air[i].q_g_radps, -(w - p) * std::numbers::pi / (4 * o.wing_span_m), kTolerance) << t;
  }
  // For a gust much longer than the span q_g ≈ −ẇ_g/V = −∂w_g/∂x: the sign convention of q_a = q − q_g.
  EXPECT_LT(air[70].q_g_radps, 0.0) << "q_g = −∂w_g/∂x < 0 while w_g grows along the path (t' = 0.2 s)";
}

// The airplane of Eq. (1) in air-relative form with the field's air motion: 5 + 5 states.
struct AirplaneInWind {
  static constexpr int kDimension = 5 + DisturbanceField::kStateCount;
  static constexpr int kEventCount = 0;
  using State = OdeState<kDimension>;
  const LongitudinalModel* model;
  const DisturbanceField* field;
  const std::vector<Segment>* table;
  double h0, u0;
  AirMotion last;
  void Derivative(double, const State& x, int segment, State& dxdt) {
    DisturbanceField::State xf, dxf;
    std::copy(x.begin() + 5, x.end(), xf.begin());
    last = field->Evaluate((*table)[segment], h0 + x[kDeltaH], u0 + x[kDeltaU], xf, dxf);
    const Vector5d x5(x[0], x[1], x[2], x[3], x[4]);
    const Vector5d d5 = model->StateDerivative(
        h0, u0, x5, 0.0, AirVelocity{last.u_g_mps, last.w_g_mps, last.q_g_radps, last.w_g_dot_mps2});
    for (int i = 0; i < 5; ++i) dxdt[i] = d5[i];
    std::copy(dxf.begin(), dxf.end(), dxdt.begin() + 5);
  }
  void EventValues(double, const State&, int, std::array<double, 0>&) const {}
  EventAction OnEvent(int, double, const State&, int) { return EventAction::kContinue; }
  void OnStep(double, const State&, int) {}
  void OnOutput(double, const State&, int) {}
};

struct WindRun {
  OdeState<10> final_state;
  AirMotion air;
};

WindRun FlyAirplane(const DisturbanceOptions& options, double h0, double u0, double initial_delta_u,
                    const IntegratorOptions& io, double duration_s) {
  static const LongitudinalModel model(LoadAircraftFile(testing::AnceAircraftPath()), ModelOptions{});
  const DisturbanceField field(options, 0, 0);
  const std::vector<double> breakpoints = field.Breakpoints(0.0, duration_s);
  const std::vector<Segment> table = field.SegmentTable(breakpoints, 0.0);
  AirplaneInWind problem{&model, &field, &table, h0, u0, {}};
  OdeState<10> x0{};
  x0[kDeltaU] = initial_delta_u;
  const auto result = Integrate(problem, x0, 0.0, duration_s, breakpoints, io);
  EXPECT_EQ(result.status, IntegrationStatus::kReachedEnd);
  OdeState<10> dx;
  problem.Derivative(duration_s, result.final_state, result.final_segment, dx);  // air motion at the end
  return {result.final_state, problem.last};
}

TEST(SteadyHeadwind, EquilibriumIsDeltaUEqualsMinusWindAtAirspeedU0) {
  // With shear: at 50 m the 15 kt (20 ft) headwind is u_g = W(50 m) < −W20. Started at Δu = u_g the
  // airplane is in equilibrium: ground speed u0 + u_g, airspeed u0, and it stays there exactly.
  DisturbanceOptions o;
  o.wind_20ft_mps = -7.717;
  const double h0 = 50.0, u0 = 32.0208;
  const double u_g = MeanWindAt(o.wind_20ft_mps, h0, WindShear::kLogarithmic);
  // docs/model.md §9's table prints W/W20 = 1.430 at 50 m (3 decimals): half a unit of it is 0.004 m/s
  // of this wind; 0.01 m/s bounds it.
  constexpr double kPrintedRatioTolerance_mps = 0.01;
  EXPECT_NEAR(u_g, -7.717 * 1.430, kPrintedRatioTolerance_mps);
  IntegratorOptions io;  // the paper's RK4, 0.015 s
  const WindRun held = FlyAirplane(o, h0, u0, u_g, io, 30.0);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(held.final_state[i], i == kDeltaU ? u_g : 0.0) << i;
  constexpr double kOneRounding_mps = 1e-12;  // (u0 + u_g) − u_g: one rounding (an ulp of 32 m/s is 7e-15)
  EXPECT_NEAR(held.air.airspeed_mps, u0, kOneRounding_mps);
  // The same start in still air is not an equilibrium: the airplane slows and sinks (the test can fail).
  const WindRun still = FlyAirplane(DisturbanceOptions{}, h0, u0, u_g, io, 30.0);
  EXPECT_GT(std::abs(still.final_state[kDeltaH]), 1.0);
}

TEST(SteadyHeadwind, ReachedFromTheStillAirTrim) {
  // Entering a steady 4 m/s headwind (no shear) at the still-air trim: the airspeed jumps to u0 + 4,
  // the phugoid that follows decays, and the airplane settles at Δu = −4 m/s, airspeed u0, q = 0, at
  // a new height (the height mode is neutral in free flight).
  DisturbanceOptions o;
  o.wind_20ft_mps = -4.0;
  o.wind_shear = WindShear::kNone;
  IntegratorOptions io;
  io.kind = IntegratorKind::kDopri5;
  io.relative_tolerance = 1e-10;
  io.absolute_tolerance = 1e-12;
  io.step_s = 0.01;
  const WindRun r = FlyAirplane(o, 60.0, 32.0208, 0.0, io, 3000.0);
  // What the phugoid leaves after 3000 s: its real part is −0.0033 s⁻¹ out of ground effect (the
  // README's modes table), so e^−9.9 ≈ 5e-5 of the 4 m/s entry, 2e-4 m/s (measured 2.1e-4 m/s); and of
  // its pitch rate, ω²·4 m/s/g ≈ 0.025 rad/s at ω = 0.25 rad/s (Lanchester), 1.3e-6 rad/s (measured
  // 1.3e-6). The bounds are about a hundredfold that; the still-air answer Δu = 0 is 4 m/s away.
  constexpr double kSettled_mps = 0.02;
  constexpr double kSettledPitchRate_radps = 1e-4;
  EXPECT_NEAR(r.final_state[kDeltaU], -4.0, kSettled_mps);
  EXPECT_NEAR(r.air.airspeed_mps, 32.0208, kSettled_mps);
  EXPECT_NEAR(r.final_state[kPitchRate], 0.0, kSettledPitchRate_radps);
  EXPECT_GT(r.final_state[kDeltaH], 1.0) << "the excess airspeed was traded for height";
}

// Issue 26, item 5: SIGINT/SIGTERM are heard while a run's noise table is built (the flag is read
// every kCancelCheckInterval entries), so a stop never waits for the table.
TEST(DisturbanceField, TheNoiseTableStopsBeingBuiltOnceCancelled) {
  DisturbanceOptions o = Turbulent();
  o.turbulence_sample_interval_s = 1e-4;
  const DisturbanceField field(o, 1, 2);
  std::atomic<bool> cancel{false};
  const std::vector<double> whole = field.Breakpoints(0.0, 1000.0, &cancel);
  EXPECT_EQ(whole.size(), 9999999u);  // k = 1 .. 1e7 - 1: 1e7 samples, the limit (input_limits.h)
  cancel.store(true);
  EXPECT_TRUE(field.Breakpoints(0.0, 1000.0, &cancel).empty());
  const std::vector<Segment> table = field.SegmentTable(whole, 0.0, &cancel);
  ASSERT_EQ(table.size(), whole.size() + 1);  // sized as the list, left unfilled
  EXPECT_EQ(table.back().sample_index, 0);
  cancel.store(false);
  EXPECT_EQ(field.SegmentTable(whole, 0.0, &cancel).back().sample_index, 9999999);
}

}  // namespace
}  // namespace gesweep
