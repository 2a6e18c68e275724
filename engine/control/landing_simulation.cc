#include "engine/control/landing_simulation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>

#include "engine/common/errors.h"
#include "engine/common/units.h"
#include "engine/control/landing_lanes.h"
#include "engine/disturbance/disturbance_field.h"
#include "engine/disturbance/mean_wind.h"
#include "engine/simulation/derivative_kernel.h"
#include "engine/simulation/integrator.h"
#include "engine/simulation/lane_loop.h"

namespace gesweep {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Extremes are monitored at this interval when no series is requested: fine enough to catch the peak of
/// a 20 rad/s closed-loop short-period oscillation to a few per cent.
constexpr double kMonitorInterval_s = 0.05;
/// A resumed landing (ResumeLanding) without a series is integrated in windows this long.
constexpr double kResumeWindow_s = 2.0;

/// Simulation state: the plant's [Δu, Δw, q, Δθ] and the absolute height H (Ḣ = u0·Δθ − Δw, the ΔH row
/// of Eq. (1)), the actuator δe and the compensator. The tracking error e (d or H − H_ref) is not a
/// state: with ḋ = Ḣ − u0·γr it is exactly H minus the reference trajectory (docs/landing.md §3).
/// In a moving atmosphere (docs/model.md §9) two more: the along-track ground position x_g (m from the
/// start, ẋ_g = u0 + Δu, over which the glide path is a line) and the disturbance field's states.
enum SimIndex : int {
  kSimDu,
  kSimDw,
  kSimQ,
  kSimTheta,
  kSimH,
  kSimElevator,
  kSimCompensator,
  kSimIntegral,
  kSimGround,
  kSimField
};
constexpr int kSimDimension = 8;
constexpr int kSimAirDimension = kSimField + DisturbanceField::kStateCount;

enum EventIndex : int {
  kFlareEvent,
  kTouchdownEvent,
  kStallEvent,
  kDivergenceEvent,
  kUpperEnter,
  kUpperLeave,
  kLowerEnter,
  kLowerLeave,
  kEventTotal
};

// kAir: in a moving atmosphere (the field's states, the ground position, the geometric glide path);
// otherwise the still-air problem of docs/landing.md.
template <bool kAir>
class LandingProblem {
 public:
  static constexpr int kDimension = kAir ? kSimAirDimension : kSimDimension;
  static constexpr int kEventCount = kEventTotal;
  using State = OdeState<kDimension>;

  LandingProblem(const LongitudinalModel& plant, const LandingConfig& config, const LandingDesign& design,
                 LandingResult& result, bool store_series, const DisturbanceField* field = nullptr,
                 const std::vector<DisturbanceField::Segment>* field_segments = nullptr)
      : plant_(plant),
        field_(field),
        field_segments_(field_segments),
        result_(result),
        store_series_(store_series),
        u0_(config.start_speed_mps),
        gamma_r_rad_(-config.glide_slope_deg * kRadiansPerDegree),
        gamma_rad_(config.glide_slope_deg * kRadiansPerDegree),
        path_start_m_(config.start_height_m - config.start_glide_path_offset_m),
        flare_height_m_(config.flare_height_m),
        flare_asymptote_m_(config.flare_asymptote_m),
        reset_at_flare_(config.reset_compensator_at_flare),
        tau_s_(FlareTimeConstant(config)),
        touchdown_height_m_(plant.aircraft().wheel_contact_height_m),
        stall_speed_mps_(plant.aircraft().stall_speed_mps),
        divergence_rad_(config.divergence_pitch_deg * kRadiansPerDegree),
        elevator_min_rad_(config.elevator_min_deg * kRadiansPerDegree),
        elevator_max_rad_(config.elevator_max_deg * kRadiansPerDegree),
        actuator_pole_(config.actuator_pole_per_s),
        compensator_pole_(config.compensator_pole_per_s),
        fixed_reference_(config.plant_height_reference == PlantHeightReference::kFixedHeight),
        fixed_reference_height_m_(result.plant_fixed_reference_height_m),
        gain_(design.gain) {
    if (plant.options().interpolation == Interpolation::kLinear) {
      table_ = std::make_unique<LinearDerivativeTable>(plant);
      table_hint_ = table_->SegmentOf(config.start_height_m);
    }
  }

  /// Height of the reference trajectory: the glide path (over time in still air; over the ground
  /// position in a moving atmosphere), or the flare's exponential towards its asymptote.
  double ReferenceHeight(double t, const State& x) const {
    if (flight_.phase == LandingPhase::kGlideSlope) {
      if constexpr (kAir) {
        return path_start_m_ + gamma_r_rad_ * x[kSimGround];
      } else {
        return path_start_m_ + u0_ * gamma_r_rad_ * t;
      }
    }
    return flare_asymptote_m_ +
           (flare_height_m_ - flare_asymptote_m_) * std::exp(-(t - flight_.flare_start_s) / tau_s_);
  }

  /// ηe = −K·z with z the states of Eq. (14) (K_ΔH = 0 by design). In a moving atmosphere the
  /// controller's Δu and Δw are the air-relative ones (what an airspeed sensor and an angle-of-attack
  /// vane measure: the deviations from the trim it was designed about, docs/landing.md §6).
  double Command(double t, const State& x, int segment) const {
    if constexpr (kAir) {
      const AirMotion air = Motion(x, segment);
      return Command(t, x, x[kSimDu] - air.u_g_mps, x[kSimDw] - air.w_g_mps);
    } else {
      (void)segment;
      return Command(t, x, x[kSimDu], x[kSimDw]);
    }
  }
  double Command(double t, const State& x, double delta_u_mps, double delta_w_mps) const {
    const double e = x[kSimH] - ReferenceHeight(t, x);
    double compensator = x[kSimCompensator];
    double integral = x[kSimIntegral];
    if (reset_at_flare_ && flight_.phase == LandingPhase::kFlare) {
      // The free response from the values at the switch (ε̇ = 0, ẋ_c = −S·x_c + ε), removed: what is
      // left started from zero at the switch and obeys the same equations.
      const double settled = flight_.integral_at_flare / compensator_pole_;
      compensator -= settled + (flight_.compensator_at_flare - settled) *
                                   std::exp(-compensator_pole_ * (t - flight_.flare_start_s));
      integral -= flight_.integral_at_flare;
    }
    return -(gain_[0] * delta_u_mps + gain_[1] * delta_w_mps + gain_[2] * x[kSimQ] + gain_[3] * x[kSimTheta] +
             gain_[5] * x[kSimElevator] + gain_[6] * e + gain_[7] * compensator + gain_[8] * integral);
  }

  /// The air motion at the airplane (zeros in still air).
  AirMotion Air(const State& x, int segment, DisturbanceField::State& field_dxdt) const {
    if constexpr (kAir) {
      DisturbanceField::State xf;
      std::copy(x.begin() + kSimField, x.end(), xf.begin());
      return field_->Evaluate((*field_segments_)[static_cast<std::size_t>(segment)], x[kSimH],
                              u0_ + x[kSimDu], xf, field_dxdt);
    } else {
      AirMotion still;
      still.airspeed_mps = u0_ + x[kSimDu];
      return still;
    }
  }

  /// The air motion alone (no field derivatives, no ẇ_g): for the controller, events and monitors.
  AirMotion Motion(const State& x, int segment) const {
    if constexpr (kAir) {
      DisturbanceField::State xf;
      std::copy(x.begin() + kSimField, x.end(), xf.begin());
      return field_->Motion((*field_segments_)[static_cast<std::size_t>(segment)], x[kSimH], u0_ + x[kSimDu],
                            xf);
    } else {
      (void)segment;
      AirMotion still;
      still.airspeed_mps = u0_ + x[kSimDu];
      return still;
    }
  }

  void Derivative(double t, const State& x, int segment, State& dxdt) const {
    const double height_m = x[kSimH];
    const double speed_mps = u0_ + x[kSimDu];
    const double e = height_m - ReferenceHeight(t, x);
    const double delta_h = fixed_reference_ ? height_m - fixed_reference_height_m_ : e;
    double command = 0.0;
    if constexpr (kAir) {
      DisturbanceField::State field_dxdt;
      const AirMotion air = Air(x, segment, field_dxdt);
      const Vector5d x5(x[kSimDu], x[kSimDw], x[kSimQ], x[kSimTheta], delta_h);
      // The per-segment table of the derivatives (derivative_kernel.h) when the interpolation is
      // linear, as the open loop's fast path; the model's own evaluation otherwise.
      const DimensionalDerivatives derivatives =
          table_ != nullptr ? table_->DerivativesAt(height_m, air.airspeed_mps, table_hint_)
                            : plant_.DerivativesAt(height_m, air.airspeed_mps);
      const Vector5d d5 =
          AirRelativeDerivative(derivatives, u0_, x5, x[kSimElevator],
                                AirVelocity{air.u_g_mps, air.w_g_mps, air.q_g_radps, air.w_g_dot_mps2});
      for (int i = 0; i < 4; ++i) dxdt[static_cast<std::size_t>(i)] = d5[i];
      dxdt[kSimH] = d5[kDeltaH];
      dxdt[kSimGround] = speed_mps;  // the ground speed, to first order
      std::copy(field_dxdt.begin(), field_dxdt.end(), dxdt.begin() + kSimField);
      command = Command(t, x, x[kSimDu] - air.u_g_mps, x[kSimDw] - air.w_g_mps);
    } else {
      (void)segment;
      const Equation1Entries entries =
          EntriesFromDerivatives(table_ != nullptr ? table_->DerivativesAt(height_m, speed_mps, table_hint_)
                                                   : plant_.DerivativesAt(height_m, speed_mps),
                                 u0_);
      const double x5[5] = {x[kSimDu], x[kSimDw], x[kSimQ], x[kSimTheta], delta_h};
      double dx5[5];
      Equation1Derivative(entries, u0_, x5, x[kSimElevator], dx5);
      for (int i = 0; i < 4; ++i) dxdt[i] = dx5[i];
      dxdt[kSimH] = dx5[kDeltaH];
      command = Command(t, x, x[kSimDu], x[kSimDw]);
    }
    command = std::clamp(command, elevator_min_rad_, elevator_max_rad_);
    dxdt[kSimElevator] = actuator_pole_ * (command - x[kSimElevator]);
    dxdt[kSimCompensator] = -compensator_pole_ * x[kSimCompensator] + x[kSimIntegral];
    dxdt[kSimIntegral] = -e;  // ε̇ = r − e with r = 0
  }

  void EventValues(double t, const State& x, int segment, std::array<double, kEventCount>& g) const {
    g[kFlareEvent] = flight_.phase == LandingPhase::kGlideSlope ? x[kSimH] - flare_height_m_ : 1.0;
    g[kTouchdownEvent] = x[kSimH] - touchdown_height_m_;
    double command = 0.0;
    if constexpr (kAir) {
      const AirMotion air = Motion(x, segment);
      g[kStallEvent] = air.airspeed_mps - stall_speed_mps_;  // the airspeed stalls
      command = Command(t, x, x[kSimDu] - air.u_g_mps, x[kSimDw] - air.w_g_mps);
    } else {
      (void)segment;
      g[kStallEvent] = u0_ + x[kSimDu] - stall_speed_mps_;
      command = Command(t, x, x[kSimDu], x[kSimDw]);
    }
    g[kDivergenceEvent] = divergence_rad_ - std::abs(x[kSimTheta]);
    g[kUpperEnter] = elevator_max_rad_ - command;
    g[kUpperLeave] = command - elevator_max_rad_;
    g[kLowerEnter] = command - elevator_min_rad_;
    g[kLowerLeave] = elevator_min_rad_ - command;
  }

  EventAction OnEvent(int event, double t, const State& x, int segment) {
    Monitor(t, x, segment);
    switch (event) {
      case kFlareEvent:
        result_.flare_start_time_s = t;
        result_.glide_path_error_at_flare_m = x[kSimH] - ReferenceHeight(t, x);
        flight_.phase = LandingPhase::kFlare;
        flight_.flare_start_s = t;
        flight_.compensator_at_flare = x[kSimCompensator];
        flight_.integral_at_flare = x[kSimIntegral];
        // The tracking error jumps from d to H − H_ref = 0, and with it the command: re-read saturation.
        UpdateSaturation(t, IsSaturated(Command(t, x, segment)));
        return EventAction::kRestart;
      case kTouchdownEvent:
      case kStallEvent:
      case kDivergenceEvent:
        return EventAction::kStop;
      case kUpperEnter:
      case kLowerEnter:
        UpdateSaturation(t, true);
        return EventAction::kContinue;
      case kUpperLeave:
      case kLowerLeave:
        UpdateSaturation(t, false);  // the command is back at the limit it crossed
        return EventAction::kContinue;
      default:
        GESWEEP_UNREACHABLE();  // the problem declares no other event
    }
  }

  void OnStep(double t, const State& x, int segment) {
    Monitor(t, x, segment);
    if (observer_ == nullptr) return;
    const StepContext context{this, t, &x};
    (*observer_)(LandingStep(t, x[kSimH], SinkRate(x), flight_.phase, &SaveStep, &context));
  }

  /// The observer OnStep calls (may be null).
  void Observe(const LandingObserver* observer) { observer_ = observer; }

  /// The landing at (t, x): the part flown and the bookkeeping (LandingCheckpoint).
  LandingCheckpoint Save(double t, const State& x) const {
    LandingCheckpoint c;
    c.time_s = t;
    c.result = result_;
    c.state.assign(x.begin(), x.end());
    c.flight = flight_;
    return c;
  }

  /// Takes the bookkeeping of a saved landing (its state is the integration's start, its result the
  /// caller's).
  void Restore(const LandingCheckpoint& c) {
    flight_ = c.flight;
    if (table_ != nullptr && !c.state.empty()) table_hint_ = table_->SegmentOf(c.state[kSimH]);
  }

  void OnOutput(double t, const State& x, int segment) {
    Monitor(t, x, segment);
    if (!store_series_) return;
    LandingSample s;
    s.time_s = t;
    s.phase = flight_.phase;
    s.height_m = x[kSimH];
    s.reference_height_m = ReferenceHeight(t, x);
    s.tracking_error_m = s.height_m - s.reference_height_m;
    s.speed_mps = u0_ + x[kSimDu];
    s.delta_w_mps = x[kSimDw];
    s.pitch_rate_radps = x[kSimQ];
    s.pitch_rad = x[kSimTheta];
    s.sink_rate_mps = SinkRate(x);
    s.elevator_rad = x[kSimElevator];
    s.elevator_command_rad = Command(t, x, segment);
    s.compensator = x[kSimCompensator];
    s.error_integral = x[kSimIntegral];
    if constexpr (kAir) {
      s.distance_past_transmitter_m = x[kSimGround] - path_start_m_ / gamma_rad_;
      const AirMotion air = Motion(x, segment);
      s.u_g_mps = air.u_g_mps;
      s.w_g_mps = air.w_g_mps;
      s.q_g_radps = air.q_g_radps;
    } else {
      (void)segment;
      s.distance_past_transmitter_m = u0_ * (t - path_start_m_ / (u0_ * gamma_rad_));
    }
    result_.series.push_back(s);
  }

  /// Starts the saturation bookkeeping at the initial state.
  void Start(double t, const State& x) {
    flight_.saturated = IsSaturated(Command(t, x, 0));
    flight_.saturated_since_s = t;
  }

  /// Closes an open saturation interval at the end of the run.
  void Finish(double t) { UpdateSaturation(t, false); }

  double SinkRate(const State& x) const { return x[kSimDw] - u0_ * x[kSimTheta]; }
  LandingPhase phase() const { return flight_.phase; }

  /// Lane i of a batch (landing_lanes.h): this landing's constants, its table and its field.
  template <int W>
  void ToLane(lanes::LandingStepArrays<W>& a, int i) const {
    static_assert(kAir);
    a.u0[i] = u0_;
    a.gamma_r[i] = gamma_r_rad_;
    a.path_start[i] = path_start_m_;
    a.flare_height[i] = flare_height_m_;
    a.flare_asymptote[i] = flare_asymptote_m_;
    a.tau[i] = tau_s_;
    a.elevator_min[i] = elevator_min_rad_;
    a.elevator_max[i] = elevator_max_rad_;
    a.actuator_pole[i] = actuator_pole_;
    a.compensator_pole[i] = compensator_pole_;
    a.fixed_reference_height[i] = fixed_reference_height_m_;
    for (int j = 0; j < kLandingStateCount; ++j) a.gain[j][i] = gain_[static_cast<std::size_t>(j)];
    a.sigma_w[i] = field_->sigma_w_mps();
    a.pitch_rate_gust[i] = field_->options().pitch_rate_gust;
    // As DisturbanceField::Motion and Evaluate compute it.
    a.pitch_rate_k[i] = a.pitch_rate_gust[i] ? std::numbers::pi / (4.0 * field_->options().wing_span_m) : 0.0;
    a.fixed_reference[i] = fixed_reference_;
    a.reset_at_flare[i] = reset_at_flare_;
    a.table[i] = table_.get();
    a.hint[i] = table_hint_;
    a.field[i] = field_;
    PhaseToLane(a, i);
  }

  /// The phase of lane i (after a flare switch).
  template <int W>
  void PhaseToLane(lanes::LandingStepArrays<W>& a, int i) const {
    a.flare[i] = flight_.phase == LandingPhase::kFlare;
    a.flare_start[i] = flight_.flare_start_s;
    a.compensator_at_flare[i] = flight_.compensator_at_flare;
    a.integral_at_flare[i] = flight_.integral_at_flare;
  }

 private:
  struct StepContext {
    const LandingProblem* problem;
    double t;
    const State* x;
  };
  static LandingCheckpoint SaveStep(const void* context) {
    const auto* c = static_cast<const StepContext*>(context);
    return c->problem->Save(c->t, *c->x);
  }

  bool IsSaturated(double command) const {
    return command > elevator_max_rad_ || command < elevator_min_rad_;
  }

  void UpdateSaturation(double t, bool saturated) {
    if (saturated == flight_.saturated) return;
    if (flight_.saturated) {
      const double length = t - flight_.saturated_since_s;
      result_.saturated_time_s += length;
      result_.longest_saturation_s = std::max(result_.longest_saturation_s, length);
    }
    flight_.saturated = saturated;
    flight_.saturated_since_s = t;
  }

  void Monitor(double t, const State& x, int segment) {
    result_.max_abs_elevator_deg =
        std::max(result_.max_abs_elevator_deg, std::abs(x[kSimElevator]) * kDegreesPerRadian);
    result_.max_abs_elevator_command_deg =
        std::max(result_.max_abs_elevator_command_deg, std::abs(Command(t, x, segment)) * kDegreesPerRadian);
    result_.max_abs_pitch_rate_degps =
        std::max(result_.max_abs_pitch_rate_degps, std::abs(x[kSimQ]) * kDegreesPerRadian);
    const double speed = u0_ + x[kSimDu];
    result_.min_speed_mps = std::min(result_.min_speed_mps, speed);
    result_.max_speed_mps = std::max(result_.max_speed_mps, speed);
    if (flight_.phase == LandingPhase::kFlare) {
      result_.flare_max_abs_elevator_deg =
          std::max(result_.flare_max_abs_elevator_deg, std::abs(x[kSimElevator]) * kDegreesPerRadian);
      result_.flare_max_abs_pitch_rate_degps =
          std::max(result_.flare_max_abs_pitch_rate_degps, std::abs(x[kSimQ]) * kDegreesPerRadian);
    }
  }

  const LongitudinalModel& plant_;
  // With linear interpolation: the derivatives' per-segment table (derivative_table.h), in still air
  // as in a moving atmosphere (the model's own evaluation, 13 divides and a pow a call, made a
  // still-air landing 1.6x slower).
  std::unique_ptr<LinearDerivativeTable> table_;
  mutable int table_hint_ = 0;
  const DisturbanceField* field_;
  const std::vector<DisturbanceField::Segment>* field_segments_;
  LandingResult& result_;
  bool store_series_;
  double u0_;
  double gamma_r_rad_;
  double gamma_rad_;
  double path_start_m_;
  double flare_height_m_;
  double flare_asymptote_m_;
  bool reset_at_flare_;
  double tau_s_;
  double touchdown_height_m_;
  double stall_speed_mps_;
  double divergence_rad_;
  double elevator_min_rad_;
  double elevator_max_rad_;
  double actuator_pole_;
  double compensator_pole_;
  bool fixed_reference_;
  double fixed_reference_height_m_;
  std::array<double, kLandingStateCount> gain_;
  LandingCheckpoint::Flight flight_;
  const LandingObserver* observer_ = nullptr;
};

std::string Format(double value, int precision = 4) {
  std::ostringstream out;
  out.precision(precision);
  out << value;
  return out.str();
}

template <bool kAir>
void Conclude(LandingProblem<kAir>& problem, const IntegrationResult<LandingProblem<kAir>::kDimension>& run,
              const LandingConfig& config, LandingResult& result);

// Flies the landing from its start, or on from `from` (ResumeLanding).
template <bool kAir>
void Fly(const LongitudinalModel& plant, const LandingConfig& config, LandingResult& result,
         bool store_series, const DisturbanceField* field, const std::atomic<bool>* cancel,
         const LandingObserver* observer = nullptr, const LandingCheckpoint* from = nullptr) {
  // A resumed landing without a series is integrated in windows of kResumeWindow_s, each with its own
  // noise table, so that a branch that ends soon (most do) builds the table of a few seconds, not of
  // the rest of the time limit; any other in one piece.
  const bool windowed = from != nullptr && !store_series;
  const double limit_s = result.time_limit_s;
  auto window_end = [&](double t) { return windowed ? std::min(limit_s, t + kResumeWindow_s) : limit_s; };
  double t = from != nullptr ? from->time_s : 0.0;
  double end_s = window_end(t);
  std::vector<double> breakpoints;
  std::vector<DisturbanceField::Segment> field_segments;
  auto build_table = [&] {
    if constexpr (kAir) {
      // SIGINT/SIGTERM are read while the noise table is built (up to kMaximumNoiseSamplesPerRun
      // instants): a stop empties it and Integrate stops before its first step.
      breakpoints = field->Breakpoints(t, end_s, cancel);
      field_segments = field->SegmentTable(breakpoints, t, cancel);
      if (cancel != nullptr && cancel->load()) breakpoints.clear();
    }
  };
  build_table();
  LandingProblem<kAir> problem(plant, config, result.design, result, store_series, field, &field_segments);
  problem.Observe(observer);
  typename LandingProblem<kAir>::State x0{};
  if (from != nullptr) {
    std::copy(from->state.begin(), from->state.end(), x0.begin());
    problem.Restore(*from);
  } else {
    x0[kSimTheta] = config.start_pitch_deg * kRadiansPerDegree;
    x0[kSimH] = config.start_height_m;
    if constexpr (kAir) {
      // At airspeed start_speed_mps in the mean wind (docs/model.md §9).
      x0[kSimDu] =
          MeanWindAt(field->options().wind_20ft_mps, config.start_height_m, field->options().wind_shear);
      const DisturbanceField::State field_start = field->InitialState();
      std::copy(field_start.begin(), field_start.end(), x0.begin() + kSimField);
    }
    problem.Start(0.0, x0);
  }

  IntegratorOptions options = config.integrator;
  options.kind = IntegratorKind::kDopri5;
  options.step_s = std::min(0.01, config.integrator.max_step_s);
  options.output_interval_s = store_series ? config.output_interval_s : kMonitorInterval_s;
  options.cancel = cancel;
  if constexpr (kAir) {
    const DisturbanceOptions& d = field->options();
    if (d.turbulence != TurbulenceModel::kNone && field->sigma_w_mps() > 0.0 &&
        config.turbulent_integrator == IntegratorKind::kRk4) {
      // The noise's sample instants are RK4's grid (docs/disturbance.md, Cost).
      options.kind = IntegratorKind::kRk4;
      options.step_s = d.turbulence_sample_interval_s;
    }
  }
  long accepted = 0, rejected = 0, rhs_calls = 0;
  for (;;) {
    auto run = Integrate(problem, x0, t, end_s, breakpoints, options);
    accepted += run.accepted_steps;
    rejected += run.rejected_steps;
    rhs_calls += run.rhs_calls;
    if (run.status != IntegrationStatus::kReachedEnd || end_s >= limit_s) {
      run.accepted_steps = accepted;
      run.rejected_steps = rejected;
      run.rhs_calls = rhs_calls;
      Conclude(problem, run, config, result);
      return;
    }
    t = run.end_time_s;
    x0 = run.final_state;
    end_s = window_end(t);
    build_table();
  }
}

// The result from how the integration ended (Fly's, and each lane's of a batch).
template <bool kAir>
void Conclude(LandingProblem<kAir>& problem, const IntegrationResult<LandingProblem<kAir>::kDimension>& run,
              const LandingConfig& config, LandingResult& result) {
  problem.Finish(run.end_time_s);

  const auto& xf = run.final_state;
  result.final_time_s = run.end_time_s;
  result.final_height_m = xf[kSimH];
  result.accepted_steps = run.accepted_steps;
  result.rejected_steps = run.rejected_steps;
  result.rhs_calls = run.rhs_calls;
  const std::string at = " at t = " + Format(run.end_time_s, 6) + " s";
  switch (run.status) {
    case IntegrationStatus::kReachedEnd:
      result.outcome = LandingOutcome::kNoTouchdown;
      result.message = "time limit reached in flight at H = " + Format(xf[kSimH]) + " m";
      break;
    case IntegrationStatus::kCancelled:
      result.cancelled = true;
      result.outcome = LandingOutcome::kNoTouchdown;
      result.message = "cancelled" + at;
      break;
    case IntegrationStatus::kNonFinite:
    case IntegrationStatus::kStepSizeUnderflow:
      result.outcome = LandingOutcome::kDiverged;
      result.message = "the state stopped being finite (" + std::string(ToString(run.status)) + ")" + at;
      break;
    case IntegrationStatus::kStoppedByEvent:
      if (run.stopping_event == kTouchdownEvent) {
        result.outcome = LandingOutcome::kLanded;
        result.message = "touchdown" + at + " in the " + std::string(ToString(problem.phase())) + " phase";
        result.touchdown_time_s = run.end_time_s;
        const double gamma_rad = config.glide_slope_deg * kRadiansPerDegree;
        if constexpr (kAir) {
          // The glide path meets H = 0 at x_g = (H0 − d0)/γ; the ground position is a state.
          result.touchdown_distance_past_transmitter_m =
              xf[kSimGround] - (config.start_height_m - config.start_glide_path_offset_m) / gamma_rad;
          result.touchdown_airspeed_mps = problem.Motion(xf, run.final_segment).airspeed_mps;
        } else {
          const double transmitter_time_s = (config.start_height_m - config.start_glide_path_offset_m) /
                                            (config.start_speed_mps * gamma_rad);
          result.touchdown_distance_past_transmitter_m =
              config.start_speed_mps * (run.end_time_s - transmitter_time_s);
          result.touchdown_airspeed_mps = config.start_speed_mps + xf[kSimDu];
        }
        result.touchdown_sink_rate_mps = problem.SinkRate(xf);
        result.touchdown_pitch_deg = xf[kSimTheta] * kDegreesPerRadian;
        result.touchdown_speed_mps = config.start_speed_mps + xf[kSimDu];
      } else if (run.stopping_event == kStallEvent) {
        result.outcome = LandingOutcome::kStall;
        result.message = "stall speed reached" + at + " at H = " + Format(xf[kSimH]) + " m";
      } else {
        result.outcome = LandingOutcome::kDiverged;
        result.message = "|pitch| reached " + Format(config.divergence_pitch_deg) + " deg" + at;
      }
      break;
  }
}

// The noise point's length (SimulateLanding checks it once the design succeeded).
void CheckNoisePoint(const LongitudinalModel& plant, const LandingConfig& config,
                     std::span<const double> noise_point) {
  const Aircraft& aircraft = plant.aircraft();
  if (!noise_point.empty()) {
    const std::uint64_t needed = LandingNoiseDimension(aircraft, config);
    if (noise_point.size() < needed) {
      throw InputError("landing config", "noise point", std::to_string(noise_point.size()) + " values",
                       "at least " + std::to_string(needed) + " (LandingNoiseDimension)");
    }
  }
}

// The result before the flight: what the run uses, the extremes' starting values, the gain (a failed
// design's result is complete).
LandingResult BeginLanding(const LongitudinalModel& plant, const LandingConfig& config) {
  const Aircraft& aircraft = plant.aircraft();
  LandingResult result;
  result.flare_height_m = config.flare_height_m;
  result.flare_time_constant_s = FlareTimeConstant(config);
  result.glide_slope_deg = config.glide_slope_deg;
  result.plant_fixed_reference_height_m =
      SetOr(config.plant_fixed_reference_height_m, aircraft.table_heights_m.back());
  result.plant_h_derivatives = plant.options().h_derivatives;
  result.time_limit_s = LandingTimeLimit(config, aircraft.wheel_contact_height_m);
  for (double* field :
       {&result.touchdown_time_s, &result.touchdown_distance_past_transmitter_m,
        &result.touchdown_sink_rate_mps, &result.touchdown_pitch_deg, &result.touchdown_speed_mps,
        &result.touchdown_airspeed_mps, &result.flare_start_time_s, &result.glide_path_error_at_flare_m}) {
    *field = kNaN;
  }
  result.min_speed_mps = std::numeric_limits<double>::infinity();
  result.max_speed_mps = -std::numeric_limits<double>::infinity();

  result.design = DesignLandingController(plant, config);
  if (!result.design.ok()) {
    result.outcome = LandingOutcome::kDesignFailed;
    result.message =
        "LQR design failed (" + std::string(ToString(result.design.status)) + "): " + result.design.message;
    result.final_height_m = config.start_height_m;
    result.min_speed_mps = result.max_speed_mps = config.start_speed_mps;
    return result;
  }
  if (config.output_interval_s > 0.0) {
    result.series.reserve(static_cast<std::size_t>(result.time_limit_s / config.output_interval_s) + 2);
  }
  return result;
}

// The landing's moving atmosphere: its noise from (seed, run index), or the given point.
DisturbanceField LandingField(const LongitudinalModel& plant, const LandingConfig& config,
                              std::span<const double> noise_point) {
  DisturbanceOptions disturbance = config.disturbance;
  disturbance.wing_span_m = plant.aircraft().wingspan_m;
  return noise_point.empty() ? DisturbanceField(disturbance, config.seed, config.run_index)
                             : DisturbanceField(disturbance, noise_point);
}

// The result after the flight.
void EndLanding(LandingResult& result) {
  if (result.flare_start_time_s != result.flare_start_time_s) {  // NaN: no flare
    result.flare_max_abs_elevator_deg = kNaN;
    result.flare_max_abs_pitch_rate_degps = kNaN;
  }
}

// ---------------------------------------------------------------- many landings in lockstep (SIMD lanes)

// The settings of Integrate that Fly gives a turbulent landing flown by RK4 (LandingRunUsesLanes).
IntegratorOptions LaneIntegratorOptions(const LandingConfig& config) {
  IntegratorOptions options = config.integrator;
  options.kind = IntegratorKind::kRk4;
  options.step_s = config.disturbance.turbulence_sample_interval_s;
  options.output_interval_s = config.output_interval_s > 0.0 ? config.output_interval_s : kMonitorInterval_s;
  return options;
}

// A landing flown in a lane: its field, breakpoints and problem as Fly<true> makes them, its
// integrator's settings and output grid, and IntegrateWith's bookkeeping (LaneRunBase).
struct LandingLaneRun : lanes::LaneRunBase<LandingProblem<true>, LandingConfig> {
  static_assert(N == lanes::kLandingLaneStates);

  std::unique_ptr<DisturbanceField> field;
  std::vector<double> breakpoints;
  std::vector<DisturbanceField::Segment> segments;
  std::unique_ptr<Problem> problem;
  IntegratorOptions options;
  std::int64_t noise_index = -1;  // the held sample whose noise the lane's arrays hold
  long next_output = 0;
  double last_output_time = -std::numeric_limits<double>::infinity();
};

// W lanes: the landings' states side by side (landing_lanes.h), component c of lane i at [c][i]. The
// per-lane decisions are here, in scalar code, through each landing's own LandingProblem (events,
// outputs, monitors, the flare switch); the RK4 stages and the restarts' derivatives of all lanes are
// the kernels of the batch's instruction set.
template <int W>
class LandingLanes : public lanes::LaneFleet<LandingLanes<W>, W, LandingLaneRun, LandingResult,
                                             lanes::LandingStepArrays<W>> {
  using Fleet =
      lanes::LaneFleet<LandingLanes<W>, W, LandingLaneRun, LandingResult, lanes::LandingStepArrays<W>>;
  friend Fleet;
  using Run = LandingLaneRun;
  using typename Fleet::State;
  using typename Fleet::Step;
  static constexpr int N = Run::N;
  using Fleet::a_;
  using Fleet::active_;
  using Fleet::cancel_;
  using Fleet::Finish;
  using Fleet::Interpolate;
  using Fleet::Lane;
  using Fleet::lane_;
  using Fleet::results_;
  using Fleet::SetLane;

 public:
  LandingLanes(std::span<const LandingBatchRun> runs, std::span<const std::size_t> order,
               std::vector<LandingResult>& results, LanesIsa isa, const std::atomic<bool>* cancel)
      : Fleet(order, results, cancel),
        runs_(runs),
        kernels_(lanes::KernelsFor<lanes::LandingKernels, W>(isa)) {}

 private:
  // The held noise of lane i's segment in its arrays (DisturbanceField::Evaluate's).
  void SetNoise(int i) {
    Run& lane = lane_[i];
    const std::int64_t index = lane.segments[static_cast<std::size_t>(lane.segment)].sample_index;
    if (index == lane.noise_index) return;
    a_.noise_u[i] = lane.field->HeldNoise(NoiseStream::kTurbulenceU, index);
    a_.noise_w[i] = lane.field->HeldNoise(NoiseStream::kTurbulenceW, index);
    lane.noise_index = index;
  }

  // IntegrateWith's emit_outputs_through for lane i.
  template <class Interpolate>
  void EmitOutputsThrough(int i, double t_cut, Interpolate&& interpolate) {
    Run& lane = lane_[i];
    const double interval = lane.options.output_interval_s;
    const double snap = integrator_detail::kSnapFraction * interval;
    for (;;) {
      const double t_out = 0.0 + static_cast<double>(lane.next_output) * interval;
      if (t_out > t_cut + snap) break;
      const double tau = std::min(t_out, t_cut);
      State xo;
      interpolate(tau, xo);
      lane.problem->OnOutput(tau, xo, lane.segment);
      lane.last_output_time = tau;
      ++lane.next_output;
    }
  }

  // For LaneFleet: starts `run` in lane i (SimulateLanding's and Fly<true>'s start, IntegrateWith's);
  // a landing whose design fails is complete at once (false).
  bool Start(int i, std::size_t run) {
    const LandingBatchRun& r = runs_[run];
    LandingResult& result = results_[run];
    result = BeginLanding(*r.plant, r.config);
    if (!result.design.ok()) return false;
    Run& lane = lane_[i];
    lane = Run{};
    lane.run = run;
    lane.config = &r.config;
    lane.field = std::make_unique<DisturbanceField>(LandingField(*r.plant, r.config, r.noise_point));
    lane.breakpoints = lane.field->Breakpoints(0.0, result.time_limit_s, cancel_);
    lane.segments = lane.field->SegmentTable(lane.breakpoints, 0.0, cancel_);
    if (cancel_ != nullptr && cancel_->load()) lane.breakpoints.clear();
    const bool store_series = r.config.output_interval_s > 0.0;
    lane.problem = std::make_unique<Run::Problem>(*r.plant, r.config, result.design, result, store_series,
                                                  lane.field.get(), &lane.segments);
    State x0{};
    x0[kSimTheta] = r.config.start_pitch_deg * kRadiansPerDegree;
    x0[kSimH] = r.config.start_height_m;
    const DisturbanceOptions& d = lane.field->options();
    x0[kSimDu] = MeanWindAt(d.wind_20ft_mps, r.config.start_height_m, d.wind_shear);
    const DisturbanceField::State field_start = lane.field->InitialState();
    std::copy(field_start.begin(), field_start.end(), x0.begin() + kSimField);
    lane.problem->Start(0.0, x0);
    lane.options = LaneIntegratorOptions(r.config);
    lane.end_s = result.time_limit_s;
    lane.segment = integrator_detail::SegmentOf(lane.breakpoints, 0.0);
    lane.next_breakpoint = static_cast<std::size_t>(lane.segment);
    lane.problem->ToLane(a_, i);
    // IntegrateWith's start.
    lane.problem->OnStep(0.0, x0, lane.segment);
    lane.problem->EventValues(0.0, x0, lane.segment, lane.g_previous);
    EmitOutputsThrough(i, 0.0, [&](double, State& out) { out = x0; });
    State f0;
    ++lane.result.rhs_calls;
    lane.problem->Derivative(0.0, x0, lane.segment, f0);
    SetLane(a_.x, i, x0);
    SetLane(a_.f, i, f0);
    return true;
  }

  // For LaneFleet: an idle lane flies zeros on another lane's table and field (its results are never read).
  void Idle(int i) {
    for (int c = 0; c < N; ++c) a_.x[c][i] = a_.f[c][i] = 0.0;
    a_.h[i] = a_.half_h[i] = a_.sixth_h[i] = 0.0;
    a_.flare[i] = false;
    for (int j = 0; j < W; ++j) {
      if (a_.table[j] != nullptr) {
        if (a_.table[i] == nullptr) {
          a_.table[i] = a_.table[j];
          a_.field[i] = a_.field[j];
        }
        break;
      }
    }
  }

  // For LaneFleet: Rk4Method::Advance up to the stages.
  void PrepareStep(int i) {
    Run& lane = lane_[i];
    const double t_to = this->StepEnd(i, lane.breakpoints, lane.options.step_s);
    const double h = t_to - lane.t;
    const double half_h = 0.5 * h;
    a_.t[i] = lane.t;
    a_.t_to[i] = t_to;
    a_.h[i] = h;
    a_.half_h[i] = half_h;
    a_.sixth_h[i] = h / 6.0;
    a_.t_mid[i] = lane.t + half_h;
    SetNoise(i);
  }

  // For LaneFleet: one step of every lane at once.
  void StepAll() {
    kernels_.rk4_stages(a_);
    bool any_restart = false;
    for (int i = 0; i < W; ++i) {
      restart_[i] = false;
      if (active_[i]) CompleteStep(i);
      any_restart = any_restart || restart_[i];
    }
    if (!any_restart) return;
    // IntegrateWith's restart_here of every lane at a breakpoint or after the flare switch: the
    // derivative at the new segment's start (its held noise) or in the new phase.
    kernels_.derivatives(a_);
    for (int i = 0; i < W; ++i) {
      if (restart_[i]) CompleteRestart(i);
    }
  }

  // IntegrateWith's step after Advance for lane i: the finiteness check, the events located in the
  // step, the outputs, the step's record; a restart is left to CompleteRestart. The step's states
  // other than its end are taken out of the arrays only when the interpolant is wanted inside the
  // step (an event, an output between its ends).
  void CompleteStep(int i) {
    Run& lane = lane_[i];
    Run::Problem& problem = *lane.problem;
    lane.result.rhs_calls += 4;
    const double t = lane.t;
    const double t_new = a_.t_to[i];
    const State x_new = Lane(a_.x_new, i);
    if (!integrator_detail::AllFinite<N>(x_new)) return Finish(i, IntegrationStatus::kNonFinite);
    ++lane.result.accepted_steps;
    Step step;  // filled on the first interpolation inside the step (no std::optional: it zeroes 472 bytes)
    bool step_taken = false;
    auto interpolate = [&](double tau, State& out) {
      if (tau == t_new) {
        out = x_new;
        return;
      }
      if (!step_taken) {
        step = Step{t, t_new, Lane(a_.x, i), Lane(a_.f, i), x_new, Lane(a_.f_new, i)};
        step_taken = true;
      }
      Interpolate(step, tau, out);
    };
    const int segment = lane.segment;
    Run::Events g_new;
    problem.EventValues(t_new, x_new, segment, g_new);
    integrator_detail::StepCut<N> cut;
    const bool cut_here = integrator_detail::FireEvents<N>(
        problem, lane.g_previous, g_new, t, t_new, lane.options.event_time_tolerance_s, interpolate,
        [segment](double) { return segment; },
        [&](double t_through, auto&& through) { EmitOutputsThrough(i, t_through, through); },
        lane.result.events_fired, cut);
    if (!cut_here) {
      EmitOutputsThrough(i, t_new, interpolate);
      problem.OnStep(t_new, x_new, segment);
      lane.t = t_new;
      for (int c = 0; c < N; ++c) {
        a_.x[c][i] = x_new[static_cast<std::size_t>(c)];
        a_.f[c][i] = a_.f_new[c][i];
      }
      lane.g_previous = g_new;
      if (lane.next_breakpoint < lane.breakpoints.size() &&
          lane.breakpoints[lane.next_breakpoint] <= lane.t) {
        // The restart's event values are g_new: the same time, state and phase, and the events do not
        // read the segment (DisturbanceField::Motion does not; the held noise enters derivatives only).
        return StartRestart(i, /*events_known=*/true);
      }
      if (!(lane.t < lane.end_s)) Finish(i, IntegrationStatus::kReachedEnd);
      return;
    }
    // The step is cut at the event.
    EmitOutputsThrough(i, cut.t, interpolate);
    problem.OnStep(cut.t, cut.x, segment);
    lane.t = cut.t;
    SetLane(a_.x, i, cut.x);
    if (cut.action == EventAction::kStop) {
      lane.result.stopping_event = cut.event;
      return Finish(i, IntegrationStatus::kStoppedByEvent);
    }
    StartRestart(i, /*events_known=*/false);
  }

  // restart_here up to its derivative: the segment at the lane's time, the phase and the noise there.
  // events_known: g_previous already holds the event values there.
  void StartRestart(int i, bool events_known) {
    Run& lane = lane_[i];
    while (lane.next_breakpoint < lane.breakpoints.size() &&
           lane.breakpoints[lane.next_breakpoint] <= lane.t) {
      ++lane.next_breakpoint;
      ++lane.segment;
    }
    lane.problem->PhaseToLane(a_, i);
    SetNoise(i);
    a_.t[i] = lane.t;
    restart_[i] = true;
    restart_events_known_[i] = events_known;
  }

  // restart_here after its derivative (the kernel's, in f_new): the event values, the finiteness
  // check, and the loop's test of the end time.
  void CompleteRestart(int i) {
    Run& lane = lane_[i];
    ++lane.result.rhs_calls;
    State f;
    for (int c = 0; c < N; ++c) f[static_cast<std::size_t>(c)] = a_.f_new[c][i];
    SetLane(a_.f, i, f);
    if (!restart_events_known_[i])
      lane.problem->EventValues(lane.t, Lane(a_.x, i), lane.segment, lane.g_previous);
    if (!integrator_detail::AllFinite<N>(f)) return Finish(i, IntegrationStatus::kNonFinite);
    if (!(lane.t < lane.end_s)) Finish(i, IntegrationStatus::kReachedEnd);
  }

  // For LaneFleet: the landing's result (Conclude, EndLanding).
  void Record(int i) {
    Run& lane = lane_[i];
    if (lane.last_output_time < lane.t) lane.problem->OnOutput(lane.t, lane.result.final_state, lane.segment);
    LandingResult& result = results_[lane.run];
    Conclude(*lane.problem, lane.result, *lane.config, result);
    EndLanding(result);
    restart_[i] = false;
  }

  std::span<const LandingBatchRun> runs_;
  lanes::RkKernels<lanes::LandingStepArrays<W>> kernels_;
  std::array<bool, W> restart_{};
  std::array<bool, W> restart_events_known_{};
};

template <int W>
void FlyLandingsInLanes(std::span<const LandingBatchRun> runs, std::span<const std::size_t> order,
                        std::vector<LandingResult>& results, LanesIsa isa, const std::atomic<bool>* cancel) {
  auto lanes = std::make_unique<LandingLanes<W>>(runs, order, results, isa, cancel);
  lanes->FlyAll();
}

}  // namespace

SeriesContents LandingSeriesContents(const LandingConfig& config) {
  DisturbanceOptions still = config.disturbance;
  still.pitch_rate_gust = false;  // needs the aircraft's span; it makes no air motion of its own
  SeriesContents contents;
  contents.disturbance = DisturbanceField(still, config.seed, config.run_index).active();
  contents.pitch_rate_gust = contents.disturbance && config.disturbance.pitch_rate_gust;
  return contents;
}

LandingConfig SettingsUsed(const LandingConfig& config, const LandingResult& result) {
  LandingConfig used = config;
  used.flare_time_constant_s = result.flare_time_constant_s;
  used.time_limit_s = result.time_limit_s;
  used.design_height_m = result.design.design_height_m;
  used.design_speed_mps = result.design.design_speed_mps;
  used.plant_fixed_reference_height_m = result.plant_fixed_reference_height_m;
  return used;
}

std::uint64_t LandingNoiseDimension(const Aircraft& aircraft, const LandingConfig& config) {
  ValidateLandingConfig(config, aircraft, "landing config");
  if (config.disturbance.turbulence != TurbulenceModel::kDryden) return 0;
  DisturbanceOptions disturbance = config.disturbance;
  disturbance.wing_span_m = aircraft.wingspan_m;
  const DisturbanceField field(disturbance, 0, 0);
  const double limit_s = LandingTimeLimit(config, aircraft.wheel_contact_height_m);
  return NoisePointDimension(static_cast<std::uint64_t>(field.SampleIndexAt(limit_s)) + 2);
}

LandingResult SimulateLanding(const LongitudinalModel& plant, const LandingConfig& config,
                              const std::atomic<bool>* cancel, std::span<const double> noise_point,
                              const LandingObserver* observer) {
  ValidateLandingConfig(config, plant.aircraft(), "landing config");
  LandingResult result = BeginLanding(plant, config);
  if (!result.design.ok()) return result;
  CheckNoisePoint(plant, config, noise_point);
  const DisturbanceField field = LandingField(plant, config, noise_point);
  const bool store_series = config.output_interval_s > 0.0;
  if (field.active()) {
    Fly<true>(plant, config, result, store_series, &field, cancel, observer);
  } else {
    Fly<false>(plant, config, result, store_series, nullptr, cancel, observer);
  }
  EndLanding(result);
  return result;
}

LandingResult ResumeLanding(const LongitudinalModel& plant, const LandingConfig& config,
                            const LandingCheckpoint& from, const std::atomic<bool>* cancel,
                            std::span<const double> noise_point, const LandingObserver* observer) {
  ValidateLandingConfig(config, plant.aircraft(), "landing config");
  CheckNoisePoint(plant, config, noise_point);
  const DisturbanceField field = LandingField(plant, config, noise_point);
  const std::size_t dimension = static_cast<std::size_t>(field.active() ? kSimAirDimension : kSimDimension);
  if (from.state.size() != dimension || !from.result.design.ok()) {
    throw InputError("landing checkpoint", "state", std::to_string(from.state.size()) + " values",
                     std::to_string(dimension) + " from a landing of this config that was flown");
  }
  LandingResult result = from.result;
  const bool store_series = config.output_interval_s > 0.0;
  if (field.active()) {
    Fly<true>(plant, config, result, store_series, &field, cancel, observer, &from);
  } else {
    Fly<false>(plant, config, result, store_series, nullptr, cancel, observer, &from);
  }
  EndLanding(result);
  return result;
}

bool LandingRunUsesLanes(const LongitudinalModel& plant, const LandingConfig& config) {
  if (config.turbulent_integrator != IntegratorKind::kRk4 || !config.integrator.honour_breakpoints)
    return false;
  if (plant.options().interpolation != Interpolation::kLinear) return false;
  const DisturbanceOptions& d = config.disturbance;
  if (d.turbulence != TurbulenceModel::kDryden || d.gust_amplitude_mps != 0.0) return false;
  DisturbanceOptions options = d;
  options.wing_span_m = plant.aircraft().wingspan_m;
  return EffectiveSigmaW(options) > 0.0;
}

std::vector<LandingResult> SimulateLandingBatch(std::span<const LandingBatchRun> runs, int width,
                                                const std::atomic<bool>* cancel,
                                                std::optional<LanesIsa> isa) {
  GESWEEP_DEMAND(width == 1 || width == 2 || width == 4 || width == 8);
  GESWEEP_DEMAND(!isa || LanesIsaSupported(*isa));
  const LanesIsa lanes_isa = isa ? *isa : ChooseLanesIsa(width);
  for (const LandingBatchRun& run : runs) {
    GESWEEP_DEMAND(run.plant != nullptr);
    ValidateLandingConfig(run.config, run.plant->aircraft(), "landing config");
    CheckNoisePoint(*run.plant, run.config, run.noise_point);
  }
  std::vector<LandingResult> results(runs.size());
  std::vector<std::size_t> in_lanes;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (LandingRunUsesLanes(*runs[i].plant, runs[i].config)) {
      in_lanes.push_back(i);
    } else {
      results[i] = SimulateLanding(*runs[i].plant, runs[i].config, cancel, runs[i].noise_point);
    }
  }
  if (in_lanes.empty()) return results;
  switch (width) {
    case 1:
      FlyLandingsInLanes<1>(runs, in_lanes, results, lanes_isa, cancel);
      break;
    case 2:
      FlyLandingsInLanes<2>(runs, in_lanes, results, lanes_isa, cancel);
      break;
    case 4:
      FlyLandingsInLanes<4>(runs, in_lanes, results, lanes_isa, cancel);
      break;
    default:
      FlyLandingsInLanes<8>(runs, in_lanes, results, lanes_isa, cancel);
      break;
  }
  return results;
}

}  // namespace gesweep
