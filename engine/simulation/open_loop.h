#pragma once
/// The open-loop time response of docs/model.md §7 (the paper's Section IV and Fig. 4): Eq. (1)
/// integrated from a start height and speed after an elevator input, with the dimensional
/// derivatives re-evaluated at every right-hand-side evaluation at the current height
/// H = H0 + ΔH and speed u = u0 + Δu, with ρ(H); the kinematic u0 entries of Eq. (1) (row Δw
/// column q, row ΔH column Δθ, and the Mẇ·u0 of row q) stay at the reference u0. The run ends at
/// touchdown, stall, the time limit, or when the state stops being finite (diverged).

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "engine/common/describe.h"
#include "engine/disturbance/disturbance_options.h"
#include "engine/dynamics/longitudinal_model.h"
#include "engine/simulation/integrator.h"
#include "engine/simulation/lanes_isa.h"

namespace gesweep {

/// The shape of the elevator input δe(t) (positive trailing edge down, docs/model.md §1).
enum class ElevatorInputKind {
  kNone,     ///< δe = 0
  kPulse,    ///< amplitude on [start, start + duration), 0 elsewhere (the paper: +5° for 0.2 s)
  kStep,     ///< amplitude from start on
  kDoublet,  ///< +amplitude on [start, start + duration), −amplitude on [start + duration, start +
             ///< 2·duration)
};

/// Names in study files, flags and output: "pulse", "step", "doublet", "none".
GESWEEP_ENUM_NAMES(ElevatorInputKind, {kPulse, "pulse"}, {kStep, "step"}, {kDoublet, "doublet"},
                   {kNone, "none"});

/// A piecewise-constant elevator input. Its jumps are the integrator's breakpoints.
struct ElevatorInput {
  ElevatorInputKind kind = ElevatorInputKind::kPulse;
  double amplitude_rad = 5.0 * 3.14159265358979323846 / 180.0;  ///< the paper's +5°
  double start_s = 0.0;     ///< time of the first jump, s, ≥ 0 (the run starts at t = 0)
  double duration_s = 0.2;  ///< pulse length, or length of each half of a doublet, s, > 0
};

/// The input as breakpoints and one value per segment (Integrate's convention: segment k is
/// [b_{k-1}, b_k)); values.size() == breakpoints.size() + 1.
struct ElevatorSchedule {
  std::vector<double> breakpoints_s;
  std::vector<double> elevator_rad;
};
/// The schedule of an input (no validation; see ValidateOpenLoopConfig).
ElevatorSchedule MakeElevatorSchedule(const ElevatorInput& input);

/// Offsets added to the initial state (which is otherwise the reference, x = 0), SI units.
struct InitialOffsets {
  double delta_speed_mps = 0;            ///< Δu(0)
  double delta_normal_velocity_mps = 0;  ///< Δw(0), positive down
  double pitch_rate_radps = 0;           ///< q(0)
  double delta_pitch_rad = 0;            ///< Δθ(0)
  double delta_height_m = 0;             ///< ΔH(0): the derivatives see H0 + ΔH(0)
};

/// One open-loop run.
struct OpenLoopConfig {
  double start_height_m = 0;       ///< H0, m; must be above the touchdown height
  double reference_speed_mps = 0;  ///< u0, m/s; must be above the stall speed
  ElevatorInput elevator;
  InitialOffsets initial_offsets;
  double duration_s = 300.0;  ///< time limit, s, > 0
  /// Method, step, tolerances, breakpoints (integrator.h). Its output_interval_s is ignored: use
  /// series_interval_s.
  IntegratorOptions integrator;
  /// > 0: record the time series every series_interval_s seconds (and at the end); 0: summary only.
  double series_interval_s = 0.0;
  /// true: A and B frozen at (H0, u0) for the whole run (the classical linear response; the floor
  /// of the performance target). false (docs/model.md §7): re-evaluated at every stage.
  bool freeze_derivatives = false;
  /// true: always evaluate the derivatives through LongitudinalModel::DerivativesAt (IsaDensity
  /// and the coefficient table), as PCHIP interpolation does anyway; false: the per-segment fast
  /// path (derivative_kernel.h) when the interpolation is linear.
  bool generic_derivative_path = false;
  std::optional<double> stall_speed_mps;     ///< default: the aircraft's stall speed, m/s
  std::optional<double> touchdown_height_m;  ///< default: the aircraft's wheel-contact height, m
  /// The moving atmosphere (docs/model.md §9); the default is still air, where the run is the one
  /// above bit for bit. With a mean wind the run starts in its equilibrium: Δu(0) = W(H0) +
  /// initial_delta_u_mps, so that the airspeed is u0 + initial_delta_u_mps. The span of the
  /// pitch-rate gust is the aircraft's.
  DisturbanceOptions disturbance;
  /// The run's turbulence is RunNoise(seed, run_index) (docs/disturbance.md); a sweep sets both.
  std::uint64_t seed = 0;
  std::uint64_t run_index = 0;

  /// The settings a person gives (describe.h): [analyses.open_loop] and the flags of `gesweep
  /// simulate`. The start condition, the input's amplitude and length are a sweep's run parameters
  /// of the same names (RunParameter: the catalogue's entries of the input are these fields), so they
  /// are flags only; so are the initial offsets.
  template <class V>
  void Describe(V& v) {
    v(Field("height_m", &start_height_m)
          .Unit("m")
          .Limit("height_m")
          .RunParameter()
          .Doc(
              "Start height H0 of the mean chord above ground, m; must be above the aircraft's wheel-contact "
              "height: starts on or below it are refused"));
    v(Field("speed_mps", &reference_speed_mps)
          .Unit("m/s")
          .Limit("speed_mps")
          .RunParameter()
          .Doc("Reference speed u0, m/s; must be above the stall speed"));
    v(Field("input", &elevator.kind).Doc("Elevator input: pulse, step, doublet or none"));
    v(Field("pulse_amplitude_deg", &elevator.amplitude_rad)
          .Unit("deg")
          .Scale(kRadiansPerDegree)
          .Limit("pulse_amplitude_deg")
          .RunParameter()
          .Doc("Elevator pulse amplitude, positive trailing edge down (paper: 5 deg)"));
    v(Field("pulse_duration_s", &elevator.duration_s)
          .Unit("s")
          .Limit("pulse_duration_s")
          .RunParameter()
          .Doc("Elevator pulse duration (paper: 0.2 s)"));
    v(Field("input_start_s", &elevator.start_s)
          .Unit("s")
          .Limit("open_loop.input_start_s")
          .Doc("Time of the input's first jump, s"));
    v(Field("duration_s", &duration_s)
          .Unit("s")
          .Limit("open_loop.duration_s")
          .Doc("Time limit of each run, s"));
    integrator.Describe(v);
    v(Field("freeze_derivatives", &freeze_derivatives)
          .Doc("Freeze A and B at the start condition (the classical linear response) instead of "
               "re-evaluating "
               "them (docs/model.md section 7)"));
    v(Field("initial_delta_u_mps", &initial_offsets.delta_speed_mps)
          .Unit("m/s")
          .Limit("open_loop.initial_delta_u_mps")
          .CommandLineOnly()
          .Doc("Initial offset of u, m/s"));
    v(Field("initial_delta_w_mps", &initial_offsets.delta_normal_velocity_mps)
          .Unit("m/s")
          .Limit("open_loop.initial_delta_w_mps")
          .CommandLineOnly()
          .Doc("Initial offset of w (positive down), m/s"));
    v(Field("initial_pitch_rate_degps", &initial_offsets.pitch_rate_radps)
          .Unit("deg/s")
          .Scale(kRadiansPerDegree)
          .Limit("open_loop.initial_pitch_rate_degps")
          .CommandLineOnly()
          .Doc("Initial pitch rate, deg/s"));
    v(Field("initial_pitch_deg", &initial_offsets.delta_pitch_rad)
          .Unit("deg")
          .Scale(kRadiansPerDegree)
          .Limit("open_loop.initial_pitch_deg")
          .CommandLineOnly()
          .Doc("Initial offset of the pitch angle, deg"));
    v(Field("initial_delta_h_m", &initial_offsets.delta_height_m)
          .Unit("m")
          .Limit("open_loop.initial_delta_h_m")
          .CommandLineOnly()
          .Doc("Initial offset of H, m (the derivatives see H0 + offset)"));
    disturbance.Describe(v);
  }
};

/// Throws InputError(source, <field>, value, expectation) when a field is out of range: the limits
/// table (engine/common/input_limits.h: height_m, speed_mps, open_loop.*, output_dt_s, the
/// tolerances), H0 not above the touchdown height, u0 + Δu(0) not above the stall speed, a pulse
/// length ≤ 0, more than kMaximumStepsPerRun steps (duration_s / step_s for RK4, duration_s /
/// max_step_s for dopri5 with a largest step), integrator options (ValidateIntegratorOptions).
void ValidateOpenLoopConfig(const LongitudinalModel& model, const OpenLoopConfig& config,
                            const std::string& source);

/// The work a run of `config` takes before and while it flies, checked against the limits table's
/// bounds on work (engine/common/input_limits.h): at most kMaximumNoiseSamplesPerRun held noise
/// samples with turbulence (duration_s / turbulence_sample_interval_s), and at most
/// kMaximumRunMemoryBytes for its noise table and its series. Throws InputError(source, <field>, ...)
/// naming the numbers. Needs no model: a sweep calls it on the design's extreme runs before the
/// first one (Analysis::CheckRun); ValidateOpenLoopConfig calls it too.
void CheckOpenLoopWork(const OpenLoopConfig& config, const std::string& source);

/// How a run ended (docs/model.md §7).
enum class OpenLoopEndEvent {
  kTouchdown,  ///< H fell to the touchdown (wheel-contact) height
  kStall,      ///< u fell to the stall speed
  kTimeLimit,  ///< duration_s reached
  kDiverged,   ///< the state became non-finite (or the adaptive step underflowed)
};
// With a disturbance, kStall is the airspeed u0 + Δu − u_g falling to the stall speed.

/// "touchdown" / "stall" / "time_limit" / "diverged", in code order (the archive's levels).
GESWEEP_ENUM_NAMES(OpenLoopEndEvent, {kTouchdown, "touchdown"}, {kStall, "stall"}, {kTimeLimit, "time_limit"},
                   {kDiverged, "diverged"});

/// The components of Eq. (1)'s state x = [Δu, Δw, q, Δθ, ΔH] as result columns.
inline constexpr FieldComponent kStateComponents[] = {{"delta_u_mps", "m/s", "Delta u"},
                                                      {"delta_w_mps", "m/s", "Delta w"},
                                                      {"pitch_rate_radps", "rad/s", "q"},
                                                      {"delta_theta_rad", "rad", "Delta theta"},
                                                      {"delta_h_m", "m", "Delta H"}};

/// The summary of one run. The state is x = [Δu m/s, Δw m/s, q rad/s, Δθ rad, ΔH m] (docs/model.md §1).
struct OpenLoopSummary {
  OpenLoopEndEvent end_event = OpenLoopEndEvent::kTimeLimit;
  double end_time_s = 0;         ///< time of the end event (touchdown and stall located inside the step)
  double min_height_m = 0;       ///< lowest H: at step ends, and local minima located inside steps
  double min_height_time_s = 0;  ///< when it occurred
  double max_abs_pitch_rate_radps = 0;      ///< largest |q| at the initial point and step ends
  Vector5d final_state = Vector5d::Zero();  ///< x at end_time_s (the last finite state if diverged)
  double final_height_m = 0;                ///< H0 + ΔH at end_time_s
  double final_speed_mps = 0;               ///< u0 + Δu at end_time_s
  long steps = 0;                           ///< accepted steps
  long rejected_steps = 0;                  ///< rejected dopri5 trials
  long rhs_calls = 0;                       ///< right-hand-side evaluations
  std::string message;                      ///< empty, or what went wrong numerically
  /// The run was stopped by its cancellation flag before it ended: the fields above describe the
  /// part flown (end_time_s is where it stopped) and end_event means nothing.
  bool cancelled = false;

  /// The final state components the archive stores (Δu and ΔH are in final_speed_mps, final_height_m).
  static constexpr int kStoredFinalState[] = {kDeltaW, kDeltaTheta, kPitchRate};

  /// The results (describe.h): archive columns results/open_loop/<key>, simulate's CSV and JSON.
  template <class V>
  void Describe(V& v) {
    v(Field("end_event", &end_event)
          .Stored(StoredAs::kInt8)
          .Doc("How the run ended (levels attribute, docs/model.md §7)"));
    v(Field("end_time_s", &end_time_s).Unit("s").Doc("Time of the end event"));
    v(Field("min_height_m", &min_height_m).Unit("m").Doc("Lowest height H reached"));
    v(Field("min_height_time_s", &min_height_time_s).Unit("s").Doc("When the lowest height was reached"));
    v(Field("max_abs_pitch_rate_radps", &max_abs_pitch_rate_radps).Unit("rad/s").Doc("Largest |q|"));
    v(Field("final_height_m", &final_height_m).Unit("m").Doc("H at the end of the run"));
    v(Field("final_speed_mps", &final_speed_mps).Unit("m/s").Doc("u at the end of the run"));
    v(Field("final_state", &final_state)
          .Components(kStateComponents, "final_", kStoredFinalState)
          .Doc("at the end of the run"));
    v(Field("steps", &steps).Stored(StoredAs::kInt32).Doc("Accepted integration steps"));
    v(Field("rejected_steps", &rejected_steps).NotStored().Doc("Rejected dopri5 trial steps"));
    v(Field("rhs_calls", &rhs_calls).Stored(StoredAs::kInt32).Doc("Right-hand-side evaluations"));
    v(Field("message", &message).NotStored().Doc("Empty, or what went wrong numerically"));
  }
};

/// The time series, one entry per sample (every series_interval_s and at the end), SI units.
struct OpenLoopSeries {
  std::vector<double> time_s;
  std::vector<double> delta_speed_mps;
  std::vector<double> delta_normal_velocity_mps;
  std::vector<double> pitch_rate_radps;
  std::vector<double> delta_pitch_rad;
  std::vector<double> delta_height_m;
  std::vector<double> height_m;
  std::vector<double> speed_mps;
  std::vector<double> elevator_rad;  ///< the input the step producing the sample used
  /// The air motion the airplane met (docs/model.md §9), only when the run has a disturbance (else
  /// empty): u_g (mean wind + turbulence + a u gust, positive forward: a headwind is negative) and
  /// w_g (positive down), m/s; q_g, rad/s, only with the pitch-rate gust.
  std::vector<double> u_g_mps;
  std::vector<double> w_g_mps;
  std::vector<double> q_g_radps;

  /// Which optional quantities the series has: the air motion only when the run had a disturbance.
  SeriesContents contents() const { return {!u_g_mps.empty(), !q_g_radps.empty()}; }

  /// The quantities (engine/common/series.h): series/open_loop/<key> in the archive (those stored),
  /// simulate's CSV and JSON, gesweep.simulate's series. The state's keys are kStateComponents'.
  template <class V>
  static void DescribeSeries(V& v) {
    using S = OpenLoopSeries;
    v(SeriesField("time_s", &S::time_s).Unit("s").Axis().Doc("Time since the start of the run"));
    v(SeriesField("height_m", &S::height_m).Unit("m").Doc("Height H"));
    v(SeriesField("speed_mps", &S::speed_mps).Unit("m/s").Doc("Speed u"));
    v(SeriesField("delta_u_mps", &S::delta_speed_mps).Unit("m/s").NotStored().Doc("Delta u"));
    v(SeriesField("delta_w_mps", &S::delta_normal_velocity_mps).Unit("m/s").Doc("Delta w (positive down)"));
    v(SeriesField("pitch_rate_radps", &S::pitch_rate_radps).Unit("rad/s").Doc("Pitch rate q"));
    v(SeriesField("delta_theta_rad", &S::delta_pitch_rad).Unit("rad").Doc("Delta theta"));
    v(SeriesField("delta_h_m", &S::delta_height_m).Unit("m").NotStored().Doc("Delta H"));
    v(SeriesField("elevator_rad", &S::elevator_rad)
          .Unit("rad")
          .Doc("Elevator deflection (positive trailing edge down)"));
    DescribeAirMotion<S>(v);
  }
};

/// A run's result: the summary, and the series when series_interval_s > 0 (else empty).
struct OpenLoopResult {
  OpenLoopSummary summary;
  OpenLoopSeries series;
};

/// Runs docs/model.md §7 once. Validates the config (throws InputError, source "open-loop config");
/// numerical outcomes (stall, divergence) are in the summary, never thrown. Allocates only the
/// series (reserved before the run) and the per-run tables; nothing per step. `cancel` (may be
/// null) is read before every step: once true the run stops there with summary.cancelled.
OpenLoopResult SimulateOpenLoop(const LongitudinalModel& model, const OpenLoopConfig& config,
                                const std::atomic<bool>* cancel = nullptr);

/// One run of a batch: its model (which outlives the call) and its settings.
struct OpenLoopBatchRun {
  const LongitudinalModel* model = nullptr;
  OpenLoopConfig config;
};

/// The lane widths SimulateOpenLoopBatch takes.
inline constexpr int kOpenLoopBatchWidths[] = {1, 2, 4, 8};

/// Whether SimulateOpenLoopBatch flies `config` in its lanes: fixed-step RK4 honouring the
/// breakpoints, linear interpolation on the per-segment table (not the generic path, not frozen), still
/// air, no series. Any other run is flown by SimulateOpenLoop, one at a time.
bool OpenLoopRunUsesLanes(const LongitudinalModel& model, const OpenLoopConfig& config);

/// SimulateOpenLoop for every run, in order: result i is SimulateOpenLoop(*runs[i].model,
/// runs[i].config, cancel) bit for bit, whatever the width and whichever runs share a batch
/// (tests/simulation/open_loop_batch_test.cc). The runs that OpenLoopRunUsesLanes are flown `width`
/// at a time in lockstep (docs/performance.md, "Batched time responses"): one RK4 step of every lane
/// at once, each lane on its own time grid, breakpoints and events; a lane whose run ends takes the
/// next run. width: one of kOpenLoopBatchWidths (GESWEEP_DEMAND). isa: the instruction set of the
/// lanes' arithmetic, one this CPU runs (GESWEEP_DEMAND, LanesIsaSupported); by default
/// ChooseLanesIsa(width): GESWEEP_LANES_ISA when it is set, else the widest that fits the width (every
/// choice gives the same results). Validates every config first (throws the first InputError, source
/// "open-loop config", before any run is flown; ChooseLanesIsa's before that).
std::vector<OpenLoopResult> SimulateOpenLoopBatch(std::span<const OpenLoopBatchRun> runs, int width,
                                                  const std::atomic<bool>* cancel = nullptr,
                                                  std::optional<LanesIsa> isa = std::nullopt);

}  // namespace gesweep
