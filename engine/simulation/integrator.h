#pragma once
/// Generic time integration for the engine's time responses (docs/model.md §7, docs/simulation.md):
/// fixed-step classical RK4 and adaptive Dormand–Prince 5(4), input breakpoints that no step
/// straddles, event functions located inside the step, output sampled on a regular grid, and step
/// and right-hand-side counts. The open-loop run (open_loop.h) and the closed-loop landing
/// (engine/control) are both problems solved by `Integrate`.
///
/// How to use it (the whole API is on this page; the implementation is in integrator_detail.h):
///
///   struct MyProblem {                       // satisfies the OdeProblem concept below
///     static constexpr int kDimension = 9;   // number of states
///     static constexpr int kEventCount = 2;  // number of event functions (may be 0)
///     void Derivative(double t, const OdeState<9>& x, int segment, OdeState<9>& dxdt);
///     void EventValues(double t, const OdeState<9>& x, int segment, std::array<double, 2>& g);
///     EventAction OnEvent(int event, double t, const OdeState<9>& x, int segment);
///     void OnStep(double t, const OdeState<9>& x, int segment);    // after each accepted step
///     void OnOutput(double t, const OdeState<9>& x, int segment);  // every output_interval_s
///   };
///   MyProblem problem{...};
///   const double breakpoints_s[] = {0.0, 0.2};  // times where the inputs jump, ascending
///   IntegrationResult<9> r = Integrate(problem, x0, 0.0, 300.0, breakpoints_s, options);
///
/// Segments. The sorted breakpoints b_0 < b_1 < … cut time into segments: segment k is
/// [b_{k-1}, b_k) (segment 0 is before b_0; the segment of a time t is the number of breakpoints
/// ≤ t). Every call to the problem carries the segment index so that piecewise inputs need no
/// comparisons in the hot path (a piecewise-constant input is a table indexed by segment).
/// - options.honour_breakpoints = true (default): no step straddles a breakpoint. A step that ends
///   at b_k belongs to segment k and all its stage evaluations, including the one at t = b_k, carry
///   segment k (the input's left limit); the next step starts at b_k with segment k+1 and a freshly
///   evaluated derivative. RK4 keeps its grid t0 + n·step_s: the step containing a breakpoint is
///   split in two.
/// - honour_breakpoints = false: every stage evaluation carries the segment of its own time, so a
///   step may straddle a jump (the paper's plain fixed-step RK4; SciPy's solve_ivp behaves so).
///
/// Events. Event i fires when g_i goes from > 0 at the start of a step to ≤ 0 at its end (falling
/// crossings only: write −g for a rising crossing, and return a positive constant to disable an
/// event). Its time is located on the step's interpolant (RK4: cubic Hermite through both ends and
/// their derivatives; dopri5: the method's 4th-order dense output) by TOMS 748 to a bracket of
/// options.event_time_tolerance_s; the reported time is the bracket end past the crossing, so g ≤ 0
/// there and the event does not fire again at once. When several events fire in one step they are
/// handled in time order; OnEvent returns what to do:
/// - kContinue: record only (e.g. a local minimum); the run goes on, the problem must not change.
/// - kStop: the run ends at the event time with status kStoppedByEvent (e.g. touchdown).
/// - kRestart: the problem changed at the event (e.g. a flare switch): the step is cut at the event,
///   the integrator restarts from the event state with a fresh derivative (RK4 goes on to its next
///   grid point), and every g is re-evaluated after the change (so the switching event can disable
///   itself). Events later in the cut step are discarded and found again if they still occur.
/// An event whose function changes sign twice within one step is missed; bound the step (RK4's
/// step_s, dopri5's max_step_s) below the time scale of the event functions.
///
/// Hooks and output. OnStep is called at the initial point and at the end of every accepted step
/// (at the event time when an event cuts the step). When options.output_interval_s > 0, OnOutput is
/// called at t0 + j·output_interval_s for every such time up to the end of the run, interpolated
/// inside the step (exact at RK4 grid points), then once more at the end time if that is not on the
/// grid; outputs up to an event's time are emitted before its OnEvent is called.
///
/// Failures are data: a non-finite state or derivative ends the run with kNonFinite and the last
/// finite state; a dopri5 step that falls below 1e-12·max(1, |t|) s ends it with kStepSizeUnderflow.
///
/// Cancellation. When options.cancel is set, Integrate reads it (a relaxed atomic load) before every
/// step and ends the run with kCancelled at the current point once it is true: a signal handler or
/// a deadline stops even a run of 1e8 steps within one step.
/// No heap allocation happens inside Integrate (states are std::array; the problem decides for its
/// own hooks).

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "engine/common/describe.h"
#include "engine/common/enum_names.h"

namespace gesweep {

/// A state of N components. std::array keeps it on the stack and lets Boost.Odeint use its
/// unrolled array algebra; map it to Eigen with AsEigen for matrix work.
template <int N>
using OdeState = std::array<double, N>;

/// A read-only Eigen view of a state (no copy).
template <int N>
Eigen::Map<const Eigen::Matrix<double, N, 1>> AsEigen(const OdeState<N>& x) {
  return Eigen::Map<const Eigen::Matrix<double, N, 1>>(x.data());
}
/// A writable Eigen view of a state (no copy).
template <int N>
Eigen::Map<Eigen::Matrix<double, N, 1>> AsEigen(OdeState<N>& x) {
  return Eigen::Map<Eigen::Matrix<double, N, 1>>(x.data());
}

/// The integration method.
enum class IntegratorKind {
  kRk4,     ///< classical 4th-order Runge–Kutta, fixed step (the paper's, 0.015 s)
  kDopri5,  ///< Dormand–Prince 5(4), error-controlled step, 4th-order dense output (Boost.Odeint)
};

/// Names in study files, flags and output: "rk4", "dopri5" (ToString, ParseEnum, EnumChoices).
GESWEEP_ENUM_NAMES(IntegratorKind, {kRk4, "rk4"}, {kDopri5, "dopri5"});

/// The limits-table entries (input_limits.h) of the integrator's steps for one analysis, and the
/// one-line docs of its adaptive settings as that analysis words them.
struct IntegratorLimitNames {
  std::string_view step_s = "open_loop.step_s";
  std::string_view max_step_s = "open_loop.max_step_s";
  std::string_view relative_tolerance_doc = "dopri5 relative tolerance";
  std::string_view absolute_tolerance_doc = "dopri5 absolute tolerance";
  std::string_view max_step_doc = "dopri5 largest step, s; 0: no limit";
};

/// Options of Integrate. Defaults: the paper's RK4 at 0.015 s with breakpoints honoured.
struct IntegratorOptions {
  IntegratorKind kind = IntegratorKind::kRk4;
  /// RK4: the fixed step, s. Dopri5: the first trial step, s. > 0.
  double step_s = 0.015;
  /// Dopri5: relative and absolute tolerances of the local error estimate, per component
  /// err_i ≤ absolute + relative·(|x_i| + step·|ẋ_i|) (Boost.Odeint's default_error_checker). > 0.
  double relative_tolerance = 1e-6;
  double absolute_tolerance = 1e-9;
  /// Dopri5: the largest step, s; 0 means no limit. ≥ 0.
  double max_step_s = 0.0;
  /// false: steps may straddle input breakpoints (reproduces the paper's plain RK4). See above.
  bool honour_breakpoints = true;
  /// > 0: OnOutput every output_interval_s seconds; 0: no output. ≥ 0.
  double output_interval_s = 0.0;
  /// Events are located to a time bracket of this width, s. In (0, 1e-6].
  double event_time_tolerance_s = 1e-10;
  /// Not null: checked before every step; the run ends with kCancelled once it holds true.
  const std::atomic<bool>* cancel = nullptr;

  /// The settings a person gives (describe.h); output_interval_s, event_time_tolerance_s and cancel
  /// are set by the caller. `limits` names the ranges of the analysis the options belong to.
  template <class V>
  void Describe(V& v, const IntegratorLimitNames& limits = {}) {
    v(Field("integrator", &kind)
          .Doc("Integration method: rk4 (fixed step, the paper's) or dopri5 (adaptive)"));
    v(Field("step_s", &step_s).Unit("s").Limit(limits.step_s).Doc("RK4 step (dopri5: first trial step), s"));
    DescribeAdaptive(v, limits);
    v(Field("honour_breakpoints", &honour_breakpoints)
          .Doc("true: no step straddles an input jump; false: steps may (the paper's plain fixed-step RK4)"));
  }

  /// The adaptive (dopri5) settings alone: a record that embeds these options and fixes the method
  /// (the landing: dopri5, its first step derived) describes only these.
  template <class V>
  void DescribeAdaptive(V& v, const IntegratorLimitNames& limits = {}) {
    v(Field("relative_tolerance", &relative_tolerance)
          .Limit("relative_tolerance")
          .Doc(limits.relative_tolerance_doc));
    v(Field("absolute_tolerance", &absolute_tolerance)
          .Limit("absolute_tolerance")
          .Doc(limits.absolute_tolerance_doc));
    v(Field("max_step_s", &max_step_s).Unit("s").Limit(limits.max_step_s).Doc(limits.max_step_doc));
  }
};

/// Throws InputError(source, <field name>, value, expectation) when an option is out of range.
void ValidateIntegratorOptions(const IntegratorOptions& options, const std::string& source);

/// What the integrator does after OnEvent (see the events paragraph above).
enum class EventAction {
  kContinue,  ///< record only; the problem is unchanged
  kStop,      ///< end the run at the event
  kRestart,   ///< the problem changed at the event: restart the integration from the event state
};

/// How a run ended.
enum class IntegrationStatus {
  kReachedEnd,         ///< the end time was reached
  kStoppedByEvent,     ///< an event returned kStop
  kNonFinite,          ///< a state or derivative became NaN or ±∞ (the final state is the last finite one)
  kStepSizeUnderflow,  ///< dopri5 could not meet its tolerance with a representable step
  kCancelled,          ///< options.cancel became true; the final state is where the run stopped
};

/// "reached_end" / "stopped_by_event" / "non_finite" / "step_size_underflow" / "cancelled".
GESWEEP_ENUM_NAMES(IntegrationStatus, {kReachedEnd, "reached_end"}, {kStoppedByEvent, "stopped_by_event"},
                   {kNonFinite, "non_finite"}, {kStepSizeUnderflow, "step_size_underflow"},
                   {kCancelled, "cancelled"});

/// What Integrate returns. Counts include everything: `rhs_calls` counts every Derivative call
/// (RK4: 1 at the start, 4 per step, 1 per breakpoint or restart; dopri5: 1 at the start, 6 per
/// trial step, 1 per breakpoint or restart).
template <int N>
struct IntegrationResult {
  IntegrationStatus status = IntegrationStatus::kReachedEnd;
  double end_time_s = 0.0;    ///< time of the final state
  OdeState<N> final_state{};  ///< state at end_time_s
  int final_segment = 0;      ///< segment of the final state
  int stopping_event = -1;    ///< index of the event that stopped the run, else -1
  long accepted_steps = 0;    ///< steps accepted (a step cut short by an event counts once)
  long rejected_steps = 0;    ///< dopri5 trial steps rejected by the error control
  long rhs_calls = 0;         ///< Derivative calls
  long events_fired = 0;      ///< OnEvent calls
};

/// A problem that Integrate can solve; see the top of this file for the meaning of each hook.
/// Derivative must be deterministic and smooth in t and x within a segment (and within a phase,
/// for problems with kRestart events). All hooks are called on the integrating thread.
template <class P>
concept OdeProblem = requires(P& problem, double t, const OdeState<P::kDimension>& x,
                              OdeState<P::kDimension>& dxdt, int segment, int event,
                              std::array<double, P::kEventCount>& values) {
  requires P::kDimension >= 1;
  requires P::kEventCount >= 0;
  problem.Derivative(t, x, segment, dxdt);
  problem.EventValues(t, x, segment, values);
  { problem.OnEvent(event, t, x, segment) } -> std::same_as<EventAction>;
  problem.OnStep(t, x, segment);
  problem.OnOutput(t, x, segment);
};

/// Integrates `problem` from (start_time_s, initial_state) to end_time_s or the first stopping event.
/// Preconditions (GESWEEP_DEMAND): end_time_s > start_time_s, both finite; breakpoints_s ascending;
/// options valid (call ValidateIntegratorOptions on anything a person wrote). Breakpoints outside
/// (start, end) only set the starting segment. Numerical failures are reported in the status.
template <OdeProblem P>
IntegrationResult<P::kDimension> Integrate(P& problem, const OdeState<P::kDimension>& initial_state,
                                           double start_time_s, double end_time_s,
                                           std::span<const double> breakpoints_s,
                                           const IntegratorOptions& options);

}  // namespace gesweep

#include "engine/simulation/integrator_detail.h"
