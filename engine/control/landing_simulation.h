#pragma once
/// The closed-loop automatic landing of docs/model.md §8 (paper Section III, Fig. 6–9): glide-slope
/// coupler, then the exponential flare, one constant LQR gain for both, flown on the same re-evaluated
/// plant as the open-loop run (docs/model.md §7: derivatives at the current H and u with ρ(H), kinematic
/// entries at u0), with or without h-derivatives as the plant model's options say. Integrated by the
/// adaptive Dormand–Prince 5(4) of engine/simulation (the paper's ode45, rtol 1e-3); the flare switch
/// and touchdown are events located in time. docs/landing.md describes every convention.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "engine/common/describe.h"
#include "engine/control/landing_config.h"
#include "engine/control/landing_design.h"
#include "engine/dynamics/longitudinal_model.h"
#include "engine/simulation/lanes_isa.h"

namespace gesweep {

/// How a landing ended.
enum class LandingOutcome {
  kLanded,        ///< H fell to the wheel-contact height
  kNoTouchdown,   ///< the time limit was reached in flight
  kStall,         ///< u fell to the aircraft's stall speed
  kDiverged,      ///< |Δθ| passed divergence_pitch_deg, or the state stopped being finite
  kDesignFailed,  ///< the LQR design had no stabilising solution (nothing was flown)
};

/// "landed" / "no_touchdown" / "stall" / "diverged" / "design_failed", in code order (the archive's
/// levels).
GESWEEP_ENUM_NAMES(LandingOutcome, {kLanded, "landed"}, {kNoTouchdown, "no_touchdown"}, {kStall, "stall"},
                   {kDiverged, "diverged"}, {kDesignFailed, "design_failed"});

/// Phase of the landing.
enum class LandingPhase { kGlideSlope = 0, kFlare = 1 };
/// "glide_slope" / "flare".
GESWEEP_ENUM_NAMES(LandingPhase, {kGlideSlope, "glide_slope"}, {kFlare, "flare"});

/// One sample of the time series (SI units; angles in rad).
struct LandingSample {
  double time_s = 0;
  LandingPhase phase = LandingPhase::kGlideSlope;
  double height_m = 0;              ///< H of the mean chord above ground
  double reference_height_m = 0;    ///< the glide path's height, or H_ref in the flare
  double tracking_error_m = 0;      ///< e = H − reference: d before the flare, H − H_ref after
  double speed_mps = 0;             ///< u = u0 + Δu
  double delta_w_mps = 0;           ///< Δw, positive down
  double pitch_rate_radps = 0;      ///< q
  double pitch_rad = 0;             ///< θ = Δθ (the reference flight is level)
  double sink_rate_mps = 0;         ///< −Ḣ = Δw − u0·Δθ, positive down
  double elevator_rad = 0;          ///< δe, the actuator's position
  double elevator_command_rad = 0;  ///< ηe = −K·z before the limits
  double compensator = 0;           ///< x_c, m·s
  double error_integral = 0;        ///< ε_c, m·s
  /// Along-track distance past the glide-slope transmitter, m: u0·(t − t_transmitter) in still air,
  /// the ground position x_g − (H0 − d0)/γ in a moving atmosphere.
  double distance_past_transmitter_m = 0;
  /// The air motion the airplane met (docs/model.md §9; 0 in still air): u_g, w_g (m/s), q_g (rad/s).
  double u_g_mps = 0;
  double w_g_mps = 0;
  double q_g_radps = 0;

  /// The quantities (engine/common/series.h): series/landing/<key> in the archive (those stored),
  /// `gesweep land`'s CSV and JSON, gesweep.land's series; SI, angles in radians.
  template <class V>
  static void DescribeSeries(V& v) {
    using S = LandingSample;
    v(SeriesField("time_s", &S::time_s).Unit("s").Axis().Doc("Time since the start of the landing"));
    v(SeriesField("height_m", &S::height_m).Unit("m").Doc("Height H of the mean chord above ground"));
    v(SeriesField("reference_height_m", &S::reference_height_m)
          .Unit("m")
          .Doc("Height of the glide path, or H_ref in the flare"));
    v(SeriesField("tracking_error_m", &S::tracking_error_m).Unit("m").Doc("H minus the reference"));
    v(SeriesField("distance_past_transmitter_m", &S::distance_past_transmitter_m)
          .Unit("m")
          .Doc("Along-track distance past the glide-slope transmitter: u0 (t - t_transmitter) in still "
               "air, the ground position with a disturbance"));
    v(SeriesField("speed_mps", &S::speed_mps).Unit("m/s").Doc("Speed u"));
    v(SeriesField("delta_w_mps", &S::delta_w_mps).Unit("m/s").Doc("Delta w, positive down"));
    v(SeriesField("pitch_rate_radps", &S::pitch_rate_radps).Unit("rad/s").Doc("Pitch rate q"));
    v(SeriesField("pitch_rad", &S::pitch_rad).Unit("rad").Doc("Pitch angle theta"));
    v(SeriesField("sink_rate_mps", &S::sink_rate_mps).Unit("m/s").Doc("Sink rate -dH/dt, positive down"));
    v(SeriesField("elevator_rad", &S::elevator_rad)
          .Unit("rad")
          .Doc("Elevator deflection (actuator position)"));
    v(SeriesField("elevator_command_rad", &S::elevator_command_rad)
          .Unit("rad")
          .Doc("Elevator command before the limits"));
    v(SeriesField("phase", &S::phase).Doc("0 glide slope, 1 flare"));
    v(SeriesField("compensator_m_s", &S::compensator).Unit("m s").NotStored().Doc("Compensator state x_c"));
    v(SeriesField("error_integral_m_s", &S::error_integral)
          .Unit("m s")
          .NotStored()
          .Doc("Integral of the tracking error epsilon_c"));
    DescribeAirMotion<S>(v);
  }
};

/// Which optional quantities a landing flown with `config` has in its series (CSV, JSON, Python):
/// the air motion with a moving atmosphere, q_g with the pitch-rate gust.
SeriesContents LandingSeriesContents(const LandingConfig& config);

/// The result of one landing. Quantities that did not occur (no touchdown, no flare) are NaN.
struct LandingResult {
  LandingOutcome outcome = LandingOutcome::kDesignFailed;
  std::string message;                        ///< one sentence on how the run ended
  LandingDesign design;                       ///< the gain and what it was designed on
  double flare_time_constant_s = 0;           ///< τ used
  double flare_height_m = 0;                  ///< Ho used
  double glide_slope_deg = 0;                 ///< γ used
  double plant_fixed_reference_height_m = 0;  ///< ΔH reference used with PlantHeightReference::kFixedHeight
  bool plant_h_derivatives = true;            ///< the plant's option
  double time_limit_s = 0;                    ///< the time limit used (LandingTimeLimit)

  double touchdown_time_s = 0;
  /// Along-track distance from the glide-slope transmitter (where the glide path meets H = 0) to the
  /// touchdown point, m, positive past it; along-track motion at u0, as in the kinematics of Eq. (1).
  double touchdown_distance_past_transmitter_m = 0;
  double touchdown_sink_rate_mps = 0;         ///< −Ḣ at touchdown, positive down
  double touchdown_pitch_deg = 0;             ///< θ at touchdown
  double touchdown_speed_mps = 0;             ///< u at touchdown (inertial: the ground speed)
  double touchdown_airspeed_mps = 0;          ///< u0 + Δu − u_g at touchdown (= u in still air)
  double flare_start_time_s = 0;              ///< when H fell to Ho
  double glide_path_error_at_flare_m = 0;     ///< d at the flare switch, positive above the path
  double max_abs_elevator_deg = 0;            ///< max |δe| (actuator position) over steps and samples
  double max_abs_elevator_command_deg = 0;    ///< max |ηe| before the limits
  double max_abs_pitch_rate_degps = 0;        ///< max |q| over steps and samples
  double flare_max_abs_elevator_deg = 0;      ///< max |δe| in the flare phase (NaN without a flare)
  double flare_max_abs_pitch_rate_degps = 0;  ///< max |q| in the flare phase (NaN without a flare)
  double saturated_time_s = 0;                ///< total time the command was beyond a limit (located events)
  double longest_saturation_s = 0;            ///< longest single interval of saturation
  double min_speed_mps = 0;                   ///< lowest u over steps and samples
  double max_speed_mps = 0;                   ///< highest u over steps and samples
  double final_time_s = 0;                    ///< end of the run
  double final_height_m = 0;                  ///< H at the end

  long accepted_steps = 0;
  long rejected_steps = 0;
  long rhs_calls = 0;
  /// The run was stopped by its cancellation flag before it ended: `outcome` means nothing and the
  /// other fields describe the part flown.
  bool cancelled = false;

  /// Every output_interval_s and at the end (empty when output_interval_s = 0).
  std::vector<LandingSample> series;

  /// The summary (describe.h): archive columns results/landing/<key> (the gain, a 9-wide column, is
  /// declared beside them) and `gesweep land`'s CSV and JSON summary (the design beside it). The
  /// archive's order is the columns' as they were added; the fields the output leaves out sit where
  /// the output's order is unchanged by them.
  template <class V>
  void Describe(V& v) {
    v(Field("outcome", &outcome).Stored(StoredAs::kInt8).Doc("How the landing ended (levels attribute)"));
    v(Field("message", &message).NotStored().Doc("One sentence on how the run ended"));
    v(Field("touchdown_time_s", &touchdown_time_s)
          .Unit("s")
          .Doc("Time of touchdown (NaN when there was none)"));
    v(Field("touchdown_distance_past_transmitter_m", &touchdown_distance_past_transmitter_m)
          .Unit("m")
          .Doc("Along-track distance from the glide-slope transmitter to the touchdown point, positive past "
               "it"));
    v(Field("touchdown_sink_rate_mps", &touchdown_sink_rate_mps)
          .Unit("m/s")
          .Doc("Sink rate -dH/dt at touchdown, positive down"));
    v(Field("touchdown_pitch_deg", &touchdown_pitch_deg).Unit("deg").Doc("Pitch angle at touchdown"));
    v(Field("touchdown_speed_mps", &touchdown_speed_mps).Unit("m/s").Doc("Speed at touchdown"));
    v(Field("flare_start_time_s", &flare_start_time_s)
          .Unit("s")
          .Doc("When H fell to the flare height (NaN when it did not)"));
    v(Field("glide_path_error_at_flare_m", &glide_path_error_at_flare_m)
          .Unit("m")
          .Doc("Glide-path deviation d at the flare switch, positive above"));
    v(Field("max_abs_elevator_deg", &max_abs_elevator_deg)
          .Unit("deg")
          .Doc("Largest |elevator deflection| (actuator position)"));
    v(Field("max_abs_elevator_command_deg", &max_abs_elevator_command_deg)
          .Unit("deg")
          .Doc("Largest |elevator command| before the limits"));
    v(Field("max_abs_pitch_rate_degps", &max_abs_pitch_rate_degps).Unit("deg/s").Doc("Largest |q|"));
    v(Field("saturated_time_s", &saturated_time_s)
          .Unit("s")
          .Doc("Total time the elevator command was beyond a limit"));
    v(Field("longest_saturation_s", &longest_saturation_s)
          .Unit("s")
          .Doc("Longest single interval of saturation"));
    v(Field("min_speed_mps", &min_speed_mps).Unit("m/s").Doc("Lowest speed"));
    v(Field("max_speed_mps", &max_speed_mps).Unit("m/s").Doc("Highest speed"));
    v(Field("final_time_s", &final_time_s).Unit("s").Doc("End of the run"));
    v(Field("final_height_m", &final_height_m).Unit("m").Doc("H at the end of the run"));
    // What the run used (the output has them in its run and design objects).
    v(Field("flare_time_constant_s", &flare_time_constant_s)
          .Unit("s")
          .NotInOutput()
          .Doc("Flare time constant tau used"));
    v(Field("time_limit_s", &time_limit_s).Unit("s").NotInOutput().Doc("Time limit used"));
    v(Field("design_height_m", &design.design_height_m)
          .Unit("m")
          .NotInOutput()
          .Doc("Height of the linear model the gain was designed on"));
    v(Field("closed_loop_max_real_per_s", &design.closed_loop_max_real_per_s)
          .Unit("1/s")
          .NotInOutput()
          .Doc("Largest real part of the design model's closed-loop eigenvalues"));
    v(Field("touchdown_airspeed_mps", &touchdown_airspeed_mps)
          .Unit("m/s")
          .Doc("Airspeed u0 + Delta u - u_g at touchdown (the speed in still air)"));
    v(Field("flare_max_abs_elevator_deg", &flare_max_abs_elevator_deg)
          .Unit("deg")
          .Doc("Largest |elevator deflection| in the flare phase (NaN without a flare)"));
    v(Field("flare_max_abs_pitch_rate_degps", &flare_max_abs_pitch_rate_degps)
          .Unit("deg/s")
          .Doc("Largest |q| in the flare phase (NaN without a flare)"));
    // The accepted steps are the column accepted_steps and the output's steps.
    v(Field("accepted_steps", &accepted_steps).Stored(StoredAs::kInt32).NotInOutput().Doc("Accepted steps"));
    v(Field("steps", &accepted_steps).NotStored().Doc("Accepted steps"));
    v(Field("rejected_steps", &rejected_steps).NotStored().Doc("Rejected trial steps"));
    v(Field("rhs_calls", &rhs_calls).Stored(StoredAs::kInt32).Doc("Right-hand-side evaluations"));
  }
};

/// The settings a landing flew: `config` with each automatic setting (NaN) replaced by the value
/// `result` used (flare time constant, time limit, design height and speed, plant reference height).
LandingConfig SettingsUsed(const LandingConfig& config, const LandingResult& result);

/// A landing in flight, saved between two steps: what ResumeLanding needs to fly it on. The design, the
/// extremes and the flare so far are in `result` (the part flown); the rest is the integrator's state
/// and the flare's and the saturation's bookkeeping, opaque to a caller.
struct LandingCheckpoint {
  /// The phase, and what the flare switch and the saturation bookkeeping keep, of a landing in flight.
  struct Flight {
    LandingPhase phase = LandingPhase::kGlideSlope;
    double flare_start_s = 0;
    double compensator_at_flare = 0;
    double integral_at_flare = 0;
    bool saturated = false;
    double saturated_since_s = 0;
  };
  double time_s = 0;
  LandingResult result;
  std::vector<double> state;
  Flight flight;
};

/// What an observer of a landing sees after each accepted step (and at the start): the time, the
/// height, the sink rate and the phase, and a checkpoint on demand (a copy of the landing so far).
class LandingStep {
 public:
  using Save = LandingCheckpoint (*)(const void* context);
  LandingStep(double time_s, double height_m, double sink_rate_mps, LandingPhase phase, Save save,
              const void* context)
      : time_s_(time_s),
        height_m_(height_m),
        sink_rate_mps_(sink_rate_mps),
        phase_(phase),
        save_(save),
        context_(context) {}
  double time_s() const { return time_s_; }
  double height_m() const { return height_m_; }
  double sink_rate_mps() const { return sink_rate_mps_; }
  LandingPhase phase() const { return phase_; }
  /// The landing at this step, to fly on from with ResumeLanding.
  LandingCheckpoint Checkpoint() const { return save_(context_); }

 private:
  double time_s_;
  double height_m_;
  double sink_rate_mps_;
  LandingPhase phase_;
  Save save_;
  const void* context_;
};

/// Called after every accepted step of a landing (RK4: every grid point of the noise), at its start
/// and at the touchdown or other stopping event. A splitting estimator reads the state here, saves
/// checkpoints and stops a run through the cancellation flag it passed.
using LandingObserver = std::function<void(const LandingStep&)>;

/// Designs the gain (DesignLandingController) and flies the landing on `plant`. Validates `config`
/// (throws InputError with source "landing config"); numerical outcomes are in the result, never thrown.
/// `cancel` (may be null) is read before every integration step: once true the run stops there with
/// result.cancelled.
/// `noise_point` (may be empty): the run's noise as a point of the standard-normal space
/// (RunNoise(point), engine/disturbance/run_noise.h) instead of RunNoise(seed, run_index); it must
/// hold at least LandingNoiseDimension values (InputError otherwise). A subset simulation flies it.
/// `observer` (may be null) sees every step (LandingObserver).
LandingResult SimulateLanding(const LongitudinalModel& plant, const LandingConfig& config,
                              const std::atomic<bool>* cancel = nullptr,
                              std::span<const double> noise_point = {},
                              const LandingObserver* observer = nullptr);

/// Flies on the landing saved in `from` (LandingStep::Checkpoint of a landing of the same plant and
/// config, but for the seed, run index and noise point) to its end, with the noise of `config`'s
/// (seed, run index) or of `noise_point` from the checkpoint's time on: the noise held before it is
/// not read, so a landing resumed with other noise is a branch of the saved one (docs/dispersion.md,
/// "Splitting with restarts"). With the saved landing's own noise a turbulent RK4 landing is the
/// unbroken one bit for bit: its steps end on the noise's breakpoints whatever time they start from
/// (the extremes, also read on an output grid that restarts at the checkpoint, may differ in the last
/// digits; a dopri5 landing restarts its step control). Without a series it is integrated in windows
/// of a few seconds, each with its own noise table. Steps and right-hand sides count the part flown
/// here. Throws InputError for a config SimulateLanding refuses, or for a checkpoint whose
/// state does not fit the config (still air against a moving atmosphere).
LandingResult ResumeLanding(const LongitudinalModel& plant, const LandingConfig& config,
                            const LandingCheckpoint& from, const std::atomic<bool>* cancel = nullptr,
                            std::span<const double> noise_point = {},
                            const LandingObserver* observer = nullptr);

/// The dimension of a landing's noise point: the initial state and every held sample up to the
/// landing's time limit (LandingTimeLimit) and one more; 0 without turbulence (the landing then draws
/// no noise). Validates `config` as SimulateLanding does.
std::uint64_t LandingNoiseDimension(const Aircraft& aircraft, const LandingConfig& config);

/// One landing of a batch (SimulateLandingBatch): its plant (never null), settings and noise point
/// (as SimulateLanding's; may be empty).
struct LandingBatchRun {
  const LongitudinalModel* plant = nullptr;
  LandingConfig config;
  std::span<const double> noise_point;
};

/// Whether SimulateLandingBatch flies `config` in its lanes: a landing in Dryden turbulence (σ_w > 0)
/// flown by RK4 at the noise's sample interval (turbulent_integrator = rk4, breakpoints honoured), on
/// a plant with linear interpolation, without a discrete gust.
bool LandingRunUsesLanes(const LongitudinalModel& plant, const LandingConfig& config);

/// The landings of `runs`, each result bit for bit SimulateLanding's for that run (every field and
/// every sample of its series), whatever the width, the instruction set and whichever runs share the
/// batch (tests/control/landing_batch_test.cc). The runs that LandingRunUsesLanes are flown `width` at
/// a time in lockstep (docs/performance.md, "The turbulent landing in lanes"): one RK4 step of every
/// lane at once, each lane's events, outputs and flare switch through its own landing's problem in
/// scalar code, and a lane whose landing ended takes the next one; the others are flown by
/// SimulateLanding in place. width: 1, 2, 4 or 8 (GESWEEP_DEMAND). isa: as SimulateOpenLoopBatch's
/// (engine/simulation/open_loop.h). `cancel` as SimulateLanding's, read before every step of the
/// batch. Throws SimulateLanding's InputError for the first run that has one, before any is flown.
std::vector<LandingResult> SimulateLandingBatch(std::span<const LandingBatchRun> runs, int width,
                                                const std::atomic<bool>* cancel = nullptr,
                                                std::optional<LanesIsa> isa = std::nullopt);

}  // namespace gesweep
