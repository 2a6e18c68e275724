// The moving atmosphere in the time responses (docs/model.md §9, docs/disturbance.md): the open-loop
// run and the landing in steady wind, turbulence and a 1 − cos gust. Oracles: the equilibrium of the
// air-relative Eq. (1) (Δu = u_g at airspeed u0), the glide path's geometry (ground speed × time),
// the turbulence as a function of time alone (two integrators at different steps see the same
// input), and the still-air runs (a disturbance whose every option is at its default changes no bit).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "engine/aircraft/aircraft.h"
#include "engine/control/landing_simulation.h"
#include "engine/disturbance/mean_wind.h"
#include "engine/simulation/open_loop.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

// Tolerances: each says where it comes from.
/// A run started in equilibrium stays there: Eq. (1)'s right-hand side is zero to rounding of terms of
/// order u0·Δθ, X_u·u_g (~1e-15 relative), accumulated over 2000 RK4 steps.
constexpr double kEquilibriumTolerance = 1e-9;
/// Entering a steady wind from the still-air trim: the phugoid (σ ≈ −0.0033 1/s at 50 m, the README's
/// modes table) decays as e^(σt); after 3000 s the initial 4 m/s is down to about 2e-4 m/s.
constexpr double kSettledSpeedTolerance_mps = 1e-3;
/// Same turbulence for RK4 at Δt_n and dopri5 at 1e-10: each integrates the same held noise to its
/// accuracy; 1e-3 m/s against σ_w = 1.5 m/s is far below the sampling spread and far above both errors
/// (docs/disturbance.md: the field alone agrees to 1e-4 m/s).
constexpr double kSameTurbulenceTolerance_mps = 1e-3;
/// The series' first Δu is the −4 m/s wind plus the 4 m/s airspeed offset: exact in binary, and 1e-15
/// allows no more than one rounding of a 4 m/s value (ulp 8.9e-16).
constexpr double kOffsetSumTolerance_mps = 1e-15;
/// Series interval of the geometric tests, s.
constexpr double kSeriesInterval_s = 0.01;
/// Rounding of a difference of speeds of ~60 m/s, or of distances of ~1 km (×1e3).
constexpr double kRoundingTolerance = 1e-11;
/// ∫u dt over a ~10 s flare by the trapezoid at 0.01 s: u changes by ~1 m/s over the flare, smoothly,
/// so the rule's error is ~1e-5 m; the last sample is the touchdown itself. 1 cm allows for it.
constexpr double kTrapezoidTolerance_m = 0.01;
/// The reference path's height against the line at the sample's ground position: the same closed
/// form in the engine and here, rounding of ~1e3 m values.
constexpr double kPathTolerance_m = 1e-9;

constexpr double kSpeed_mps = 32.0208;

const LongitudinalModel& Model() {
  static const LongitudinalModel model(LoadAircraftFile(testing::AnceAircraftPath()), ModelOptions{});
  return model;
}

OpenLoopConfig Cruise(double height_m, double duration_s) {
  OpenLoopConfig config;
  config.start_height_m = height_m;
  config.reference_speed_mps = kSpeed_mps;
  config.elevator.kind = ElevatorInputKind::kNone;
  config.duration_s = duration_s;
  return config;
}

TEST(OpenLoopInWind, StartedInASteadyHeadwindItStaysAtDeltaUEqualsTheWind) {
  // At 50 m with the logarithmic profile a 15 kt headwind at 20 ft is u_g = W(50 m). The run starts
  // at airspeed u0 (Δu(0) = u_g) and, with no input, Eq. (1) in air-relative form has ẋ = 0 there.
  OpenLoopConfig config = Cruise(50.0, 30.0);
  config.disturbance.wind_20ft_mps = -7.717;
  const double u_g = MeanWindAt(-7.717, 50.0, WindShear::kLogarithmic);
  ASSERT_LT(u_g, -7.717) << "the shear makes the wind at 50 m stronger than at 20 ft";
  for (bool frozen : {false, true}) {
    config.freeze_derivatives = frozen;
    const OpenLoopResult r = SimulateOpenLoop(Model(), config);
    EXPECT_EQ(r.summary.end_event, OpenLoopEndEvent::kTimeLimit);
    EXPECT_NEAR(r.summary.final_state[kDeltaU], u_g, kEquilibriumTolerance) << frozen;
    EXPECT_NEAR(r.summary.final_speed_mps - u_g, kSpeed_mps, kEquilibriumTolerance) << "airspeed u0";
    EXPECT_NEAR(r.summary.final_state[kDeltaH], 0.0, kEquilibriumTolerance);
    EXPECT_NEAR(r.summary.final_state[kDeltaTheta], 0.0, kEquilibriumTolerance);
  }
}

TEST(OpenLoopInWind, EnteringASteadyHeadwindAtGroundSpeedU0ItSettlesAtAirspeedU0) {
  // Without shear the wind is −4 m/s everywhere. Started at inertial Δu = 0 (initial offset +4 m/s on
  // the airspeed), the airplane oscillates in its phugoid and settles at Δu = −4 m/s: airspeed u0.
  OpenLoopConfig config = Cruise(50.0, 3000.0);
  config.disturbance.wind_20ft_mps = -4.0;
  config.disturbance.wind_shear = WindShear::kNone;
  config.initial_offsets.delta_speed_mps = 4.0;
  config.series_interval_s = 1.0;
  const OpenLoopResult r = SimulateOpenLoop(Model(), config);
  ASSERT_EQ(r.summary.end_event, OpenLoopEndEvent::kTimeLimit) << r.summary.message;
  EXPECT_NEAR(r.series.delta_speed_mps.front(), 0.0, kOffsetSumTolerance_mps) << "starts at ground speed u0";
  EXPECT_NEAR(r.summary.final_state[kDeltaU], -4.0, kSettledSpeedTolerance_mps);
  EXPECT_NEAR(r.summary.final_state[kPitchRate], 0.0, kSettledSpeedTolerance_mps);
  // The series carries the wind the airplane met: −4 m/s throughout, no vertical air motion.
  ASSERT_EQ(r.series.u_g_mps.size(), r.series.time_s.size());
  for (std::size_t i = 0; i < r.series.u_g_mps.size(); ++i) {
    EXPECT_EQ(r.series.u_g_mps[i], -4.0);
    EXPECT_EQ(r.series.w_g_mps[i], 0.0);
  }
  EXPECT_TRUE(r.series.q_g_radps.empty()) << "no pitch-rate gust asked for";
  // The same start in still air is not this equilibrium (the test can fail): it settles at Δu = 0.
  OpenLoopConfig still = config;
  still.disturbance = {};
  const OpenLoopResult s = SimulateOpenLoop(Model(), still);
  EXPECT_GT(std::abs(s.summary.final_state[kDeltaU] + 4.0), 1.0);
  EXPECT_TRUE(s.series.u_g_mps.empty()) << "still air: no air-motion columns";
}

TEST(OpenLoopInWind, DefaultDisturbanceOptionsChangeNoBit) {
  // Still air by default: a config with a DisturbanceOptions{} (and any seed) is the run of docs/model.md
  // §7 to the bit, on each derivative source.
  for (int source = 0; source < 3; ++source) {
    OpenLoopConfig config = Cruise(3.0, 20.0);
    config.elevator.kind = ElevatorInputKind::kPulse;
    config.series_interval_s = 0.05;
    config.freeze_derivatives = source == 1;
    config.generic_derivative_path = source == 2;
    OpenLoopConfig seeded = config;
    seeded.seed = 12345;
    seeded.run_index = 7;
    const OpenLoopResult a = SimulateOpenLoop(Model(), config);
    const OpenLoopResult b = SimulateOpenLoop(Model(), seeded);
    ASSERT_EQ(a.series.time_s.size(), b.series.time_s.size());
    for (std::size_t i = 0; i < a.series.time_s.size(); ++i) {
      EXPECT_EQ(a.series.height_m[i], b.series.height_m[i]);
      EXPECT_EQ(a.series.pitch_rate_radps[i], b.series.pitch_rate_radps[i]);
    }
    EXPECT_EQ(a.summary.rhs_calls, b.summary.rhs_calls);
  }
}

TEST(OpenLoopInWind, Rk4AndDopri5MeetTheSameTurbulence) {
  // The held noise is a function of time alone: RK4 at Δt_n and dopri5 at tight tolerances, both
  // stopping at every sample instant, give the same u_g and w_g at every output time.
  OpenLoopConfig config = Cruise(30.0, 20.0);
  config.disturbance.wind_20ft_mps = -15.433;  // 30 kt: σ_w = 1.54 m/s
  config.disturbance.turbulence = TurbulenceModel::kDryden;
  config.seed = 3;
  config.run_index = 11;
  config.series_interval_s = 0.1;
  config.integrator.step_s = config.disturbance.turbulence_sample_interval_s;
  const OpenLoopResult rk4 = SimulateOpenLoop(Model(), config);
  OpenLoopConfig adaptive = config;
  adaptive.integrator.kind = IntegratorKind::kDopri5;
  adaptive.integrator.relative_tolerance = 1e-10;
  adaptive.integrator.absolute_tolerance = 1e-12;
  const OpenLoopResult dopri5 = SimulateOpenLoop(Model(), adaptive);
  ASSERT_EQ(rk4.series.time_s.size(), dopri5.series.time_s.size());
  double largest_w_g = 0;
  for (std::size_t i = 0; i < rk4.series.time_s.size(); ++i) {
    EXPECT_NEAR(rk4.series.u_g_mps[i], dopri5.series.u_g_mps[i], kSameTurbulenceTolerance_mps) << i;
    EXPECT_NEAR(rk4.series.w_g_mps[i], dopri5.series.w_g_mps[i], kSameTurbulenceTolerance_mps) << i;
    largest_w_g = std::max(largest_w_g, std::abs(rk4.series.w_g_mps[i]));
  }
  EXPECT_GT(largest_w_g, 0.5) << "the turbulence is there (the test can fail)";
  // Another run of the same study meets another turbulence.
  OpenLoopConfig other = config;
  other.run_index = 12;
  const OpenLoopResult next = SimulateOpenLoop(Model(), other);
  EXPECT_NE(next.series.w_g_mps[50], rk4.series.w_g_mps[50]);
}

LandingConfig PaperLanding() {
  LandingConfig config;  // the paper's: 500 m, 52.21 m/s, 2.5°, flare at 10 m
  config.output_interval_s = 0.0;
  return config;
}

TEST(LandingInWind, DefaultDisturbanceOptionsChangeNoBit) {
  LandingConfig seeded = PaperLanding();
  seeded.seed = 99;
  seeded.run_index = 4;
  const LandingResult a = SimulateLanding(Model(), PaperLanding());
  const LandingResult b = SimulateLanding(Model(), seeded);
  ASSERT_EQ(a.outcome, LandingOutcome::kLanded);
  EXPECT_EQ(a.touchdown_time_s, b.touchdown_time_s);
  EXPECT_EQ(a.touchdown_distance_past_transmitter_m, b.touchdown_distance_past_transmitter_m);
  EXPECT_EQ(a.touchdown_sink_rate_mps, b.touchdown_sink_rate_mps);
  EXPECT_EQ(a.rhs_calls, b.rhs_calls);
  EXPECT_EQ(a.touchdown_airspeed_mps, a.touchdown_speed_mps) << "still air: airspeed is the speed";
  // The flare-phase maxima are within the whole run's.
  EXPECT_LE(a.flare_max_abs_elevator_deg, a.max_abs_elevator_deg);
  EXPECT_LE(a.flare_max_abs_pitch_rate_degps, a.max_abs_pitch_rate_degps);
  EXPECT_GT(a.flare_max_abs_elevator_deg, 0.0);
}

TEST(LandingInWind, TheGlidePathIsALineOverTheGround) {
  // A steady wind without shear on the geometric glide path (docs/model.md §9): the path is a line over
  // the along-track ground position, so the flare starts at the same ground point whatever the wind
  // (where the line is at Ho, give or take the tracking error there), later in a headwind (lower ground
  // speed) than in a tailwind; from there the airplane covers the ground at its inertial speed
  // u = u0 + Δu, so the touchdown point is the flare's start plus ∫u dt over the flare, and a
  // headwind lands short of a tailwind. (Still air flies the time-based path of docs/model.md §8, whose
  // along-track distance is u0·t: not comparable, since the unpowered model's speed rises by 30 % on
  // the glide, docs/landing.md §6.)
  double distance[2], flare_time[2];
  const double winds[2] = {-5.0, 5.0};
  for (int i = 0; i < 2; ++i) {
    LandingConfig config = PaperLanding();
    config.disturbance.wind_20ft_mps = winds[i];
    config.disturbance.wind_shear = WindShear::kNone;
    config.output_interval_s = kSeriesInterval_s;
    const LandingResult r = SimulateLanding(Model(), config);
    ASSERT_EQ(r.outcome, LandingOutcome::kLanded) << r.message;
    distance[i] = r.touchdown_distance_past_transmitter_m;
    flare_time[i] = r.flare_start_time_s;
    EXPECT_NEAR(r.touchdown_airspeed_mps, r.touchdown_speed_mps - winds[i], kRoundingTolerance)
        << "airspeed = u − u_g";
    // The geometry, from the series: before the flare the reference is the line's height −γ·x at the
    // sample's ground position x; the touchdown point is the first flare sample's position plus the
    // trapezoid of u over the flare samples.
    const double gamma_rad = config.glide_slope_deg * std::numbers::pi / 180.0;
    std::size_t first = 0;
    while (r.series[first].phase != LandingPhase::kFlare) ++first;
    const LandingSample& start = r.series[first];
    EXPECT_NEAR(r.series[first - 1].distance_past_transmitter_m,
                -r.series[first - 1].reference_height_m / gamma_rad, kPathTolerance_m)
        << "on the glide path the reference is the line over the ground";
    double flown_m = 0;
    for (std::size_t k = first + 1; k < r.series.size(); ++k) {
      const LandingSample& a = r.series[k - 1];
      const LandingSample& b = r.series[k];
      flown_m += 0.5 * (a.speed_mps + b.speed_mps) * (b.time_s - a.time_s);
    }
    EXPECT_NEAR(distance[i], start.distance_past_transmitter_m + flown_m, kTrapezoidTolerance_m) << winds[i];
  }
  EXPECT_LT(distance[0], distance[1]);
  EXPECT_GT(flare_time[0], flare_time[1]);
  // The same ground distance (the line from the start to where it is at Ho) at ground speeds 10 m/s
  // apart, about 60 m/s on average: the headwind's glide is longer by roughly 10/60 of it (~25 s).
  EXPECT_GT(flare_time[0] - flare_time[1], 0.1 * flare_time[1]);
}

TEST(LandingInWind, TurbulentLandingLandsAndReplays) {
  LandingConfig config = PaperLanding();
  config.start_height_m = 60.0;
  config.disturbance.wind_20ft_mps = -7.7;
  config.disturbance.turbulence = TurbulenceModel::kDryden;
  config.seed = 1;
  config.run_index = 2;
  const LandingResult a = SimulateLanding(Model(), config);
  const LandingResult b = SimulateLanding(Model(), config);
  ASSERT_EQ(a.outcome, LandingOutcome::kLanded) << a.message;
  EXPECT_EQ(a.touchdown_time_s, b.touchdown_time_s) << "deterministic per (seed, run)";
  config.run_index = 3;
  const LandingResult c = SimulateLanding(Model(), config);
  EXPECT_NE(a.touchdown_time_s, c.touchdown_time_s);
}

TEST(LandingOptions, FlareAsymptoteAtTheWheelsFloats) {
  // H_ref → the wheel-contact height: the reference never reaches the wheels, so the airplane floats
  // down only by its lag behind H_ref, far longer than the paper's flare.
  const LandingResult paper = SimulateLanding(Model(), PaperLanding());
  LandingConfig config = PaperLanding();
  config.flare_asymptote_m = Model().aircraft().wheel_contact_height_m;
  const LandingResult floated = SimulateLanding(Model(), config);
  ASSERT_EQ(paper.outcome, LandingOutcome::kLanded);
  ASSERT_EQ(floated.outcome, LandingOutcome::kLanded) << floated.message;
  EXPECT_GT(floated.touchdown_time_s - floated.flare_start_time_s,
            2.0 * (paper.touchdown_time_s - paper.flare_start_time_s));
  EXPECT_LT(floated.touchdown_sink_rate_mps, paper.touchdown_sink_rate_mps);
}

TEST(LandingOptions, CompensatorResetChangesOnlyTheFlare) {
  const LandingResult carried = SimulateLanding(Model(), PaperLanding());
  LandingConfig config = PaperLanding();
  config.reset_compensator_at_flare = true;
  const LandingResult reset = SimulateLanding(Model(), config);
  ASSERT_EQ(reset.outcome, LandingOutcome::kLanded) << reset.message;
  EXPECT_EQ(reset.flare_start_time_s, carried.flare_start_time_s) << "the glide is the same run";
  EXPECT_NE(reset.touchdown_time_s, carried.touchdown_time_s);
}

}  // namespace
}  // namespace gesweep
