#pragma once
/// Parameters of the automatic landing of docs/model.md §8 (the paper's Section III, after Stevens &
/// Lewis): start state, glide path, LQR design, flare, elevator limits, plant convention and
/// integration. Every field has a documented default; docs/landing.md explains each choice.

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>

#include "engine/aircraft/aircraft.h"
#include "engine/common/describe.h"
#include "engine/disturbance/disturbance_options.h"
#include "engine/simulation/integrator.h"

namespace gesweep {

/// Number of states of the paper's augmented glide-slope system, Eq. (14).
inline constexpr int kLandingStateCount = 9;

/// The states of Eq. (14) in order, as used for weights and gains, with their units.
inline constexpr FieldComponent kLandingStates[kLandingStateCount] = {
    {"delta_u", "m/s", "Speed perturbation"},
    {"delta_w", "m/s", "Normal-velocity perturbation, positive down"},
    {"pitch_rate", "rad/s", "Pitch rate q"},
    {"delta_theta", "rad", "Pitch-angle perturbation"},
    {"delta_h", "m", "Height perturbation"},
    {"elevator", "rad", "Elevator deflection (actuator state)"},
    {"deviation", "m", "Deviation d from the reference path, positive above"},
    {"compensator", "m s", "Compensator state x_d"},
    {"error_integral", "m s", "Integral eps_d of the path error r_d - d"}};

/// The names of kLandingStates in order: delta_u, delta_w, pitch_rate, delta_theta, delta_h,
/// elevator, deviation, compensator, error_integral.
const std::array<std::string_view, kLandingStateCount>& LandingStateNames();

/// What the ΔH that multiplies Xh, Zh, Mh in the plant is measured from (docs/landing.md §3).
enum class PlantHeightReference {
  /// The reference trajectory: the glide path before the flare, the flare's H_ref after it. Eq. (1) is
  /// linearised about the commanded flight, so ΔH is the deviation d (or H − H_ref). Default.
  kReferencePath,
  /// A fixed trim height (LandingConfig::plant_fixed_reference_height_m), as the open-loop run measures
  /// ΔH from its start height.
  kFixedHeight,
};
/// "path" / "fixed": the study values, flag values and JSON strings.
GESWEEP_ENUM_NAMES(PlantHeightReference, {kReferencePath, "path"}, {kFixedHeight, "fixed"});

/// A setting whose NaN means "automatic" (as DisturbanceOptions::turbulence_sigma_w_mps): `value`
/// when set, else `automatic`.
inline double SetOr(double value, double automatic) { return std::isnan(value) ? automatic : value; }

/// The landing's integrator: dopri5 at ode45's default tolerances, its largest step 1 s.
inline IntegratorOptions LandingIntegrator() {
  IntegratorOptions options;
  options.kind = IntegratorKind::kDopri5;
  options.relative_tolerance = 1e-3;
  options.absolute_tolerance = 1e-6;
  options.max_step_s = 1.0;
  return options;
}

/// Everything SimulateLanding needs besides the aircraft model. Angles are in degrees at this
/// interface (they are written by people); the engine converts once. A setting that is NaN by default
/// is computed when unset ("automatic", SetOr).
struct LandingConfig {
  // --- Start state (the paper's Eq. (30): [u0 0 0 0 H0 0 0 0 0]) ---
  double start_height_m = 500.0;  ///< H at t = 0, m (> flare height)
  /// u at t = 0, m/s; also the plant's reference speed u0 (Δu = u − u0, kinematic entries of Eq. (1)).
  double start_speed_mps = 52.21;
  double start_pitch_deg = 0.0;            ///< Δθ at t = 0, deg (the reference flight is level, θ0 = 0)
  double start_glide_path_offset_m = 0.0;  ///< d at t = 0, m, positive above the glide path

  // --- Glide path ---
  /// Glide-slope angle γ, deg, positive for a descent; the reference flight-path angle is γr = −γ.
  double glide_slope_deg = 2.5;

  // --- LQR design (paper: Matlab lqry on Eq. (16), identity weights) ---
  /// Height of the linear model used for the gain, m. NaN: the aircraft's wheel-contact height, where
  /// the ground effect (and the open-loop instability) is strongest. +∞ designs on the free-flight row.
  double design_height_m = std::numeric_limits<double>::quiet_NaN();
  /// Speed of the linear model used for the gain, m/s. NaN: start_speed_mps.
  double design_speed_mps = std::numeric_limits<double>::quiet_NaN();
  /// Include Xh, Zh, Mh in the design model (the paper's recommendation). Independent of the plant's
  /// model option, so that the paper's experiment flies one gain in two plants.
  bool design_h_derivatives = true;
  /// Diagonal of the output weight Q on the 9 states of Eq. (14) (order: LandingStateNames()); ≥ 0.
  /// The ΔH weight adds to the deviation weight, since the design model measures both as one state.
  std::array<double, kLandingStateCount> q_weights = {1, 1, 1, 1, 1, 1, 1, 1, 1};
  double r_weight = 1.0;                 ///< weight R on the elevator command ηe (rad²); > 0
  double actuator_pole_per_s = 10.0;     ///< Sδ of Tf3 = Sδ/(s + Sδ) (paper Eq. (29)); > 0
  double compensator_pole_per_s = 10.0;  ///< S_d of Tf2 = 1/(s + S_d) (paper Eq. (29)); > 0

  // --- Flare (paper Eq. (22)–(27)) ---
  double flare_height_m = 10.0;  ///< Ho: the flare starts when H falls to it, m
  /// τ of Ḣ_ref = −(H_ref − h_a)/τ, s. NaN: (Ho − h_a)/(u0·sin γ), so the commanded sink rate is
  /// continuous at Ho.
  double flare_time_constant_s = std::numeric_limits<double>::quiet_NaN();
  /// The flare's asymptote h_a, m: H_ref = h_a + (Ho − h_a)·e^(−(t − t_f)/τ). 0 (default): the
  /// paper's Eq. (22), H_ref → the ground; the wheel-contact height makes touchdown a long float
  /// (docs/landing.md §5). In [0, Ho).
  double flare_asymptote_m = 0.0;
  /// true: the compensator and the error integral restart from zero at the flare switch (their
  /// values at the switch are removed with the free response they would have had); false (default):
  /// they carry over, as the paper's one controller (docs/landing.md §5).
  bool reset_compensator_at_flare = false;

  // --- Elevator (positive trailing edge down) ---
  double elevator_min_deg = -25.0;  ///< the command ηe is clipped to [min, max], deg
  double elevator_max_deg = 25.0;

  // --- Plant ---
  PlantHeightReference plant_height_reference = PlantHeightReference::kReferencePath;
  /// Used with kFixedHeight: ΔH = H − this, m. NaN: the aircraft's highest finite table height (where
  /// the h-derivatives start to be non-zero).
  double plant_fixed_reference_height_m = std::numeric_limits<double>::quiet_NaN();

  // --- Integration (adaptive Dormand–Prince 5(4), as the paper's ode45) ---
  /// dopri5 at ode45's default tolerances (relative 1e-3, the paper's; absolute 1e-6), its largest
  /// step 1 s so that no event is stepped over. Only the tolerances and the largest step are
  /// settings (DescribeAdaptive); the method, the first step and the output are set per run.
  IntegratorOptions integrator = LandingIntegrator();
  /// Outcome no_touchdown when reached in flight, s. NaN: twice NominalLandingTime, so that a sweep over
  /// the glide slope or the start height needs no retuning.
  double time_limit_s = std::numeric_limits<double>::quiet_NaN();
  double output_interval_s = 0.1;  ///< series sampling, s; 0: no series
  /// |Δθ| beyond this ends the run as diverged, deg: the small-angle model no longer means anything.
  double divergence_pitch_deg = 60.0;

  // --- The moving atmosphere (docs/model.md §9) ---
  /// Default still air: the landing above, bit for bit. With any disturbance the glide path is
  /// geometric (a line over the along-track ground position, docs/model.md §9), the airplane starts
  /// at airspeed start_speed_mps in the mean wind (Δu(0) = W(H0)), and the span of the pitch-rate
  /// gust is the aircraft's.
  DisturbanceOptions disturbance;
  std::uint64_t seed = 0;  ///< the turbulence is RunNoise(seed, run_index) (docs/disturbance.md)
  std::uint64_t run_index = 0;
  /// The integrator of a landing in turbulence: rk4 (default) with its step equal to
  /// turbulence_sample_interval_s, so the noise's sample instants are its grid (docs/disturbance.md,
  /// Cost); dopri5 at the tolerances above, stopping at every sample instant (about 1.8× the cost).
  IntegratorKind turbulent_integrator = IntegratorKind::kRk4;

  /// The settings a person gives (describe.h): [analyses.landing], the flags of `gesweep land` and
  /// the keywords of gesweep.land, under the keys ValidateLandingConfig names. The glide slope, the
  /// flare and the LQR weights are a sweep's run parameters of the same keys (RunParameter: their
  /// catalogue entries are these fields; q_weights, a setting's array, one q_weights.<state> per
  /// state), and the start condition is the run parameters height_m and speed_mps, so they are flags
  /// only; so are the series interval (a study's [storage]) and the turbulence's seed and run index.
  template <class V>
  void Describe(V& v) {
    v(Field("start_height_m", &start_height_m)
          .Unit("m")
          .Limit("height_m")
          .CommandLineOnly()
          .Doc("Start height of the mean chord, m"));
    v(Field("start_speed_mps", &start_speed_mps)
          .Unit("m/s")
          .Limit("speed_mps")
          .CommandLineOnly()
          .Doc("Start speed, also the reference speed u0 of the plant, m/s"));
    v(Field("start_pitch_deg", &start_pitch_deg)
          .Unit("deg")
          .Limit("landing.start_pitch_deg")
          .Doc("Start pitch angle (reference: level), deg"));
    v(Field("start_glide_path_offset_m", &start_glide_path_offset_m)
          .Unit("m")
          .Limit("landing.start_glide_path_offset_m")
          .Doc("Start deviation d from the glide path, m, positive above"));
    v(Field("glide_slope_deg", &glide_slope_deg)
          .Unit("deg")
          .Limit("glide_slope_deg")
          .RunParameter()
          .Doc("Glide-slope angle gamma, positive for a descent (the paper: 2.5 to 3 deg)"));
    v(Field("flare_height_m", &flare_height_m)
          .Unit("m")
          .Limit("flare_height_m")
          .RunParameter()
          .Doc("Height Ho at which the flare starts"));
    v(Field("flare_time_constant_s", &flare_time_constant_s)
          .Automatic()
          .Unit("s")
          .Limit("flare_time_constant_s")
          .RunParameter()
          .Doc("Time constant tau of the exponential flare command; default (left out): automatic, "
               "Ho/(u0 sin gamma), so the commanded sink rate is continuous at Ho"));
    v(Field("q_weights", &q_weights)
          .NamedComponents(kLandingStates)
          .Limit("q_weights")
          .RunParameter()
          .Doc("LQR weight on the state <component> of the paper's Eq. (14) (diagonal of Q; the paper: "
               "identity)"));
    v(Field("r_weight", &r_weight)
          .Unit("rad^2")
          .Limit("r_weight")
          .RunParameter()
          .Doc("LQR weight R on the elevator command (the paper: 1)"));
    v(Field("design_height_m", &design_height_m)
          .Automatic()
          .Unit("m")
          .Limit("landing.design_height_m")
          .Doc("Height of the linear model used for the gain, m; default (left out): the wheel-contact "
               "height"));
    v(Field("design_speed_mps", &design_speed_mps)
          .Automatic()
          .Unit("m/s")
          .Limit("speed_mps")
          .Doc("Speed of the linear model used for the gain, m/s; default (left out): the start speed"));
    v(Field("design_h_derivatives", &design_h_derivatives)
          .Doc("Include Xh, Zh, Mh in the design model (the plant follows h_derivatives)"));
    v(Field("actuator_pole_per_s", &actuator_pole_per_s)
          .Unit("1/s")
          .Limit("landing.actuator_pole_per_s")
          .Doc("Elevator actuator pole, 1/s"));
    v(Field("compensator_pole_per_s", &compensator_pole_per_s)
          .Unit("1/s")
          .Limit("landing.compensator_pole_per_s")
          .Doc("Compensator pole S_d, 1/s"));
    v(Field("elevator_min_deg", &elevator_min_deg)
          .Unit("deg")
          .Limit("landing.elevator_min_deg")
          .Doc("Lower elevator limit, deg"));
    v(Field("elevator_max_deg", &elevator_max_deg)
          .Unit("deg")
          .Limit("landing.elevator_max_deg")
          .Doc("Upper elevator limit, deg"));
    v(Field("plant_height_reference", &plant_height_reference)
          .Doc("What the plant's h-derivative terms measure dH from: path (the reference trajectory) or "
               "fixed (plant_fixed_reference_height_m)"));
    v(Field("plant_fixed_reference_height_m", &plant_fixed_reference_height_m)
          .Automatic()
          .Unit("m")
          .Limit("landing.plant_fixed_reference_height_m")
          .Doc("Fixed reference height with plant_height_reference fixed, m; default (left out): the top "
               "table "
               "height"));
    integrator.DescribeAdaptive(
        v, {.step_s = "",
            .max_step_s = "landing.max_step_s",
            .relative_tolerance_doc = "Dormand-Prince relative tolerance (1e-3: ode45's, the paper's)",
            .absolute_tolerance_doc = "Dormand-Prince absolute tolerance",
            .max_step_doc = "Largest step, s"});
    v(Field("time_limit_s", &time_limit_s)
          .Automatic()
          .Unit("s")
          .Limit("landing.time_limit_s")
          .Doc("Time limit, s (outcome no_touchdown); default (left out): twice the reference trajectory's "
               "time to "
               "the wheels"));
    v(Field("output_interval_s", &output_interval_s)
          .Unit("s")
          .Limit("output_dt_s")
          .CommandLineOnly()
          .Doc("Series sampling interval, s"));
    v(Field("divergence_pitch_deg", &divergence_pitch_deg)
          .Unit("deg")
          .Limit("landing.divergence_pitch_deg")
          .Doc("|pitch| that ends the run as diverged, deg"));
    v(Field("flare_asymptote_m", &flare_asymptote_m)
          .Unit("m")
          .Limit("landing.flare_asymptote_m")
          .Doc("Height the flare's exponential tends to, m, in [0, Ho); 0: the ground, the paper's; the "
               "wheel-contact height makes touchdown a long float (docs/landing.md)"));
    v(Field("reset_compensator_at_flare", &reset_compensator_at_flare)
          .Doc("Restart the compensator and the error integral from zero at the flare switch (default: they "
               "carry over)"));
    disturbance.Describe(v);
    v(Field("turbulent_integrator", &turbulent_integrator)
          .Doc("Integrator of a landing in turbulence: rk4 (step = turbulence_sample_interval_s) or dopri5 "
               "(relative_tolerance, absolute_tolerance)"));
    v(Field("seed", &seed)
          .CommandLineOnly()
          .Limit("seed")
          .Doc("Seed of the turbulence (a sweep's seed parameter, docs/disturbance.md)"));
    v(Field("run_index", &run_index)
          .CommandLineOnly()
          .Limit("run_index")
          .Doc("Run index i of the turbulence RunNoise(seed, i): replays run i of a sweep"));
  }
};

/// Throws InputError(source, <field name>, value, expectation) when a field is out of range: first the
/// limits table (engine/common/input_limits.h; docs/limits.md), then the aircraft's limits (flare,
/// start and design heights above its wheel-contact height, the start speed above its stall speed),
/// then the step count: time limit / max_step_s at most kMaximumStepsPerRun.
void ValidateLandingConfig(const LandingConfig& config, const Aircraft& aircraft, const std::string& source);

/// The flare time constant used: config's, or (Ho − h_a)/(u0·sin γ), s.
double FlareTimeConstant(const LandingConfig& config);

/// Time the reference trajectory takes from the start to the wheels, s: down the glide path to Ho at
/// u0·γ (γ in rad, the small-angle kinematics of Eq. (1)), then H_ref = Ho·e^(−t/τ) down to the
/// wheel-contact height.
double NominalLandingTime(const LandingConfig& config, double wheel_contact_height_m);

/// The time limit used: config's, or 2·NominalLandingTime, s.
double LandingTimeLimit(const LandingConfig& config, double wheel_contact_height_m);

}  // namespace gesweep
