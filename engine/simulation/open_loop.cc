#include "engine/simulation/open_loop.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include "engine/common/errors.h"
#include "engine/common/input_limits.h"
#include "engine/disturbance/disturbance_field.h"
#include "engine/disturbance/mean_wind.h"
#include "engine/simulation/derivative_kernel.h"
#include "engine/simulation/lane_loop.h"
#include "engine/simulation/open_loop_lanes.h"

namespace gesweep {

ElevatorSchedule MakeElevatorSchedule(const ElevatorInput& input) {
  const double a = input.amplitude_rad;
  const double t0 = input.start_s;
  const double d = input.duration_s;
  switch (input.kind) {
    case ElevatorInputKind::kNone:
      return {{}, {0.0}};
    case ElevatorInputKind::kPulse:
      return {{t0, t0 + d}, {0.0, a, 0.0}};
    case ElevatorInputKind::kStep:
      return {{t0}, {0.0, a}};
    case ElevatorInputKind::kDoublet:
      return {{t0, t0 + d, t0 + 2.0 * d}, {0.0, a, -a, 0.0}};
  }
  GESWEEP_UNREACHABLE();
}

namespace {

std::string Text(double value) { return ShortNumber(value); }

double TouchdownHeight(const LongitudinalModel& model, const OpenLoopConfig& config) {
  return config.touchdown_height_m.value_or(model.aircraft().wheel_contact_height_m);
}

double StallSpeed(const LongitudinalModel& model, const OpenLoopConfig& config) {
  return config.stall_speed_mps.value_or(model.aircraft().stall_speed_mps);
}

// Where ẋ comes from: three sources with one interface, so that each instantiation of the problem
// inlines its own.
struct FrozenSource {
  Equation1Entries entries;  // A and B at the start condition
  GESWEEP_ALWAYS_INLINE void Derivative(double /*h0*/, double u0, const double* x, double elevator_rad,
                                        double* dxdt) {
    Equation1Derivative(entries, u0, x, elevator_rad, dxdt);
  }
};

struct TableSource {
  const LinearDerivativeTable* table;
  int segment_hint;
  GESWEEP_ALWAYS_INLINE void Derivative(double h0, double u0, const double* x, double elevator_rad,
                                        double* dxdt) {
    table->Equation1(h0, u0, x, elevator_rad, dxdt, segment_hint);
  }
};

struct ModelSource {
  const LongitudinalModel* model;
  void Derivative(double h0, double u0, const double* x, double elevator_rad, double* dxdt) {
    const DimensionalDerivatives d = model->DerivativesAt(h0 + x[kDeltaH], u0 + x[kDeltaU]);
    Equation1Derivative(EntriesFromDerivatives(d, u0), u0, x, elevator_rad, dxdt);
  }
};

enum OpenLoopEvent : int { kTouchdownEvent = 0, kStallEvent = 1, kHeightMinimumEvent = 2 };

// What the two problems below share: the start condition, the event functions, the series they
// fill, and what they keep along the run (OnEvent, OnStep): the lowest height and its time, the
// largest |q|, and the event that stopped the run. The airplane's states are x[0 .. 5).
class OpenLoopRecorder {
 public:
  static constexpr int kEventCount = 3;

  template <class State>
  EventAction OnEvent(int event, double t, const State& x, int /*segment*/) {
    if (event == kHeightMinimumEvent) {
      NoteHeight(t, x);
      return EventAction::kContinue;
    }
    stopping_event_ = event;
    return EventAction::kStop;
  }

  template <class State>
  void OnStep(double t, const State& x, int /*segment*/) {
    NoteHeight(t, x);
    max_abs_pitch_rate_radps_ = std::max(max_abs_pitch_rate_radps_, std::abs(x[kPitchRate]));
  }

  double min_height_m() const { return min_height_m_; }
  double min_height_time_s() const { return min_height_time_s_; }
  double max_abs_pitch_rate_radps() const { return max_abs_pitch_rate_radps_; }
  int stopping_event() const { return stopping_event_; }

 protected:
  OpenLoopRecorder(double start_height_m, double reference_speed_mps, double touchdown_height_m,
                   double stall_speed_mps, OpenLoopSeries* series)
      : start_height_m_(start_height_m),
        u0_(reference_speed_mps),
        touchdown_height_m_(touchdown_height_m),
        stall_speed_mps_(stall_speed_mps),
        series_(series) {}

  // The event functions, given the speed that stalls (u0 + Δu in still air, the airspeed in wind).
  template <class State>
  void EventValuesAt(const State& x, double stalling_speed_mps, std::array<double, kEventCount>& g) const {
    g[kTouchdownEvent] = start_height_m_ + x[kDeltaH] - touchdown_height_m_;
    g[kStallEvent] = stalling_speed_mps - stall_speed_mps_;
    // Ḣ = −Δw + u0·Δθ (row ΔH of Eq. 1); −Ḣ falls through zero at a local minimum of H.
    g[kHeightMinimumEvent] = x[kDeltaW] - u0_ * x[kDeltaTheta];
  }

  // Appends the airplane's part of a sample to the series (series_ not null).
  template <class State>
  void AppendSample(double t, const State& x, double elevator_rad) {
    series_->time_s.push_back(t);
    series_->delta_speed_mps.push_back(x[kDeltaU]);
    series_->delta_normal_velocity_mps.push_back(x[kDeltaW]);
    series_->pitch_rate_radps.push_back(x[kPitchRate]);
    series_->delta_pitch_rad.push_back(x[kDeltaTheta]);
    series_->delta_height_m.push_back(x[kDeltaH]);
    series_->height_m.push_back(start_height_m_ + x[kDeltaH]);
    series_->speed_mps.push_back(u0_ + x[kDeltaU]);
    series_->elevator_rad.push_back(elevator_rad);
  }

  double start_height_m_;
  double u0_;
  double touchdown_height_m_;
  double stall_speed_mps_;
  OpenLoopSeries* series_;

 private:
  template <class State>
  void NoteHeight(double t, const State& x) {
    const double height_m = start_height_m_ + x[kDeltaH];
    if (height_m < min_height_m_) {
      min_height_m_ = height_m;
      min_height_time_s_ = t;
    }
  }

  double min_height_m_ = std::numeric_limits<double>::infinity();
  double min_height_time_s_ = 0;
  double max_abs_pitch_rate_radps_ = 0;
  int stopping_event_ = -1;
};

// Eq. (1) as an OdeProblem (integrator.h).
template <class Source>
class OpenLoopProblem : public OpenLoopRecorder {
 public:
  static constexpr int kDimension = 5;
  using State = OdeState<kDimension>;

  OpenLoopProblem(Source source, double start_height_m, double reference_speed_mps,
                  const std::vector<double>& elevator_by_segment, double touchdown_height_m,
                  double stall_speed_mps, OpenLoopSeries* series)
      : OpenLoopRecorder(start_height_m, reference_speed_mps, touchdown_height_m, stall_speed_mps, series),
        source_(source),
        elevator_by_segment_(elevator_by_segment.data()) {}

  GESWEEP_ALWAYS_INLINE void Derivative(double /*t*/, const State& x, int segment, State& dxdt) {
    source_.Derivative(start_height_m_, u0_, x.data(), elevator_by_segment_[segment], dxdt.data());
  }

  void EventValues(double /*t*/, const State& x, int /*segment*/, std::array<double, kEventCount>& g) const {
    EventValuesAt(x, u0_ + x[kDeltaU], g);
  }

  void OnOutput(double t, const State& x, int segment) {
    if (series_ != nullptr) AppendSample(t, x, elevator_by_segment_[segment]);
  }

 private:
  Source source_;
  const double* elevator_by_segment_;
};

void Reserve(OpenLoopSeries& series, std::size_t count) {
  for (auto* column : {&series.time_s, &series.delta_speed_mps, &series.delta_normal_velocity_mps,
                       &series.pitch_rate_radps, &series.delta_pitch_rad, &series.delta_height_m,
                       &series.height_m, &series.speed_mps, &series.elevator_rad}) {
    column->reserve(count);
  }
}

// The summary of a run from the integrator's result and the problem's records.
template <int N>
void FillSummary(OpenLoopSummary& summary, const IntegrationResult<N>& run, const OpenLoopRecorder& problem,
                 const OpenLoopConfig& config) {
  summary.end_time_s = run.end_time_s;
  for (int i = 0; i < 5; ++i) summary.final_state[i] = run.final_state[static_cast<std::size_t>(i)];
  summary.final_height_m = config.start_height_m + run.final_state[kDeltaH];
  summary.final_speed_mps = config.reference_speed_mps + run.final_state[kDeltaU];
  summary.min_height_m = problem.min_height_m();
  summary.min_height_time_s = problem.min_height_time_s();
  summary.max_abs_pitch_rate_radps = problem.max_abs_pitch_rate_radps();
  summary.steps = run.accepted_steps;
  summary.rejected_steps = run.rejected_steps;
  summary.rhs_calls = run.rhs_calls;
  switch (run.status) {
    case IntegrationStatus::kReachedEnd:
      summary.end_event = OpenLoopEndEvent::kTimeLimit;
      break;
    case IntegrationStatus::kStoppedByEvent:
      summary.end_event =
          run.stopping_event == kTouchdownEvent ? OpenLoopEndEvent::kTouchdown : OpenLoopEndEvent::kStall;
      break;
    case IntegrationStatus::kNonFinite:
      summary.end_event = OpenLoopEndEvent::kDiverged;
      summary.message = "the state became non-finite in the step after t = " + Text(run.end_time_s) + " s";
      break;
    case IntegrationStatus::kStepSizeUnderflow:
      summary.end_event = OpenLoopEndEvent::kDiverged;
      summary.message = "the adaptive step fell below its floor at t = " + Text(run.end_time_s) + " s";
      break;
    case IntegrationStatus::kCancelled:
      summary.cancelled = true;
      summary.message = "cancelled at t = " + Text(run.end_time_s) + " s";
      break;
  }
}

template <class Source>
OpenLoopResult Run(Source source, const LongitudinalModel& model, const OpenLoopConfig& config,
                   const std::atomic<bool>* cancel) {
  OpenLoopResult result;
  const ElevatorSchedule schedule = MakeElevatorSchedule(config.elevator);
  IntegratorOptions options = config.integrator;
  options.output_interval_s = config.series_interval_s;
  options.cancel = cancel;
  OpenLoopSeries* series = nullptr;
  if (config.series_interval_s > 0.0) {
    // Every sample and the end point, so that push_back never reallocates during the run.
    Reserve(result.series, static_cast<std::size_t>(config.duration_s / config.series_interval_s) + 3);
    series = &result.series;
  }
  OpenLoopProblem<Source> problem(source, config.start_height_m, config.reference_speed_mps,
                                  schedule.elevator_rad, TouchdownHeight(model, config),
                                  StallSpeed(model, config), series);
  const InitialOffsets& o = config.initial_offsets;
  const OdeState<5> x0 = {o.delta_speed_mps, o.delta_normal_velocity_mps, o.pitch_rate_radps,
                          o.delta_pitch_rad, o.delta_height_m};
  const IntegrationResult<5> run =
      Integrate(problem, x0, 0.0, config.duration_s, schedule.breakpoints_s, options);
  FillSummary(result.summary, run, problem, config);
  return result;
}

// ---------------------------------------------------------------- with a disturbance (model.md §9)

// The derivatives at (H, airspeed): the same three sources as above, as DimensionalDerivatives for
// the air-relative Eq. (1) (AirRelativeDerivative).
struct FrozenDerivatives {
  DimensionalDerivatives d;
  const DimensionalDerivatives& At(double /*height_m*/, double /*airspeed_mps*/) const { return d; }
};
struct TableDerivatives {
  const LinearDerivativeTable* table;
  int segment_hint;
  DimensionalDerivatives At(double height_m, double airspeed_mps) {
    return table->DerivativesAt(height_m, airspeed_mps, segment_hint);
  }
};
struct ModelDerivatives {
  const LongitudinalModel* model;
  DimensionalDerivatives At(double height_m, double airspeed_mps) const {
    return model->DerivativesAt(height_m, airspeed_mps);
  }
};

// The open-loop airplane and the field's states: x = [Δu, Δw, q, Δθ, ΔH, field states].
template <class Derivatives>
class DisturbedOpenLoopProblem : public OpenLoopRecorder {
 public:
  static constexpr int kDimension = 5 + DisturbanceField::kStateCount;
  using State = OdeState<kDimension>;

  DisturbedOpenLoopProblem(Derivatives derivatives, const DisturbanceField* field,
                           const std::vector<DisturbanceField::Segment>* field_segments,
                           const std::vector<double>* elevator_by_segment, double start_height_m,
                           double reference_speed_mps, double touchdown_height_m, double stall_speed_mps,
                           OpenLoopSeries* series)
      : OpenLoopRecorder(start_height_m, reference_speed_mps, touchdown_height_m, stall_speed_mps, series),
        derivatives_(derivatives),
        field_(field),
        field_segments_(field_segments),
        elevator_by_segment_(elevator_by_segment) {}

  void Derivative(double /*t*/, const State& x, int segment, State& dxdt) {
    DisturbanceField::State field_dxdt;
    const AirMotion air = Air(x, segment, field_dxdt);
    const double height_m = start_height_m_ + x[kDeltaH];
    const Vector5d x5(x[0], x[1], x[2], x[3], x[4]);
    const Vector5d d5 =
        AirRelativeDerivative(derivatives_.At(height_m, air.airspeed_mps), u0_, x5,
                              (*elevator_by_segment_)[static_cast<std::size_t>(segment)],
                              AirVelocity{air.u_g_mps, air.w_g_mps, air.q_g_radps, air.w_g_dot_mps2});
    for (int i = 0; i < 5; ++i) dxdt[static_cast<std::size_t>(i)] = d5[i];
    std::copy(field_dxdt.begin(), field_dxdt.end(), dxdt.begin() + 5);
  }

  void EventValues(double /*t*/, const State& x, int segment, std::array<double, kEventCount>& g) const {
    DisturbanceField::State unused;
    EventValuesAt(x, Air(x, segment, unused).airspeed_mps, g);  // the airspeed stalls
  }

  void OnOutput(double t, const State& x, int segment) {
    if (series_ == nullptr) return;
    DisturbanceField::State unused;
    const AirMotion air = Air(x, segment, unused);
    AppendSample(t, x, (*elevator_by_segment_)[static_cast<std::size_t>(segment)]);
    series_->u_g_mps.push_back(air.u_g_mps);
    series_->w_g_mps.push_back(air.w_g_mps);
    if (field_->options().pitch_rate_gust) series_->q_g_radps.push_back(air.q_g_radps);
  }

 private:
  AirMotion Air(const State& x, int segment, DisturbanceField::State& field_dxdt) const {
    DisturbanceField::State xf;
    std::copy(x.begin() + 5, x.end(), xf.begin());
    return field_->Evaluate((*field_segments_)[static_cast<std::size_t>(segment)],
                            start_height_m_ + x[kDeltaH], u0_ + x[kDeltaU], xf, field_dxdt);
  }

  Derivatives derivatives_;
  const DisturbanceField* field_;
  const std::vector<DisturbanceField::Segment>* field_segments_;
  const std::vector<double>* elevator_by_segment_;
};

// The options the field is built from: the span of the pitch-rate gust is the aircraft's.
DisturbanceOptions FieldOptions(const LongitudinalModel& model, const OpenLoopConfig& config) {
  DisturbanceOptions options = config.disturbance;
  options.wing_span_m = model.aircraft().wingspan_m;
  return options;
}

template <class Derivatives>
OpenLoopResult RunDisturbed(Derivatives derivatives, const DisturbanceField& field,
                            const LongitudinalModel& model, const OpenLoopConfig& config,
                            const std::atomic<bool>* cancel) {
  OpenLoopResult result;
  const ElevatorSchedule schedule = MakeElevatorSchedule(config.elevator);
  // The input's jumps and the field's (noise samples, gust entry) in one ascending list; the
  // elevator of each merged segment is the schedule's value at the segment's left end.
  // SIGINT/SIGTERM are read while the tables are built, too (a turbulent run's table holds up to
  // kMaximumNoiseSamplesPerRun instants): a stop empties them and Integrate stops before its first step.
  std::vector<double> breakpoints = field.Breakpoints(0.0, config.duration_s, cancel);
  breakpoints.insert(breakpoints.end(), schedule.breakpoints_s.begin(), schedule.breakpoints_s.end());
  std::sort(breakpoints.begin(), breakpoints.end());
  breakpoints.erase(std::unique(breakpoints.begin(), breakpoints.end()), breakpoints.end());
  if (cancel != nullptr && cancel->load()) breakpoints.clear();
  const std::vector<DisturbanceField::Segment> field_segments = field.SegmentTable(breakpoints, 0.0, cancel);
  if (cancel != nullptr && cancel->load()) breakpoints.clear();
  std::vector<double> elevator(breakpoints.size() + 1);
  for (std::size_t s = 0; s < elevator.size(); ++s) {
    const double left_s = s == 0 ? 0.0 : breakpoints[s - 1];
    const auto jumps =
        std::upper_bound(schedule.breakpoints_s.begin(), schedule.breakpoints_s.end(), left_s) -
        schedule.breakpoints_s.begin();
    elevator[s] = schedule.elevator_rad[static_cast<std::size_t>(jumps)];
  }
  IntegratorOptions options = config.integrator;
  options.output_interval_s = config.series_interval_s;
  options.cancel = cancel;
  OpenLoopSeries* series = nullptr;
  if (config.series_interval_s > 0.0) {
    const auto count = static_cast<std::size_t>(config.duration_s / config.series_interval_s) + 3;
    Reserve(result.series, count);
    result.series.u_g_mps.reserve(count);
    result.series.w_g_mps.reserve(count);
    if (field.options().pitch_rate_gust) result.series.q_g_radps.reserve(count);
    series = &result.series;
  }
  DisturbedOpenLoopProblem<Derivatives> problem(
      derivatives, &field, &field_segments, &elevator, config.start_height_m, config.reference_speed_mps,
      TouchdownHeight(model, config), StallSpeed(model, config), series);
  const InitialOffsets& o = config.initial_offsets;
  OdeState<DisturbedOpenLoopProblem<Derivatives>::kDimension> x0{};
  // Started in the mean wind's equilibrium: airspeed u0 + the offset (docs/model.md §9).
  const double start_height_m = config.start_height_m + o.delta_height_m;
  x0[kDeltaU] = MeanWindAt(config.disturbance.wind_20ft_mps, start_height_m, config.disturbance.wind_shear) +
                o.delta_speed_mps;
  x0[kDeltaW] = o.delta_normal_velocity_mps;
  x0[kPitchRate] = o.pitch_rate_radps;
  x0[kDeltaTheta] = o.delta_pitch_rad;
  x0[kDeltaH] = o.delta_height_m;
  const DisturbanceField::State field_start = field.InitialState();
  std::copy(field_start.begin(), field_start.end(), x0.begin() + 5);
  const auto run = Integrate(problem, x0, 0.0, config.duration_s, breakpoints, options);
  FillSummary(result.summary, run, problem, config);
  return result;
}

// ---------------------------------------------------------------- many runs in lockstep (SIMD lanes)

// A run flown in a lane: the scalar problem (its recorder: events, lowest height, largest |q|), its
// elevator schedule and step, and IntegrateWith's bookkeeping (LaneRunBase; no output).
struct LaneRun : lanes::LaneRunBase<OpenLoopProblem<TableSource>, OpenLoopConfig> {
  ElevatorSchedule schedule;
  std::optional<Problem> problem;
  double step_s = 0;
};

// W lanes: the runs' states side by side (open_loop_lanes.h), component c of lane i at [c][i]. The
// per-lane decisions are here, in scalar code; the RK4 stages of all lanes are the kernel of the
// batch's instruction set.
template <int W>
class OpenLoopLanes
    : public lanes::LaneFleet<OpenLoopLanes<W>, W, LaneRun, OpenLoopResult, lanes::StepArrays<W>> {
  using Fleet = lanes::LaneFleet<OpenLoopLanes<W>, W, LaneRun, OpenLoopResult, lanes::StepArrays<W>>;
  friend Fleet;
  using Fleet::a_;
  using Fleet::active_;
  using Fleet::Finish;
  using Fleet::Interpolate;
  using Fleet::Lane;
  using Fleet::lane_;
  using Fleet::SetLane;
  using typename Fleet::State;
  using typename Fleet::Step;

 public:
  OpenLoopLanes(std::span<const OpenLoopBatchRun> runs, std::span<const std::size_t> order,
                const std::vector<const LinearDerivativeTable*>& tables, std::vector<OpenLoopResult>& results,
                LanesIsa isa, const std::atomic<bool>* cancel)
      : Fleet(order, results, cancel),
        runs_(runs),
        run_tables_(tables),
        kernels_(lanes::KernelsFor<lanes::OpenLoopKernels, W>(isa)) {
    for (int i = 0; i < W; ++i) a_.table[i] = tables[order.front()];  // idle lanes fly zeros on a valid table
  }

 private:
  // The derivative of lane i alone, through its problem (what Integrate's rhs calls).
  void LaneDerivative(int i, const State& x, State& dxdt) {
    LaneRun& lane = lane_[i];
    ++lane.result.rhs_calls;
    lane.problem->Derivative(lane.t, x, lane.segment, dxdt);
  }

  // For LaneFleet: starts `run` in lane i. IntegrateWith's start: the initial step record and event
  // values, the derivative at t = 0.
  bool Start(int i, std::size_t run) {
    const OpenLoopBatchRun& r = runs_[run];
    LaneRun& lane = lane_[i];
    lane = LaneRun{};
    lane.run = run;
    lane.config = &r.config;
    lane.schedule = MakeElevatorSchedule(r.config.elevator);
    const LinearDerivativeTable* table = run_tables_[run];
    lane.problem.emplace(TableSource{table, table->SegmentOf(r.config.start_height_m)},
                         r.config.start_height_m, r.config.reference_speed_mps, lane.schedule.elevator_rad,
                         TouchdownHeight(*r.model, r.config), StallSpeed(*r.model, r.config), nullptr);
    lane.end_s = r.config.duration_s;
    lane.step_s = r.config.integrator.step_s;
    lane.segment = integrator_detail::SegmentOf(lane.schedule.breakpoints_s, 0.0);
    lane.next_breakpoint = static_cast<std::size_t>(lane.segment);
    a_.table[i] = table;
    a_.hint[i] = table->SegmentOf(r.config.start_height_m);
    a_.h0[i] = r.config.start_height_m;
    a_.u0[i] = r.config.reference_speed_mps;
    const InitialOffsets& o = r.config.initial_offsets;
    const State x0 = {o.delta_speed_mps, o.delta_normal_velocity_mps, o.pitch_rate_radps, o.delta_pitch_rad,
                      o.delta_height_m};
    lane.problem->OnStep(0.0, x0, lane.segment);
    lane.problem->EventValues(0.0, x0, lane.segment, lane.g_previous);
    State f0;
    LaneDerivative(i, x0, f0);
    SetLane(a_.x, i, x0);
    SetLane(a_.f, i, f0);
    return true;
  }

  // For LaneFleet: an idle lane flies zeros.
  void Idle(int i) {
    for (int c = 0; c < 5; ++c) a_.x[c][i] = a_.f[c][i] = 0.0;
    a_.t[i] = a_.t_to[i] = a_.elevator[i] = 0.0;
  }

  // For LaneFleet: Rk4Method::Advance up to the stages (the step's length and its fractions are the
  // kernel's).
  void PrepareStep(int i) {
    LaneRun& lane = lane_[i];
    a_.t[i] = lane.t;
    a_.t_to[i] = this->StepEnd(i, lane.schedule.breakpoints_s, lane.step_s);
    a_.elevator[i] = lane.schedule.elevator_rad[static_cast<std::size_t>(lane.segment)];
  }

  // For LaneFleet: one step of every lane at once.
  void StepAll() {
    kernels_.rk4_stages(a_);
    for (int i = 0; i < W; ++i) {
      if (active_[i]) CompleteStep(i);
    }
  }

  // IntegrateWith's step after Advance for lane i: the finiteness check, the events located in the
  // step (StopAtEvent), the step's record and a breakpoint's restart (AcceptStep). The step's four
  // states are taken out of the arrays only when an event may have fired (a value crossed from
  // positive to at most zero: LocateEvents' test); otherwise FireEvents would find none, and the
  // lane's values are read and written in place.
  void CompleteStep(int i) {
    LaneRun& lane = lane_[i];
    lane.result.rhs_calls += 4;
    const State x_new = Lane(a_.x_new, i);
    if (!integrator_detail::AllFinite<5>(x_new)) return Finish(i, IntegrationStatus::kNonFinite);
    ++lane.result.accepted_steps;
    LaneRun::Events g_new;
    lane.problem->EventValues(a_.t_to[i], x_new, lane.segment, g_new);
    if (integrator_detail::AnyEventCrossing(lane.g_previous, g_new) && StopAtEvent(i, g_new)) return;
    AcceptStep(i, x_new, g_new);
  }

  // The events fired in lane i's step, in time order: one that records is recorded; one that stops
  // ends the run at its time (true).
  bool StopAtEvent(int i, const LaneRun::Events& g_new) {
    LaneRun& lane = lane_[i];
    LaneRun::Problem& problem = *lane.problem;
    const int segment = lane.segment;
    const Step step{lane.t, a_.t_to[i], Lane(a_.x, i), Lane(a_.f, i), Lane(a_.x_new, i), Lane(a_.f_new, i)};
    integrator_detail::StepCut<5> cut;
    if (!integrator_detail::FireEvents<5>(
            problem, lane.g_previous, g_new, step.t, step.t_new,
            lane.config->integrator.event_time_tolerance_s,
            [&](double tau, State& out) { Interpolate(step, tau, out); },
            [segment](double) { return segment; }, [](double, auto&&) {}, lane.result.events_fired, cut)) {
      return false;
    }
    GESWEEP_DEMAND(cut.action == EventAction::kStop);  // the open loop only records or stops
    problem.OnStep(cut.t, cut.x, segment);
    lane.t = cut.t;
    SetLane(a_.x, i, cut.x);
    lane.result.stopping_event = cut.event;
    Finish(i, IntegrationStatus::kStoppedByEvent);
    return true;
  }

  // Lane i's step recorded and taken (x_new and f_new become the lane's x and f); at a breakpoint,
  // the next segment's start.
  void AcceptStep(int i, const State& x_new, const LaneRun::Events& g_new) {
    LaneRun& lane = lane_[i];
    lane.problem->OnStep(a_.t_to[i], x_new, lane.segment);
    lane.t = a_.t_to[i];
    for (int c = 0; c < 5; ++c) {
      a_.x[c][i] = x_new[c];
      a_.f[c][i] = a_.f_new[c][i];
    }
    lane.g_previous = g_new;
    const std::vector<double>& breakpoints = lane.schedule.breakpoints_s;
    if (lane.next_breakpoint < breakpoints.size() && breakpoints[lane.next_breakpoint] <= lane.t) {
      while (lane.next_breakpoint < breakpoints.size() && breakpoints[lane.next_breakpoint] <= lane.t) {
        ++lane.next_breakpoint;
        ++lane.segment;
      }
      State f_restart;
      LaneDerivative(i, x_new, f_restart);
      SetLane(a_.f, i, f_restart);
      lane.problem->EventValues(lane.t, x_new, lane.segment, lane.g_previous);
      if (!integrator_detail::AllFinite<5>(f_restart)) return Finish(i, IntegrationStatus::kNonFinite);
    }
    if (!(lane.t < lane.end_s)) Finish(i, IntegrationStatus::kReachedEnd);
  }

  // For LaneFleet: the run's summary.
  void Record(int i) {
    LaneRun& lane = lane_[i];
    FillSummary(this->results_[lane.run].summary, lane.result, *lane.problem, *lane.config);
  }

  std::span<const OpenLoopBatchRun> runs_;
  const std::vector<const LinearDerivativeTable*>& run_tables_;
  lanes::RkKernels<lanes::StepArrays<W>> kernels_;
};

template <int W>
void FlyInLanes(std::span<const OpenLoopBatchRun> runs, std::span<const std::size_t> order,
                const std::vector<const LinearDerivativeTable*>& tables, std::vector<OpenLoopResult>& results,
                LanesIsa isa, const std::atomic<bool>* cancel) {
  // On the heap: the lanes hold W runs' problems and arrays.
  auto lanes = std::make_unique<OpenLoopLanes<W>>(runs, order, tables, results, isa, cancel);
  lanes->FlyAll();
}

}  // namespace

void ValidateOpenLoopConfig(const LongitudinalModel& model, const OpenLoopConfig& config,
                            const std::string& source) {
  auto require = [&source](bool ok, std::string_view key, double value, const char* expected) {
    if (!ok) throw InputError(source, std::string(key), Text(value), expected);
  };
  const double touchdown_m = TouchdownHeight(model, config);
  const double stall_mps = StallSpeed(model, config);
  require(std::isfinite(touchdown_m) && touchdown_m >= 0.0, "touchdown_height_m", touchdown_m,
          "expected a finite height >= 0 m");
  require(std::isfinite(stall_mps) && stall_mps >= 0.0, "stall_speed_mps", stall_mps,
          "expected a finite speed >= 0 m/s");
  // Every described number against its range, named by its key (OpenLoopConfig::Describe).
  CheckFieldRanges(config, source);
  const double start_m = config.start_height_m + config.initial_offsets.delta_height_m;
  if (!(start_m > touchdown_m)) {  // the message is built only on failure: this runs once per sweep run
    throw InputError(source, std::string(KeyOf(config, &config.start_height_m)), Text(start_m),
                     "expected a start height above the touchdown (wheel-contact) height " +
                         Text(touchdown_m) + " m; a run cannot start on or below the ground");
  }
  const double start_speed = config.reference_speed_mps + config.initial_offsets.delta_speed_mps;
  if (!(start_speed > stall_mps)) {
    throw InputError(source, std::string(KeyOf(config, &config.reference_speed_mps)), Text(start_speed),
                     "expected a start speed above the stall speed " + Text(stall_mps) + " m/s");
  }
  require(std::isfinite(config.series_interval_s) && config.series_interval_s >= 0.0, "series_interval_s",
          config.series_interval_s, "expected a finite interval >= 0 s (0: summary only)");
  if (config.series_interval_s > 0.0) {
    CheckInputLimit("output_dt_s", config.series_interval_s, source, "series_interval_s");
    require(config.duration_s / config.series_interval_s <= kMaximumStepsPerRun, "series_interval_s",
            config.series_interval_s, "expected at most 1e8 samples per run");
  }
  const ElevatorInput& input = config.elevator;
  if (input.kind == ElevatorInputKind::kPulse || input.kind == ElevatorInputKind::kDoublet) {
    if (!(input.duration_s > 0.0)) {
      throw InputError(source, std::string(KeyOf(config, &input.duration_s)), Text(input.duration_s),
                       "expected a finite duration > 0 s");
    }
  }
  ValidateIntegratorOptions(config.integrator, source);
  ValidateDisturbanceOptions(FieldOptions(model, config), source);
  CheckOpenLoopWork(config, source);
  const IntegratorOptions& integrator = config.integrator;
  // An adaptive run without a largest step has no step count known before it runs; its steps are
  // bounded by the cancellation flag (SIGINT/SIGTERM, the dry run's deadline).
  const bool rk4 = integrator.kind == IntegratorKind::kRk4;
  const double& step_s = rk4 ? integrator.step_s : integrator.max_step_s;
  if (step_s > 0.0 &&
      config.duration_s / step_s > kMaximumStepsPerRun) {  // the keys are looked up on failure only
    CheckStepCount(config.duration_s, step_s, source, std::string(KeyOf(config, &config.duration_s)),
                   std::string(KeyOf(config, &step_s)));
  }
}

void CheckOpenLoopWork(const OpenLoopConfig& config, const std::string& source) {
  const double interval_s = config.disturbance.turbulence_sample_interval_s;
  const bool turbulent = config.disturbance.turbulence == TurbulenceModel::kDryden;
  const double noise_samples = turbulent ? NoiseSampleCount(config.duration_s, interval_s) : 0.0;
  if (noise_samples > kMaximumNoiseSamplesPerRun) {
    CheckNoiseSamples(config.duration_s, interval_s, source, std::string(KeyOf(config, &config.duration_s)),
                      std::string(KeyOf(config, &config.disturbance.turbulence_sample_interval_s)));
  }
  // The series RunDisturbed and RunStillAir reserve: 9 state columns, u_g and w_g, q_g.
  const double series_samples = config.series_interval_s > 0.0 && std::isfinite(config.duration_s)
                                    ? std::floor(config.duration_s / config.series_interval_s) + 3
                                    : 0.0;
  constexpr double kSeriesBytesPerSample = 12 * sizeof(double);
  const double bytes = noise_samples * kNoiseBytesPerSample + series_samples * kSeriesBytesPerSample;
  if (bytes > kMaximumRunMemoryBytes) {
    std::string breakdown =
        ShortNumber(series_samples) + " series samples x " + ShortNumber(kSeriesBytesPerSample) + " bytes";
    if (noise_samples > 0)
      breakdown += " + " + ShortNumber(noise_samples) + " noise samples x " +
                   ShortNumber(kNoiseBytesPerSample) + " bytes";
    CheckRunMemory(bytes, breakdown, source, "series_interval_s", ShortNumber(config.series_interval_s));
  }
}

OpenLoopResult SimulateOpenLoop(const LongitudinalModel& model, const OpenLoopConfig& config,
                                const std::atomic<bool>* cancel) {
  ValidateOpenLoopConfig(model, config, "open-loop config");
  const double h0 = config.start_height_m;
  const double u0 = config.reference_speed_mps;
  const DisturbanceField field(FieldOptions(model, config), config.seed, config.run_index);
  if (field.active()) {
    if (config.freeze_derivatives) {
      // A and B at the start condition: H0 + ΔH(0) and the airspeed u0 + Δu(0) offset.
      const double height_m = h0 + config.initial_offsets.delta_height_m;
      const double speed_mps = u0 + config.initial_offsets.delta_speed_mps;
      return RunDisturbed(FrozenDerivatives{model.DerivativesAt(height_m, speed_mps)}, field, model, config,
                          cancel);
    }
    if (config.generic_derivative_path || model.options().interpolation != Interpolation::kLinear) {
      return RunDisturbed(ModelDerivatives{&model}, field, model, config, cancel);
    }
    const LinearDerivativeTable table(model);
    return RunDisturbed(TableDerivatives{&table, table.SegmentOf(h0)}, field, model, config, cancel);
  }
  if (config.freeze_derivatives) {
    // A and B at the start condition H0 + ΔH(0), u0 + Δu(0), through the generic path.
    const double height_m = h0 + config.initial_offsets.delta_height_m;
    const double speed_mps = u0 + config.initial_offsets.delta_speed_mps;
    return Run(FrozenSource{EntriesFromDerivatives(model.DerivativesAt(height_m, speed_mps), u0)}, model,
               config, cancel);
  }
  if (config.generic_derivative_path || model.options().interpolation != Interpolation::kLinear) {
    return Run(ModelSource{&model}, model, config, cancel);
  }
  const LinearDerivativeTable table(model);
  return Run(TableSource{&table, table.SegmentOf(h0)}, model, config, cancel);
}

bool OpenLoopRunUsesLanes(const LongitudinalModel& model, const OpenLoopConfig& config) {
  if (config.integrator.kind != IntegratorKind::kRk4 || !config.integrator.honour_breakpoints) return false;
  if (config.freeze_derivatives || config.generic_derivative_path) return false;
  if (model.options().interpolation != Interpolation::kLinear) return false;
  if (config.series_interval_s > 0.0) return false;
  return !DisturbanceField(FieldOptions(model, config), config.seed, config.run_index).active();
}

std::vector<OpenLoopResult> SimulateOpenLoopBatch(std::span<const OpenLoopBatchRun> runs, int width,
                                                  const std::atomic<bool>* cancel,
                                                  std::optional<LanesIsa> isa) {
  GESWEEP_DEMAND(std::find(std::begin(kOpenLoopBatchWidths), std::end(kOpenLoopBatchWidths), width) !=
                 std::end(kOpenLoopBatchWidths));
  GESWEEP_DEMAND(!isa || LanesIsaSupported(*isa));
  const LanesIsa lanes_isa = isa ? *isa : ChooseLanesIsa(width);
  for (const OpenLoopBatchRun& run : runs) {
    GESWEEP_DEMAND(run.model != nullptr);
    ValidateOpenLoopConfig(*run.model, run.config, "open-loop config");
  }
  std::vector<OpenLoopResult> results(runs.size());
  // One table per model, built as SimulateOpenLoop builds it (its values depend on the model only).
  std::vector<std::unique_ptr<LinearDerivativeTable>> owned;
  std::vector<const LongitudinalModel*> owners;
  std::vector<const LinearDerivativeTable*> tables(runs.size(), nullptr);
  std::vector<std::size_t> in_lanes;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const LongitudinalModel& model = *runs[i].model;
    if (!OpenLoopRunUsesLanes(model, runs[i].config)) {
      results[i] = SimulateOpenLoop(model, runs[i].config, cancel);
      continue;
    }
    const auto known = std::find(owners.begin(), owners.end(), &model);
    if (known == owners.end()) {
      owned.push_back(std::make_unique<LinearDerivativeTable>(model));
      owners.push_back(&model);
      tables[i] = owned.back().get();
    } else {
      tables[i] = owned[static_cast<std::size_t>(known - owners.begin())].get();
    }
    in_lanes.push_back(i);
  }
  if (in_lanes.empty()) return results;
  switch (width) {
    case 1:
      FlyInLanes<1>(runs, in_lanes, tables, results, lanes_isa, cancel);
      break;
    case 2:
      FlyInLanes<2>(runs, in_lanes, tables, results, lanes_isa, cancel);
      break;
    case 4:
      FlyInLanes<4>(runs, in_lanes, tables, results, lanes_isa, cancel);
      break;
    default:
      FlyInLanes<8>(runs, in_lanes, tables, results, lanes_isa, cancel);
      break;
  }
  return results;
}

}  // namespace gesweep
