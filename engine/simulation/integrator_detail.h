#pragma once
// The implementation of Integrate (engine/simulation/integrator.h). Not part of the API: include
// integrator.h. Everything here works on stack arrays; nothing allocates.

#include <algorithm>
#include <array>
#include <boost/math/tools/toms748_solve.hpp>
#include <boost/numeric/odeint/stepper/controlled_runge_kutta.hpp>
#include <boost/numeric/odeint/stepper/runge_kutta_dopri5.hpp>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>

#include "engine/common/errors.h"

namespace gesweep::integrator_detail {

/// True when every component is finite: x·0 is 0 for finite x and NaN for NaN or ±∞.
template <int N>
inline bool AllFinite(const OdeState<N>& x) {
  double sum = 0.0;
  for (double v : x) sum += v * 0.0;
  return sum == 0.0;
}

/// The segment of time t: the number of breakpoints ≤ t (there are only a handful).
inline int SegmentOf(std::span<const double> breakpoints_s, double t) {
  int k = 0;
  const int count = static_cast<int>(breakpoints_s.size());
  while (k < count && breakpoints_s[k] <= t) ++k;
  return k;
}

/// Relative width below which a step end and a grid or output time are the same instant: far above
/// the rounding of t0 + n·h, far below any step anyone would choose.
inline constexpr double kSnapFraction = 1e-9;

/// Smallest dopri5 step relative to max(1, |t|): below it t + dt no longer carries ~4 digits of dt.
inline constexpr double kMinRelativeStep = 1e-12;

/// Largest number of consecutive rejected dopri5 trials before the run is declared stuck.
inline constexpr int kMaxConsecutiveRejections = 200;

/// TOMS 748 iterations allowed per event; it converges in well under 20 on a smooth interpolant.
inline constexpr std::uintmax_t kMaxEventIterations = 100;

/// Whether an event's value crossed in a step: from > 0 before it to ≤ 0 after (the one test of
/// LocateEvents and AnyEventCrossing).
inline bool EventCrossed(double g_previous, double g_new) { return g_previous > 0.0 && g_new <= 0.0; }

/// The events that fired in a step from t to t_new: those whose value fell from > 0 at t to ≤ 0 at
/// t_new, in time order. An event that is 0 at t_new fired there; one below 0 is located on the step's
/// interpolant by TOMS 748 between t and t_new, to `tolerance` in time, and reported at the bracket's
/// right end (past the crossing, g ≤ 0 there). g_at(i, tau): event i's value at tau in [t, t_new].
template <std::size_t E>
struct FiredEvents {
  std::array<double, E> time{};  ///< by event: when it fired (only the fired ones are set)
  std::array<int, E> order{};    ///< the fired events, earliest first
  int count = 0;
};

template <std::size_t E, class EventValueAt>
FiredEvents<E> LocateEvents(const std::array<double, E>& g_previous, const std::array<double, E>& g_new,
                            double t, double t_new, double tolerance, EventValueAt&& g_at) {
  FiredEvents<E> fired;
  for (int i = 0; i < static_cast<int>(E); ++i) {
    if (!EventCrossed(g_previous[i], g_new[i])) continue;
    double t_event = t_new;
    if (g_new[i] < 0.0) {
      auto g_of = [&](double tau) { return g_at(i, tau); };
      auto converged = [tolerance](double a, double b) { return std::abs(b - a) <= tolerance; };
      std::uintmax_t iterations = kMaxEventIterations;
      t_event =
          boost::math::tools::toms748_solve(g_of, t, t_new, g_previous[i], g_new[i], converged, iterations)
              .second;
    }
    fired.time[i] = t_event;
    // Insertion by time keeps the handful of simultaneous events ordered.
    int position = fired.count++;
    while (position > 0 && fired.time[fired.order[position - 1]] > t_event) {
      fired.order[position] = fired.order[position - 1];
      --position;
    }
    fired.order[position] = i;
  }
  return fired;
}

/// Whether any event value crossed (EventCrossed): without one, LocateEvents fires nothing.
template <std::size_t E>
bool AnyEventCrossing(const std::array<double, E>& g_previous, const std::array<double, E>& g_new) {
  for (std::size_t i = 0; i < E; ++i) {
    if (EventCrossed(g_previous[i], g_new[i])) return true;
  }
  return false;
}

/// Where an event cut a step: the first event whose OnEvent did not continue.
template <int N>
struct StepCut {
  EventAction action = EventAction::kContinue;
  double t = 0;    ///< the event's time
  OdeState<N> x;   ///< the state there (set by FireEvents)
  int event = -1;  ///< the event
};

/// The events that fired in the step from t to t_new (values g_previous at t, g_new at t_new),
/// located on the step's interpolant within `tolerance` and taken in time order: before each, the
/// outputs through its time (emit_outputs_through), then OnEvent at the interpolated state, until
/// one does not continue. Returns whether one cut the step, and then `cut` says where. IntegrateWith's
/// events, and every lane's (simulation/lane_loop.h).
template <int N, class P, class Events, class Interpolate, class SegmentAt, class EmitThrough>
bool FireEvents(P& problem, const Events& g_previous, const Events& g_new, double t, double t_new,
                double tolerance, Interpolate&& interpolate, SegmentAt&& segment_at,
                EmitThrough&& emit_outputs_through, long& events_fired, StepCut<N>& cut) {
  const auto fired = LocateEvents(g_previous, g_new, t, t_new, tolerance, [&](int i, double tau) {
    OdeState<N> xs;
    interpolate(tau, xs);
    Events values;
    problem.EventValues(tau, xs, segment_at(tau), values);
    return values[static_cast<std::size_t>(i)];
  });
  for (int k = 0; k < fired.count; ++k) {
    const int i = fired.order[static_cast<std::size_t>(k)];
    const double t_event = fired.time[static_cast<std::size_t>(i)];
    interpolate(t_event, cut.x);
    emit_outputs_through(t_event, interpolate);
    ++events_fired;
    const EventAction action = problem.OnEvent(i, t_event, cut.x, segment_at(t_event));
    if (action == EventAction::kContinue) continue;
    cut.action = action;
    cut.t = t_event;
    cut.event = i;
    return true;
  }
  return false;
}

enum class StepOutcome { kAccepted, kNonFinite, kUnderflow };

/// Fixed-step classical RK4 on the grid t0 + n·h. The derivative at the step start is given, so a
/// step costs 3 new evaluations; the 4th evaluates the derivative at the step end, which the cubic
/// Hermite interpolant needs and the next step reuses as its first stage.
template <int N>
class Rk4Method {
 public:
  using State = OdeState<N>;

  Rk4Method(double start_time_s, const IntegratorOptions& options)
      : grid_start_s_(start_time_s), step_s_(options.step_s) {}

  template <class Rhs>
  StepOutcome Advance(Rhs& rhs, double t, const State& x, const State& f, double t_limit, double& t_new,
                      State& x_new, State& f_new, long& /*rejected*/) {
    const double t_to = StepEnd(grid_start_s_, step_s_, grid_index_, t, t_limit);
    // The classical tableau (Kutta 1901) written out on local arrays rather than through odeint's
    // runge_kutta4: the compiler then keeps the stages in registers. Measured on the 30 s paper run
    // with re-evaluation (tests/bench, before double buffering): 205 µs with odeint's stepper,
    // 186 µs written out.
    const double h = t_to - t;
    const double half_h = 0.5 * h;
    const double sixth_h = h / 6.0;
    State stage, k2, k3, k4;
    for (int i = 0; i < N; ++i) stage[i] = x[i] + half_h * f[i];
    rhs(stage, k2, t + half_h);
    for (int i = 0; i < N; ++i) stage[i] = x[i] + half_h * k2[i];
    rhs(stage, k3, t + half_h);
    for (int i = 0; i < N; ++i) stage[i] = x[i] + h * k3[i];
    rhs(stage, k4, t_to);
    for (int i = 0; i < N; ++i) x_new[i] = x[i] + sixth_h * ((f[i] + k4[i]) + 2.0 * (k2[i] + k3[i]));
    rhs(x_new, f_new, t_to);
    // A non-finite derivative shows in the next step's state; checking x alone halves the cost.
    if (!AllFinite<N>(x_new)) return StepOutcome::kNonFinite;
    t_new = t_to;
    return StepOutcome::kAccepted;
  }

  /// The end of a step from t on the grid grid_start + n·step: the next grid point, or t_limit when
  /// it comes before it or lands on it (within the snap of it: a breakpoint or end time that
  /// coincides with the grid). grid_index, the last grid point at or before t, is advanced here
  /// only, so that a step cut short by an event does not advance it. (Advance's, and every lane's:
  /// simulation/lane_loop.h.)
  static double StepEnd(double grid_start_s, double step_s, long& grid_index, double t, double t_limit) {
    const double snap = kSnapFraction * step_s;
    auto grid_time = [&](long index) { return grid_start_s + static_cast<double>(index) * step_s; };
    while (grid_time(grid_index + 1) <= t + snap) ++grid_index;
    const double target = grid_time(grid_index + 1);
    return t_limit <= target + snap ? t_limit : target;
  }

  /// Cubic Hermite through (t0, x0, f0) and (t1, x1, f1) at t0 < tau < t1: 4th-order accurate
  /// locally (the step's ends are IntegrateWith's).
  static void Interpolate(double tau, double t0, const State& x0, const State& f0, double t1, const State& x1,
                          const State& f1, State& out) {
    const double h = t1 - t0;
    const double s = (tau - t0) / h;
    const double s2 = s * s;
    const double s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1;
    const double h10 = (s3 - 2 * s2 + s) * h;
    const double h01 = -2 * s3 + 3 * s2;
    const double h11 = (s3 - s2) * h;
    for (int i = 0; i < N; ++i) out[i] = h00 * x0[i] + h10 * f0[i] + h01 * x1[i] + h11 * f1[i];
  }

 private:
  double grid_start_s_;
  double step_s_;
  long grid_index_ = 0;
};

/// Dopri5's step-size control: the PI controller of Hairer's DOPRI5 (Hairer, Nørsett & Wanner,
/// Solving ODEs I, 2nd ed., §II.4, with Gustafsson's stabilisation, IV.2): after a step of error
/// err (odeint's max over the components of error / tolerance), the next is
///     h · clamp(0.9 · err^−(1/5 − 0.75β) · err_prev^β, 1/5, 10),  β = 0.04,
/// not larger than h right after a rejection; a rejected step is retried at
/// h / min(5, err^(1/5 − 0.75β) / 0.9). err_prev is the last accepted step's (at least 1e-4). Odeint's
/// own controller (0.9 · err^−1/5, and no growth while 0.5 ≤ err ≤ 1) rejects about 30 % of the
/// trials of a landing, whose steps are bounded by the stability of its fast poles rather than by
/// accuracy; this one about 20 % (docs/simulation.md). A model of odeint's StepAdjuster; the
/// controller's state (err_prev, the last trial's rejection) is one integration's.
class PiStepAdjuster : public boost::numeric::odeint::default_step_adjuster<double, double> {
 public:
  explicit PiStepAdjuster(double max_dt) : default_step_adjuster(max_dt) {}

  double decrease_step(double dt, double error, int /*error_order*/) {
    rejected_last_ = true;
    dt /= std::min(kLargestShrink, std::exp(kExponent * std::log(error)) / kSafety);
    return m_max_dt != 0.0 ? std::min(dt, m_max_dt) : dt;
  }

  double increase_step(double dt, double error, int /*stepper_order*/) {
    const double log_error = std::log(error);
    const double factor = std::exp(kExponent * log_error - kBeta * log_previous_error_) / kSafety;
    double next = dt / std::max(1.0 / kLargestGrowth, std::min(kLargestShrink, factor));
    if (rejected_last_) next = std::min(next, dt);
    rejected_last_ = false;
    log_previous_error_ = std::max(log_error, kLogSmallestError);
    return m_max_dt != 0.0 ? std::min(next, m_max_dt) : next;
  }

 private:
  static constexpr double kBeta = 0.04;
  static constexpr double kExponent = 0.2 - 0.75 * kBeta;
  static constexpr double kSafety = 0.9;
  static constexpr double kLargestShrink = 5.0;   ///< a step is at least a fifth of the previous
  static constexpr double kLargestGrowth = 10.0;  ///< and at most ten times it
  static constexpr double kLogSmallestError = -9.210340371976184;  ///< log(1e-4)
  double log_previous_error_ = 0.0;  ///< log err_prev: 0 (err_prev = 1) before the first step
  bool rejected_last_ = false;
};

/// Dormand–Prince 5(4) with Boost.Odeint's controlled stepper (FSAL form: 6 evaluations per trial)
/// and the method's own dense output (runge_kutta_dopri5::calc_state). The loop is ours rather than
/// odeint's dense_output_runge_kutta so that a step can be clipped to a breakpoint and a failure
/// becomes a status instead of an exception.
template <int N>
class Dopri5Method {
 public:
  using State = OdeState<N>;
  using Stepper = boost::numeric::odeint::runge_kutta_dopri5<State>;
  using ErrorChecker = boost::numeric::odeint::default_error_checker<double, typename Stepper::algebra_type,
                                                                     typename Stepper::operations_type>;
  using StepAdjuster = PiStepAdjuster;
  using Controlled = boost::numeric::odeint::controlled_runge_kutta<Stepper, ErrorChecker, StepAdjuster>;

  Dopri5Method(double /*start_time_s*/, const IntegratorOptions& options)
      : controlled_(ErrorChecker(options.absolute_tolerance, options.relative_tolerance, 1.0, 1.0),
                    StepAdjuster(options.max_step_s)),
        max_step_s_(options.max_step_s),
        trial_step_s_(options.max_step_s > 0 ? std::min(options.step_s, options.max_step_s)
                                             : options.step_s) {}

  template <class Rhs>
  StepOutcome Advance(Rhs& rhs, double t, const State& x, const State& f, double t_limit, double& t_new,
                      State& x_new, State& f_new, long& rejected) {
    for (int attempt = 0; attempt < kMaxConsecutiveRejections; ++attempt) {
      const double remaining = t_limit - t;
      double dt = trial_step_s_;
      bool clipped = false;
      // Land exactly on the limit when the trial step reaches it or would leave a sliver behind.
      if (dt >= remaining * (1.0 - kSnapFraction)) {
        dt = remaining;
        clipped = true;
      }
      if (dt < kMinRelativeStep * std::max(1.0, std::abs(t))) return StepOutcome::kUnderflow;
      double t_try = t;
      double dt_try = dt;
      const auto result = controlled_.try_step(rhs, x, f, t_try, x_new, f_new, dt_try);
      if (result == boost::numeric::odeint::success) {
        if (!AllFinite<N>(x_new) || !AllFinite<N>(f_new)) return StepOutcome::kNonFinite;
        t_new = clipped ? t_limit : t_try;
        // Odeint proposes the next step from this one's error; a clipped step must not shrink it.
        trial_step_s_ = clipped ? std::max(dt_try, trial_step_s_) : dt_try;
        if (max_step_s_ > 0) trial_step_s_ = std::min(trial_step_s_, max_step_s_);
        return StepOutcome::kAccepted;
      }
      ++rejected;
      trial_step_s_ = dt_try;
    }
    return StepOutcome::kUnderflow;
  }

  /// The 4th-order continuous extension of the last accepted step at t0 < tau < t1 (the step's ends
  /// are IntegrateWith's).
  void Interpolate(double tau, double t0, const State& x0, const State& f0, double t1, const State& x1,
                   const State& f1, State& out) const {
    controlled_.stepper().calc_state(tau, out, x0, f0, t0, x1, f1, t1);
  }

 private:
  Controlled controlled_;
  double max_step_s_;
  double trial_step_s_;
};

template <class Method, OdeProblem P>
IntegrationResult<P::kDimension> IntegrateWith(P& problem, const OdeState<P::kDimension>& initial_state,
                                               double start_time_s, double end_time_s,
                                               std::span<const double> breakpoints_s,
                                               const IntegratorOptions& options) {
  constexpr int N = P::kDimension;
  constexpr int E = P::kEventCount;
  using State = OdeState<N>;
  using Events = std::array<double, E>;

  IntegrationResult<N> result;
  const bool honour = options.honour_breakpoints;
  const std::size_t breakpoint_count = breakpoints_s.size();

  int segment = SegmentOf(breakpoints_s, start_time_s);
  std::size_t next_breakpoint = static_cast<std::size_t>(segment);
  int step_segment = segment;
  auto segment_at = [&](double tau) { return honour ? step_segment : SegmentOf(breakpoints_s, tau); };
  auto rhs = [&](const State& xs, State& dxdt, double ts) __attribute__((always_inline)) {
    ++result.rhs_calls;
    problem.Derivative(ts, xs, honour ? step_segment : SegmentOf(breakpoints_s, ts), dxdt);
  };

  Method method(start_time_s, options);
  double t = start_time_s;
  double t_new = t;
  // Double buffers: an accepted step swaps pointers instead of copying states (a copy right after
  // the element-wise writes stalls store forwarding on the step-to-step dependency).
  State buffer_x[2] = {initial_state, State{}};
  State buffer_f[2] = {State{}, State{}};
  State* x = &buffer_x[0];
  State* x_new = &buffer_x[1];
  State* f = &buffer_f[0];
  State* f_new = &buffer_f[1];

  // Output on the grid start + j·interval.
  const double output_interval = options.output_interval_s;
  const bool output = output_interval > 0.0;
  const double output_snap = kSnapFraction * output_interval;
  long next_output = 0;
  double last_output_time = -std::numeric_limits<double>::infinity();
  auto emit_outputs_through = [&](double t_cut, auto&& interpolate) {
    if (!output) return;
    for (;;) {
      const double t_out = start_time_s + static_cast<double>(next_output) * output_interval;
      if (t_out > t_cut + output_snap) break;
      const double tau = std::min(t_out, t_cut);
      State xo;
      interpolate(tau, xo);
      problem.OnOutput(tau, xo, segment_at(tau));
      last_output_time = tau;
      ++next_output;
    }
  };

  Events g_previous{};
  Events g_new{};
  problem.OnStep(t, *x, segment);
  if constexpr (E > 0) problem.EventValues(t, *x, segment, g_previous);
  emit_outputs_through(t, [&](double, State& out) { out = *x; });

  auto finish = [&](IntegrationStatus status) {
    result.status = status;
    result.end_time_s = t;
    result.final_state = *x;
    result.final_segment = segment;
    if (output && last_output_time < t) problem.OnOutput(t, *x, segment);
    return result;
  };

  rhs(*x, *f, t);
  if (!AllFinite<N>(*f) || !AllFinite<N>(*x)) return finish(IntegrationStatus::kNonFinite);

  // After a breakpoint or a restart: a new segment or phase starts at (t, x).
  auto restart_here = [&]() -> bool {
    if (honour) {
      while (next_breakpoint < breakpoint_count && breakpoints_s[next_breakpoint] <= t) {
        ++next_breakpoint;
        ++segment;
      }
    } else {
      segment = SegmentOf(breakpoints_s, t);
    }
    step_segment = segment;
    rhs(*x, *f, t);
    if constexpr (E > 0) problem.EventValues(t, *x, segment, g_previous);
    return AllFinite<N>(*f);
  };

  const std::atomic<bool>* cancel = options.cancel;
  StepCut<N> cut;
  while (t < end_time_s) {
    if (cancel != nullptr && cancel->load(std::memory_order_relaxed))
      return finish(IntegrationStatus::kCancelled);
    double t_limit = end_time_s;
    if (honour && next_breakpoint < breakpoint_count && breakpoints_s[next_breakpoint] < end_time_s) {
      t_limit = breakpoints_s[next_breakpoint];
    }
    step_segment = segment;
    const StepOutcome outcome =
        method.Advance(rhs, t, *x, *f, t_limit, t_new, *x_new, *f_new, result.rejected_steps);
    if (outcome == StepOutcome::kNonFinite) return finish(IntegrationStatus::kNonFinite);
    if (outcome == StepOutcome::kUnderflow) return finish(IntegrationStatus::kStepSizeUnderflow);
    ++result.accepted_steps;

    // The state at tau in [t, t_new]: exactly the step's end states at its ends, the method's
    // interpolant between them.
    auto interpolate = [&](double tau, State& out) {
      if (tau == t_new) {
        out = *x_new;
      } else if (tau == t) {
        out = *x;
      } else {
        method.Interpolate(tau, t, *x, *f, t_new, *x_new, *f_new, out);
      }
    };
    bool cut_here = false;
    if constexpr (E > 0) {
      problem.EventValues(t_new, *x_new, segment_at(t_new), g_new);
      cut_here = FireEvents<N>(problem, g_previous, g_new, t, t_new, options.event_time_tolerance_s,
                               interpolate, segment_at, emit_outputs_through, result.events_fired, cut);
    }
    if (!cut_here) {
      emit_outputs_through(t_new, interpolate);
      problem.OnStep(t_new, *x_new, segment_at(t_new));
      t = t_new;
      std::swap(x, x_new);
      std::swap(f, f_new);
      if constexpr (E > 0) g_previous = g_new;
      if (honour) {
        if (next_breakpoint < breakpoint_count && breakpoints_s[next_breakpoint] <= t) {
          if (!restart_here()) return finish(IntegrationStatus::kNonFinite);
        }
      } else {
        segment = SegmentOf(breakpoints_s, t);
      }
      continue;
    }
    // The step is cut at the event.
    emit_outputs_through(cut.t, interpolate);
    problem.OnStep(cut.t, cut.x, segment_at(cut.t));
    t = cut.t;
    *x = cut.x;
    if (cut.action == EventAction::kStop) {
      if (!honour) segment = SegmentOf(breakpoints_s, t);
      result.stopping_event = cut.event;
      return finish(IntegrationStatus::kStoppedByEvent);
    }
    if (!restart_here()) return finish(IntegrationStatus::kNonFinite);
  }
  return finish(IntegrationStatus::kReachedEnd);
}

}  // namespace gesweep::integrator_detail

namespace gesweep {

template <OdeProblem P>
IntegrationResult<P::kDimension> Integrate(P& problem, const OdeState<P::kDimension>& initial_state,
                                           double start_time_s, double end_time_s,
                                           std::span<const double> breakpoints_s,
                                           const IntegratorOptions& options) {
  GESWEEP_DEMAND(std::isfinite(start_time_s) && std::isfinite(end_time_s) && end_time_s > start_time_s);
  GESWEEP_DEMAND(options.step_s > 0.0 && options.output_interval_s >= 0.0 && options.max_step_s >= 0.0);
  GESWEEP_DEMAND(options.event_time_tolerance_s > 0.0);
  for (std::size_t i = 1; i < breakpoints_s.size(); ++i)
    GESWEEP_DEMAND(breakpoints_s[i] > breakpoints_s[i - 1]);
  if (options.kind == IntegratorKind::kRk4) {
    return integrator_detail::IntegrateWith<integrator_detail::Rk4Method<P::kDimension>>(
        problem, initial_state, start_time_s, end_time_s, breakpoints_s, options);
  }
  return integrator_detail::IntegrateWith<integrator_detail::Dopri5Method<P::kDimension>>(
      problem, initial_state, start_time_s, end_time_s, breakpoints_s, options);
}

}  // namespace gesweep
