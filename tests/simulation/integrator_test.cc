// The generic integrator (engine/simulation/integrator.h) against closed-form solutions: ẋ = λx,
// the harmonic oscillator, piecewise-constant inputs with breakpoints, events and phase switches.
#include "engine/simulation/integrator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <vector>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

// Tolerances: each says where it comes from.
/// The leading term of RK4's error predicts it to a few per cent at λh = 0.0325 (the next term is O(λh)
/// smaller).
constexpr double kLeadingTermAgreement = 0.05;
/// The local tolerance is 1e-8 relative; over a few dozen steps the global error stays within 1e-7.
constexpr double kGlobalRelativeTolerance = 1e-7;
/// Output times are start + j·interval: rounding of times up to 10 s.
constexpr double kGridTimeTolerance_s = 1e-12;
/// An event located on dense output inherits the method's state error over ω: ~1e-8 s here, with margin.
constexpr double kEventTimeTolerance_s = 1e-7;
/// RK4 at h = 0.05, ω = 2: state error ≈ t·ω(ωh)^4/120 ≈ 1.3e-6, time error half that.
constexpr double kRk4EventTimeTolerance_s = 2e-6;
/// The state at that event: the 1.3e-6 state error plus the slope times the time error, with margin.
constexpr double kRk4EventStateTolerance = 1e-5;
/// A few additions of O(0.1) numbers: rounding.
constexpr double kSumRoundingTolerance = 1e-13;
/// RK4's error at h = 0.01 over 0.1 s is far below 1e-8.
constexpr double kStoppedStateTolerance = 1e-8;

// Piecewise-linear solutions are exact for every Runge–Kutta method; what remains is the event
// bracket (1e-10 s by default) times a slope of 2, plus rounding.
constexpr double kPiecewiseLinearTolerance = 1e-9;

// ẋ = λx, x(0) = 1: x(t) = e^{λt}.
struct Decay {
  static constexpr int kDimension = 1;
  static constexpr int kEventCount = 0;
  double lambda = -1.3;
  void Derivative(double, const OdeState<1>& x, int, OdeState<1>& dxdt) { dxdt[0] = lambda * x[0]; }
  void EventValues(double, const OdeState<1>&, int, std::array<double, 0>&) {}
  EventAction OnEvent(int, double, const OdeState<1>&, int) { return EventAction::kContinue; }
  void OnStep(double, const OdeState<1>&, int) { ++steps_seen; }
  void OnOutput(double t, const OdeState<1>& x, int) {
    times.push_back(t);
    values.push_back(x[0]);
  }
  int steps_seen = 0;
  std::vector<double> times, values;
};

// ẍ = −ω²x as [x, v], x(0) = 1, v(0) = 0: x = cos ωt, v = −ω sin ωt. Event 0: x falls through 0
// (first at π/(2ω)); its action is configurable.
struct Oscillator {
  static constexpr int kDimension = 2;
  static constexpr int kEventCount = 1;
  double omega = 2.0;
  EventAction action = EventAction::kContinue;
  void Derivative(double, const OdeState<2>& x, int, OdeState<2>& dxdt) {
    dxdt[0] = x[1];
    dxdt[1] = -omega * omega * x[0];
  }
  void EventValues(double, const OdeState<2>& x, int, std::array<double, 1>& g) { g[0] = x[0]; }
  EventAction OnEvent(int, double t, const OdeState<2>& x, int) {
    event_times.push_back(t);
    event_values.push_back(x[0]);
    return action;
  }
  void OnStep(double, const OdeState<2>&, int) {}
  void OnOutput(double t, const OdeState<2>& x, int) {
    times.push_back(t);
    positions.push_back(x[0]);
  }
  std::vector<double> event_times, event_values, times, positions;
};

// ẋ = input(segment): a piecewise-constant input whose integral is exact for any Runge–Kutta
// method once no step straddles a jump.
struct PiecewiseInput {
  static constexpr int kDimension = 1;
  static constexpr int kEventCount = 0;
  std::vector<double> value_by_segment;
  std::vector<std::pair<double, int>> calls;  // (t, segment) of every Derivative call
  void Derivative(double t, const OdeState<1>&, int segment, OdeState<1>& dxdt) {
    calls.emplace_back(t, segment);
    dxdt[0] = value_by_segment[segment];
  }
  void EventValues(double, const OdeState<1>&, int, std::array<double, 0>&) {}
  EventAction OnEvent(int, double, const OdeState<1>&, int) { return EventAction::kContinue; }
  void OnStep(double, const OdeState<1>&, int) {}
  void OnOutput(double, const OdeState<1>&, int) {}
};

// ẋ = rate[phase]; event 0 at x = switch_at (g = switch_at − x falls) switches phase 0 → 1 with
// kRestart and then disables itself. x(t) = t up to 0.5, then 0.5 − 2(t − 0.5).
struct PhaseSwitch {
  static constexpr int kDimension = 1;
  static constexpr int kEventCount = 1;
  int phase = 0;
  double switch_at = 0.5;
  double rate[2] = {1.0, -2.0};
  std::vector<double> switch_times;
  std::vector<double> output_times, output_values;
  std::vector<int> output_phases;
  void Derivative(double, const OdeState<1>&, int, OdeState<1>& dxdt) { dxdt[0] = rate[phase]; }
  void EventValues(double, const OdeState<1>& x, int, std::array<double, 1>& g) {
    g[0] = phase == 0 ? switch_at - x[0] : 1.0;
  }
  EventAction OnEvent(int, double t, const OdeState<1>&, int) {
    switch_times.push_back(t);
    phase = 1;
    return EventAction::kRestart;
  }
  void OnStep(double, const OdeState<1>&, int) {}
  void OnOutput(double t, const OdeState<1>& x, int) {
    output_times.push_back(t);
    output_values.push_back(x[0]);
    output_phases.push_back(phase);
  }
};

// ẋ = x², x(0) = 1: x = 1/(1 − t) blows up at t = 1.
struct BlowUp {
  static constexpr int kDimension = 1;
  static constexpr int kEventCount = 0;
  void Derivative(double, const OdeState<1>& x, int, OdeState<1>& dxdt) { dxdt[0] = x[0] * x[0]; }
  void EventValues(double, const OdeState<1>&, int, std::array<double, 0>&) {}
  EventAction OnEvent(int, double, const OdeState<1>&, int) { return EventAction::kContinue; }
  void OnStep(double, const OdeState<1>&, int) {}
  void OnOutput(double, const OdeState<1>&, int) {}
};

IntegratorOptions Rk4(double step_s) {
  IntegratorOptions options;
  options.kind = IntegratorKind::kRk4;
  options.step_s = step_s;
  return options;
}

IntegratorOptions Dopri5(double rtol, double atol) {
  IntegratorOptions options;
  options.kind = IntegratorKind::kDopri5;
  options.relative_tolerance = rtol;
  options.absolute_tolerance = atol;
  options.step_s = 0.01;
  return options;
}

double Rk4DecayError(double step_s) {
  Decay problem;
  const auto result = Integrate(problem, OdeState<1>{1.0}, 0.0, 2.0, {}, Rk4(step_s));
  return std::abs(result.final_state[0] - std::exp(problem.lambda * 2.0));
}

TEST(Rk4Test, DecayMatchesTheExponentialAndConvergesAtFourthOrder) {
  // Halving the step divides the global error by 2^4 = 16 for a 4th-order method.
  const double e1 = Rk4DecayError(0.1);
  const double e2 = Rk4DecayError(0.05);
  const double e3 = Rk4DecayError(0.025);
  const double order_12 = std::log2(e1 / e2);
  const double order_23 = std::log2(e2 / e3);
  constexpr double kOrderTolerance = 0.1;  // the asymptotic slope is reached to ~1 % at these steps
  EXPECT_NEAR(order_12, 4.0, kOrderTolerance);
  EXPECT_NEAR(order_23, 4.0, kOrderTolerance);
  // The leading error term of RK4 on ẋ = λx over [0, T]: T·(λh)^4·λ e^{λT}/120 in magnitude.
  const double lambda = -1.3;
  const double predicted =
      2.0 * std::pow(lambda * 0.025, 4) * std::abs(lambda) * std::exp(lambda * 2.0) / 120.0;
  EXPECT_NEAR(e3 / predicted, 1.0, kLeadingTermAgreement);
}

TEST(Rk4Test, CountsFourEvaluationsPerStepPlusTheStart) {
  Decay problem;
  const auto result = Integrate(problem, OdeState<1>{1.0}, 0.0, 1.5, {}, Rk4(0.1));
  EXPECT_EQ(result.status, IntegrationStatus::kReachedEnd);
  EXPECT_EQ(result.accepted_steps, 15);
  EXPECT_EQ(result.rhs_calls, 4 * 15 + 1);
  EXPECT_EQ(result.end_time_s, 1.5);
  EXPECT_EQ(problem.steps_seen, 16);  // the initial point and every step
}

TEST(Dopri5Test, DecayMeetsItsTolerance) {
  Decay problem;
  const auto result = Integrate(problem, OdeState<1>{1.0}, 0.0, 2.0, {}, Dopri5(1e-8, 1e-12));
  EXPECT_EQ(result.status, IntegrationStatus::kReachedEnd);
  const double exact = std::exp(problem.lambda * 2.0);
  // The local tolerance is 1e-8 relative; over a few dozen steps the global error stays within 1e-7.
  EXPECT_NEAR(result.final_state[0], exact, kGlobalRelativeTolerance * exact);
  EXPECT_GT(result.accepted_steps, 5);
  EXPECT_LT(result.accepted_steps, 200);
}

// The step control is the PI controller of Hairer's DOPRI5 (Hairer, Norsett & Wanner, Solving ODEs I,
// 2nd ed., II.4; the code's defaults safe = 0.9, fac1 = 0.2, fac2 = 10, beta = 0.04), written here
// from the published formula with pow, against the engine's log/exp form: after an accepted step
// h_new = h / max(1/fac2, min(1/fac1, err^(0.2 - 0.75 beta) / err_prev^beta / safe)), no larger than
// h after a rejection; after a rejection h_new = h / min(1/fac1, err^(0.2 - 0.75 beta) / safe).
TEST(Dopri5Test, StepControlIsHairersPiController) {
  constexpr double kBeta = 0.04, kSafety = 0.9, kFac1 = 0.2, kFac2 = 10.0;
  const double exponent = 0.2 - 0.75 * kBeta;
  // log/exp against pow: a few ulp.
  constexpr double kRelativeTolerance = 1e-14;
  integrator_detail::PiStepAdjuster adjuster(0.0);
  double previous = 1.0;  // err_prev before the first step
  bool rejected = false;
  double h = 0.1;
  // Errors of accepted (<= 1) and rejected (> 1) trials, with the clamps at both ends reached.
  for (double error : {0.3, 0.8, 1e-9, 2.5, 40.0, 0.9, 1.0, 0.05, 3.0, 0.6}) {
    double expected;
    if (error > 1.0) {
      expected = h / std::min(1.0 / kFac1, std::pow(error, exponent) / kSafety);
      const double got = adjuster.decrease_step(h, error, 4);
      EXPECT_NEAR(got, expected, kRelativeTolerance * expected) << "rejected at err = " << error;
      rejected = true;
      h = got;
    } else {
      const double fac = std::pow(error, exponent) / std::pow(previous, kBeta) / kSafety;
      expected = h / std::max(1.0 / kFac2, std::min(1.0 / kFac1, fac));
      if (rejected) expected = std::min(expected, h);
      const double got = adjuster.increase_step(h, error, 5);
      EXPECT_NEAR(got, expected, kRelativeTolerance * expected) << "accepted at err = " << error;
      previous = std::max(error, 1e-4);
      rejected = false;
      h = got;
    }
  }
  // The largest step bounds every proposal.
  integrator_detail::PiStepAdjuster bounded(0.05);
  EXPECT_EQ(bounded.increase_step(0.04, 1e-6, 5), 0.05);
}

TEST(Dopri5Test, TighterToleranceGivesSmallerError) {
  auto error = [](double rtol) {
    Decay problem;
    const auto result = Integrate(problem, OdeState<1>{1.0}, 0.0, 2.0, {}, Dopri5(rtol, rtol * 1e-3));
    return std::abs(result.final_state[0] - std::exp(problem.lambda * 2.0));
  };
  EXPECT_LT(error(1e-9), error(1e-5));
}

TEST(OscillatorTest, BothMethodsFollowTheClosedFormAndSampleOnTheGrid) {
  constexpr double kEnd = 10.0;
  for (const IntegratorOptions& base : {Rk4(0.01), Dopri5(1e-9, 1e-12)}) {
    Oscillator problem;
    IntegratorOptions options = base;
    options.output_interval_s = 0.25;
    const auto result = Integrate(problem, OdeState<2>{1.0, 0.0}, 0.0, kEnd, {}, options);
    ASSERT_EQ(result.status, IntegrationStatus::kReachedEnd);
    // RK4 at h = 0.01, ω = 2: global error ~ T·ω(ωh)^4/120 ≈ 3e-9; dopri5 at rtol 1e-9 similar.
    constexpr double kStateTolerance = 1e-7;
    EXPECT_NEAR(result.final_state[0], std::cos(problem.omega * kEnd), kStateTolerance);
    EXPECT_NEAR(result.final_state[1], -problem.omega * std::sin(problem.omega * kEnd), kStateTolerance);
    ASSERT_EQ(problem.times.size(), 41u);  // 0, 0.25, …, 10
    for (std::size_t j = 0; j < problem.times.size(); ++j) {
      EXPECT_NEAR(problem.times[j], 0.25 * static_cast<double>(j), kGridTimeTolerance_s);
      // Interpolated samples (dense output / cubic Hermite) keep the method's accuracy.
      EXPECT_NEAR(problem.positions[j], std::cos(problem.omega * problem.times[j]), kStateTolerance);
    }
    // x = cos 2t falls through zero at π/4 + kπ: at π/4, 5π/4, 9π/4 (≈ 7.07) within 10 s.
    ASSERT_EQ(problem.event_times.size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) {
      const double exact =
          (std::numbers::pi / 2 + 2 * std::numbers::pi * static_cast<double>(k)) / problem.omega;
      EXPECT_NEAR(problem.event_times[k], exact, kEventTimeTolerance_s);
      // The located state is on the far side of the crossing, within the time tolerance of it.
      EXPECT_LE(problem.event_values[k], 0.0);
      EXPECT_GT(problem.event_values[k], -1e-9);
    }
  }
}

TEST(EventTest, StopEndsTheRunAtTheLocatedTimeNotAtTheStepEnd) {
  for (const IntegratorOptions& options : {Rk4(0.05), Dopri5(1e-10, 1e-13)}) {
    Oscillator problem;
    problem.action = EventAction::kStop;
    const auto result = Integrate(problem, OdeState<2>{1.0, 0.0}, 0.0, 10.0, {}, options);
    EXPECT_EQ(result.status, IntegrationStatus::kStoppedByEvent);
    EXPECT_EQ(result.stopping_event, 0);
    const double exact = std::numbers::pi / 4;  // 0.785…, inside the RK4 step [0.75, 0.8]
    // RK4 at h = 0.05, ω = 2: state error ≈ t·ω(ωh)^4/120 ≈ 1.3e-6, time error half that.
    EXPECT_NEAR(result.end_time_s, exact, kRk4EventTimeTolerance_s);
    EXPECT_EQ(result.final_state[0], problem.event_values[0]);
    EXPECT_NEAR(result.final_state[1], -problem.omega, kRk4EventStateTolerance);
  }
}

TEST(EventTest, RestartSwitchesThePhaseExactlyAtTheEvent) {
  // Piecewise-linear solution: every Runge–Kutta method is exact on it, so all errors are rounding.
  for (const IntegratorOptions& base : {Rk4(0.15), Dopri5(1e-6, 1e-9)}) {
    PhaseSwitch problem;
    IntegratorOptions options = base;
    options.output_interval_s = 0.1;
    const auto result = Integrate(problem, OdeState<1>{0.0}, 0.0, 1.0, {}, options);
    EXPECT_EQ(result.status, IntegrationStatus::kReachedEnd);
    ASSERT_EQ(problem.switch_times.size(), 1u);
    EXPECT_NEAR(problem.switch_times[0], 0.5, kPiecewiseLinearTolerance);
    EXPECT_NEAR(result.final_state[0], 0.5 - 2.0 * 0.5, kPiecewiseLinearTolerance);
    for (std::size_t j = 0; j < problem.output_times.size(); ++j) {
      const double t = problem.output_times[j];
      const double exact = t <= 0.5 ? t : 0.5 - 2.0 * (t - 0.5);
      EXPECT_NEAR(problem.output_values[j], exact, kPiecewiseLinearTolerance) << "t = " << t;
      // Outputs before the switch are emitted before the problem changes.
      EXPECT_EQ(problem.output_phases[j], t <= 0.5 ? 0 : 1) << "t = " << t;
    }
  }
}

TEST(EventTest, RestartKeepsTheRk4Grid) {
  PhaseSwitch problem;
  problem.switch_at = 0.52;  // inside the step [0.45, 0.6]
  const auto result = Integrate(problem, OdeState<1>{0.0}, 0.0, 1.2, {}, Rk4(0.15));
  // 8 grid steps, one of them split at the switch (a cut step counts once, its rest is one more).
  EXPECT_EQ(result.accepted_steps, 9);
  EXPECT_NEAR(result.final_state[0], 0.52 - 2.0 * (1.2 - 0.52), kPiecewiseLinearTolerance);
}

TEST(BreakpointTest, HonouredBreakpointsMakeAPulseExact) {
  // ẋ = 1 on [0.1, 0.3), 0 elsewhere: x(1) = 0.2 exactly when no step straddles 0.1 or 0.3.
  const std::vector<double> breakpoints = {0.1, 0.3};
  for (const IntegratorOptions& base : {Rk4(0.15), Dopri5(1e-3, 1e-6)}) {
    PiecewiseInput problem{{0.0, 1.0, 0.0}, {}};
    const auto result = Integrate(problem, OdeState<1>{0.0}, 0.0, 1.0, breakpoints, base);
    EXPECT_NEAR(result.final_state[0], 0.2, kSumRoundingTolerance);  // a few additions of rounding
    // A step ending at a breakpoint evaluates its last stage with the left segment.
    for (const auto& [t, segment] : problem.calls) {
      EXPECT_TRUE((t < 0.1 && segment == 0) || (t == 0.1) || (t > 0.1 && t < 0.3 && segment == 1) ||
                  t == 0.3 || (t > 0.3 && segment == 2))
          << "t = " << t << " segment " << segment;
    }
  }
}

TEST(BreakpointTest, StraddlingStepsAreInexactLikeThePapersPlainRk4) {
  // RK4 at h = 0.15 without breakpoints: the steps [0, 0.15] and [0.15, 0.3], [0.3, 0.45] straddle
  // or touch the jumps and the stage rule sees the input only at t, t + h/2, t + h: the integral of
  // the pulse is no longer 0.2.
  PiecewiseInput problem{{0.0, 1.0, 0.0}, {}};
  IntegratorOptions options = Rk4(0.15);
  options.honour_breakpoints = false;
  const std::vector<double> breakpoints = {0.1, 0.3};
  const auto result = Integrate(problem, OdeState<1>{0.0}, 0.0, 1.0, breakpoints, options);
  // Step [0, 0.15]: stages at 0 (0), 0.075 (0), 0.075 (0), 0.15 (1) → 0.15/6. Step [0.15, 0.3]:
  // 1, 1, 1, and at 0.3 the segment is 2 (0) → 0.15·5/6. Then 0. Total 0.15.
  EXPECT_NEAR(result.final_state[0], 0.15 / 6 + 0.15 * 5 / 6, kSumRoundingTolerance);
}

TEST(FailureTest, BlowUpIsReportedAsNonFiniteWithTheLastFiniteState) {
  for (const IntegratorOptions& options : {Rk4(0.01), Dopri5(1e-6, 1e-9)}) {
    BlowUp problem;
    const auto result = Integrate(problem, OdeState<1>{1.0}, 0.0, 2.0, {}, options);
    EXPECT_TRUE(result.status == IntegrationStatus::kNonFinite ||
                result.status == IntegrationStatus::kStepSizeUnderflow)
        << ToString(result.status);
    EXPECT_TRUE(std::isfinite(result.final_state[0]));
    // The exact solution blows up at t = 1; the numerical one overflows a few steps from it.
    EXPECT_LT(result.end_time_s, 1.1);
    EXPECT_GT(result.end_time_s, 0.9);
  }
}

TEST(OptionsTest, ValidationNamesTheField) {
  IntegratorOptions options;
  options.step_s = 0.0;
  try {
    ValidateIntegratorOptions(options, "test");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "step_s");
  }
  options = IntegratorOptions{};
  options.relative_tolerance = -1e-3;
  EXPECT_THROW(ValidateIntegratorOptions(options, "test"), InputError);
  options = IntegratorOptions{};
  options.output_interval_s = std::nan("");
  EXPECT_THROW(ValidateIntegratorOptions(options, "test"), InputError);
  EXPECT_NO_THROW(ValidateIntegratorOptions(IntegratorOptions{}, "test"));
  EXPECT_EQ(ParseEnum<IntegratorKind>("dopri5"), IntegratorKind::kDopri5);
  EXPECT_EQ(ParseEnum<IntegratorKind>("rk45"), std::nullopt);
}

// Sets the cancellation flag from inside the run, after a given number of accepted steps.
struct CancellingDecay : Decay {
  std::atomic<bool>* cancel = nullptr;
  int cancel_after_steps = 0;
  void OnStep(double t, const OdeState<1>& x, int segment) {
    Decay::OnStep(t, x, segment);
    // OnStep runs at the initial point too: steps_seen - 1 steps are accepted.
    if (steps_seen - 1 == cancel_after_steps) cancel->store(true);
  }
};

TEST(CancellationTest, AFlagSetBeforeTheRunStopsItBeforeTheFirstStep) {
  for (IntegratorKind kind : {IntegratorKind::kRk4, IntegratorKind::kDopri5}) {
    std::atomic<bool> cancel{true};
    Decay problem;
    IntegratorOptions options;
    options.kind = kind;
    options.cancel = &cancel;
    const auto result = Integrate(problem, OdeState<1>{1.0}, 0.0, 10.0, {}, options);
    EXPECT_EQ(result.status, IntegrationStatus::kCancelled) << ToString(kind);
    EXPECT_EQ(result.accepted_steps, 0);
    EXPECT_EQ(result.end_time_s, 0.0);
    EXPECT_EQ(result.final_state[0], 1.0);
  }
}

TEST(CancellationTest, AFlagSetDuringTheRunStopsItAtTheNextStep) {
  for (IntegratorKind kind : {IntegratorKind::kRk4, IntegratorKind::kDopri5}) {
    std::atomic<bool> cancel{false};
    CancellingDecay problem;
    problem.cancel = &cancel;
    problem.cancel_after_steps = 10;
    IntegratorOptions options;
    options.kind = kind;
    options.step_s = 0.01;
    options.max_step_s = 0.01;  // dopri5: at least 1000 steps to the end
    options.cancel = &cancel;
    const auto result = Integrate(problem, OdeState<1>{1.0}, 0.0, 10.0, {}, options);
    EXPECT_EQ(result.status, IntegrationStatus::kCancelled) << ToString(kind);
    EXPECT_EQ(result.accepted_steps, 10) << ToString(kind);
    EXPECT_LT(result.end_time_s, 10.0);
    // The final state is the state where it stopped: e^{λt} there (RK4's error at h = 0.01 is far
    // below 1e-8 over 0.1 s).
    EXPECT_NEAR(result.final_state[0], std::exp(problem.lambda * result.end_time_s), kStoppedStateTolerance)
        << ToString(kind);
  }
}

TEST(CancellationTest, NoFlagRunsToTheEnd) {
  std::atomic<bool> cancel{false};
  Decay problem;
  IntegratorOptions options;
  options.cancel = &cancel;
  const auto result = Integrate(problem, OdeState<1>{1.0}, 0.0, 1.0, {}, options);
  EXPECT_EQ(result.status, IntegrationStatus::kReachedEnd);
  EXPECT_EQ(ToString(IntegrationStatus::kCancelled), "cancelled");
}

}  // namespace
}  // namespace gesweep
