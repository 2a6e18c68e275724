// The closed-loop landing (docs/landing.md §3–§4). Oracles: the glide-path and flare kinematics the
// controller is asked to track, the acceptance numbers, the series written by the run itself for
// the event-located saturation time, and model identities (no h-derivatives → the ΔH convention is moot).
#include "engine/control/landing_simulation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <thread>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/common/errors.h"
#include "engine/disturbance/run_noise.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

// Tolerances: each says where it comes from.
/// Event-located against sampled every output interval: a few sample intervals apart at most.
constexpr double kSamplingIntervals = 10;
/// Touchdown and stall are located events (bracketed in time to 1e-10 s by default): the height (m) or speed
/// (m/s) there is exact to far below 1e-6.
constexpr double kLocatedEventTolerance = 1e-6;
/// A quantity the engine computes by the same closed form as the test (reference path, flare exponential,
/// tracking error, nominal time): agreement to rounding of values up to ~1e3.
constexpr double kClosedFormTolerance = 1e-9;
/// On the glide path the height tracks H0 − u0·γ·t to centimetres; 0.1 m is the path error the default
/// landing test allows at the flare.
constexpr double kGlidePathHeightTolerance_m = 0.1;
/// Distance past the transmitter by the engine's closed form from the reported touchdown time: rounding of a
/// few-kilometre value, with margin.
constexpr double kDistanceRoundingTolerance_m = 1e-6;

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
/// The acceptance threshold for the touchdown sink rate.
constexpr double kMaxTouchdownSinkRate_mps = 1.5;
/// "No prolonged saturation": brief saturation during the initial pitch-over is acceptable, a second is not.
constexpr double kMaxSaturation_s = 1.0;
/// The glide is tracked to centimetres, so the flare starts within this of when the path reaches Ho.
constexpr double kFlareTimingTolerance_s = 0.5;
/// A tracking controller lags its reference: touchdown within this of a perfectly tracked exponential.
constexpr double kFlareTrackingTolerance_s = 2.0;
/// Steady glide: sink rate within 0.5 % of u0·γ (rtol 1e-3 plus the residual transient).
constexpr double kGlideSinkRelativeTolerance = 5e-3;

LongitudinalModel Ance(bool h_derivatives = true) {
  ModelOptions options;
  options.h_derivatives = h_derivatives;
  return LongitudinalModel(LoadAircraftFile(testing::AnceAircraftPath()), options);
}

TEST(LandingSimulation, DefaultLandingFromFiveHundredMetres) {
  const LongitudinalModel model = Ance();
  const LandingConfig config;  // 500 m, 52.21 m/s, γ = 2.5°, Ho = 10 m, matched τ
  ASSERT_DOUBLE_EQ(config.start_height_m, 500.0);
  ASSERT_DOUBLE_EQ(config.start_speed_mps, 52.21);
  const LandingResult r = SimulateLanding(model, config);
  ASSERT_EQ(r.outcome, LandingOutcome::kLanded) << r.message;
  EXPECT_GT(r.touchdown_sink_rate_mps, 0.0);
  EXPECT_LT(r.touchdown_sink_rate_mps, kMaxTouchdownSinkRate_mps);
  EXPECT_LT(r.saturated_time_s, kMaxSaturation_s);
  EXPECT_LT(r.longest_saturation_s, kMaxSaturation_s);
  EXPECT_NEAR(r.final_height_m, model.aircraft().wheel_contact_height_m, kLocatedEventTolerance);

  // Kinematics of the reference: the glide path descends at u0·γ (γ in rad, Eq. (1)'s small angle) and
  // reaches Ho after (H0 − Ho)/(u0·γ); the flare's H_ref = Ho·e^(−t/τ) reaches the wheels after τ·ln(Ho/Hc).
  const double gamma_rad = config.glide_slope_deg * kRadPerDeg;
  const double glide_sink_mps = config.start_speed_mps * gamma_rad;
  const double path_at_flare_s = (config.start_height_m - config.flare_height_m) / glide_sink_mps;
  EXPECT_NEAR(r.flare_start_time_s, path_at_flare_s, kFlareTimingTolerance_s);
  EXPECT_LT(std::abs(r.glide_path_error_at_flare_m), 0.1);
  const double tau_s = config.flare_height_m / (config.start_speed_mps * std::sin(gamma_rad));
  EXPECT_DOUBLE_EQ(r.flare_time_constant_s, tau_s);
  const double ideal_touchdown_s =
      r.flare_start_time_s +
      tau_s * std::log(config.flare_height_m / model.aircraft().wheel_contact_height_m);
  EXPECT_NEAR(r.touchdown_time_s, ideal_touchdown_s, kFlareTrackingTolerance_s);
  // The transmitter is where the glide path meets H = 0: touchdown past it by u0·(t − H0/(u0·γ)).
  EXPECT_NEAR(r.touchdown_distance_past_transmitter_m,
              config.start_speed_mps * r.touchdown_time_s - config.start_height_m / gamma_rad,
              kDistanceRoundingTolerance_m);

  // The series: steady glide at u0·γ, the reference written out, the phase switch at the flare event.
  ASSERT_FALSE(r.series.empty());
  bool checked_glide = false;
  for (const LandingSample& s : r.series) {
    EXPECT_NEAR(s.tracking_error_m, s.height_m - s.reference_height_m, kClosedFormTolerance);
    if (s.phase == LandingPhase::kGlideSlope) {
      EXPECT_LE(s.time_s, r.flare_start_time_s + 1e-9);
      EXPECT_NEAR(s.reference_height_m, config.start_height_m - glide_sink_mps * s.time_s,
                  kClosedFormTolerance);
      if (s.time_s > 100.0 && s.time_s < 200.0) {
        EXPECT_NEAR(s.sink_rate_mps, glide_sink_mps, kGlideSinkRelativeTolerance * glide_sink_mps)
            << s.time_s;
        checked_glide = true;
      }
    } else {
      EXPECT_GE(s.time_s, r.flare_start_time_s - 1e-9);
      EXPECT_NEAR(s.reference_height_m,
                  config.flare_height_m * std::exp(-(s.time_s - r.flare_start_time_s) / tau_s),
                  kClosedFormTolerance);
    }
  }
  EXPECT_TRUE(checked_glide);
  EXPECT_DOUBLE_EQ(r.series.back().time_s, r.touchdown_time_s);
}

TEST(LandingSimulation, SaturatedTimeMatchesTheSeries) {
  // An upper limit of 3.5° is below the initial pitch-over command (≈ 4.9°) and above the glide trim
  // (≈ 2.8°): the command saturates once, early. The event-located total must match a fine sampling of the
  // command.
  const LongitudinalModel model = Ance();
  LandingConfig config;
  config.elevator_max_deg = 3.5;
  config.output_interval_s = 0.002;
  config.time_limit_s = 30.0;
  const LandingResult r = SimulateLanding(model, config);
  ASSERT_EQ(r.outcome, LandingOutcome::kNoTouchdown) << r.message;
  double sampled_s = 0.0;
  for (std::size_t i = 0; i + 1 < r.series.size(); ++i) {
    if (r.series[i].elevator_command_rad > config.elevator_max_deg * kRadPerDeg) {
      sampled_s += r.series[i + 1].time_s - r.series[i].time_s;
    }
  }
  ASSERT_GT(sampled_s, 0.05);
  // Event-located vs sampled every 2 ms: a few sample intervals apart at most.
  EXPECT_NEAR(r.saturated_time_s, sampled_s, kSamplingIntervals * config.output_interval_s);
  EXPECT_LE(r.longest_saturation_s, r.saturated_time_s + 1e-12);
  EXPECT_LE(r.max_abs_elevator_deg, config.elevator_max_deg + 1e-9);
  EXPECT_GT(r.max_abs_elevator_command_deg, config.elevator_max_deg);
}

TEST(LandingSimulation, TimeLimitInFlightIsNoTouchdown) {
  const LongitudinalModel model = Ance();
  LandingConfig config;
  config.time_limit_s = 100.0;
  config.output_interval_s = 0.0;
  const LandingResult r = SimulateLanding(model, config);
  EXPECT_EQ(r.outcome, LandingOutcome::kNoTouchdown) << r.message;
  EXPECT_TRUE(r.series.empty());
  EXPECT_DOUBLE_EQ(r.final_time_s, 100.0);
  EXPECT_TRUE(std::isnan(r.touchdown_time_s));
  // On the glide path: H0 − u0·γ·t, within the path error.
  EXPECT_NEAR(r.final_height_m, 500.0 - 52.21 * 2.5 * kRadPerDeg * 100.0, kGlidePathHeightTolerance_m);
}

TEST(LandingSimulation, StallIsLocatedAtTheStallSpeed) {
  // At 30 m/s, below ANCE's minimum-drag speed (~35 m/s), the elevator-to-path sense reverses at low
  // frequency; the free-flight LQR gain asks for far more elevator than the limits give and the airplane
  // pitches up until it stalls. The run must end at the located stall, not at a step end.
  const LongitudinalModel model = Ance();
  LandingConfig config;
  config.start_speed_mps = 30.0;
  config.design_height_m = std::numeric_limits<double>::infinity();
  const LandingResult r = SimulateLanding(model, config);
  ASSERT_EQ(r.outcome, LandingOutcome::kStall) << r.message;
  EXPECT_NEAR(r.min_speed_mps, model.aircraft().stall_speed_mps, kLocatedEventTolerance);
  EXPECT_GT(r.saturated_time_s, 0.0);
}

TEST(LandingSimulation, DesignFailureIsAnOutcomeNotAnException) {
  const LongitudinalModel model = Ance();
  LandingConfig config;
  config.q_weights.fill(0.0);
  const LandingResult r = SimulateLanding(model, config);
  EXPECT_EQ(r.outcome, LandingOutcome::kDesignFailed);
  EXPECT_NE(r.message.find("not_detectable"), std::string::npos) << r.message;
  EXPECT_TRUE(r.series.empty());
}

TEST(LandingSimulation, HeightReferenceIsMootWithoutHDerivatives) {
  // Without Xh, Zh, Mh nothing multiplies ΔH, so where it is measured from cannot matter.
  const LongitudinalModel model = Ance(false);
  LandingConfig path;
  path.output_interval_s = 0.0;
  LandingConfig fixed = path;
  fixed.plant_height_reference = PlantHeightReference::kFixedHeight;
  fixed.plant_fixed_reference_height_m = 500.0;
  const LandingResult a = SimulateLanding(model, path);
  const LandingResult b = SimulateLanding(model, fixed);
  ASSERT_EQ(a.outcome, LandingOutcome::kLanded);
  EXPECT_EQ(a.touchdown_time_s, b.touchdown_time_s);
  EXPECT_EQ(a.touchdown_sink_rate_mps, b.touchdown_sink_rate_mps);
}

TEST(LandingSimulation, DefaultTimeLimitIsTwiceTheReferenceTrajectory) {
  const LongitudinalModel model = Ance();
  LandingConfig config;
  const double gamma_rad = config.glide_slope_deg * kRadPerDeg;
  const double tau_s = FlareTimeConstant(config);
  const double nominal_s =
      (config.start_height_m - config.flare_height_m) / (config.start_speed_mps * gamma_rad) +
      tau_s * std::log(config.flare_height_m / model.aircraft().wheel_contact_height_m);
  EXPECT_NEAR(NominalLandingTime(config, model.aircraft().wheel_contact_height_m), nominal_s,
              kClosedFormTolerance);
  EXPECT_NEAR(LandingTimeLimit(config, model.aircraft().wheel_contact_height_m), 2 * nominal_s,
              kClosedFormTolerance);
  config.time_limit_s = 42.0;
  EXPECT_EQ(LandingTimeLimit(config, model.aircraft().wheel_contact_height_m), 42.0);
}

TEST(LandingSimulation, ConcurrentRunsMatchSequentialOnes) {
  // The sweep runs landings on several threads: SB02OD, LAPACK and the run itself keep no shared state.
  const LongitudinalModel model = Ance();
  std::vector<LandingConfig> configs(4);
  for (std::size_t i = 0; i < configs.size(); ++i) {
    configs[i].output_interval_s = 0.0;
    configs[i].flare_height_m = 6.0 + 2.0 * static_cast<double>(i);
    configs[i].r_weight = 0.5 + static_cast<double>(i);
  }
  std::vector<LandingResult> sequential, concurrent(configs.size());
  for (const LandingConfig& c : configs) sequential.push_back(SimulateLanding(model, c));
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < configs.size(); ++i) {
    threads.emplace_back([&, i] { concurrent[i] = SimulateLanding(model, configs[i]); });
  }
  for (std::thread& t : threads) t.join();
  for (std::size_t i = 0; i < configs.size(); ++i) {
    EXPECT_EQ(sequential[i].outcome, concurrent[i].outcome);
    EXPECT_EQ(sequential[i].touchdown_time_s, concurrent[i].touchdown_time_s);
    EXPECT_EQ(sequential[i].design.gain, concurrent[i].design.gain);
  }
}

TEST(LandingSimulation, NoisePointOfTheSeedStreamIsTheSeededLanding) {
  // A subset simulation flies a landing from a point u of the standard-normal space
  // (NoisePointIndex's layout). The point filled with the seeded stream's own variates must give the
  // seeded landing bit for bit: the point is the same noise, not a re-parametrisation of it. The oracle
  // is the seeded landing itself (RunNoise(seed, run_index)), which the point path does not use.
  const LongitudinalModel model = Ance();
  LandingConfig config;
  config.start_height_m = 30.0;
  config.output_interval_s = 0.0;
  config.disturbance.wind_20ft_mps = -15.433333;
  config.disturbance.turbulence = TurbulenceModel::kDryden;
  config.seed = 2027;
  config.run_index = 11;
  const std::uint64_t dimension = LandingNoiseDimension(model.aircraft(), config);
  ASSERT_GT(dimension, 3u);
  const RunNoise seeded(config.seed, config.run_index);
  std::vector<double> point(dimension);
  for (std::uint64_t k = 0; k < 3; ++k) {
    point[NoisePointIndex(NoiseStream::kInitialState, k)] =
        seeded.StandardNormal(NoiseStream::kInitialState, k);
  }
  for (std::uint64_t k = 0; NoisePointIndex(NoiseStream::kTurbulenceW, k) < dimension; ++k) {
    point[NoisePointIndex(NoiseStream::kTurbulenceU, k)] =
        seeded.StandardNormal(NoiseStream::kTurbulenceU, k);
    point[NoisePointIndex(NoiseStream::kTurbulenceW, k)] =
        seeded.StandardNormal(NoiseStream::kTurbulenceW, k);
  }
  const LandingResult from_seed = SimulateLanding(model, config);
  const LandingResult from_point = SimulateLanding(model, config, nullptr, point);
  ASSERT_EQ(from_seed.outcome, LandingOutcome::kLanded);
  EXPECT_EQ(from_point.outcome, from_seed.outcome);
  EXPECT_EQ(from_point.touchdown_time_s, from_seed.touchdown_time_s);
  EXPECT_EQ(from_point.touchdown_sink_rate_mps, from_seed.touchdown_sink_rate_mps);
  EXPECT_EQ(from_point.touchdown_pitch_deg, from_seed.touchdown_pitch_deg);
  EXPECT_EQ(from_point.touchdown_distance_past_transmitter_m,
            from_seed.touchdown_distance_past_transmitter_m);
  // And the point is the noise: another point gives another landing.
  point[NoisePointIndex(NoiseStream::kTurbulenceW, 100)] += 3.0;
  EXPECT_NE(SimulateLanding(model, config, nullptr, point).touchdown_time_s, from_seed.touchdown_time_s);
  // A point shorter than the landing's noise is refused, not read past its end.
  point.resize(dimension - 1);
  EXPECT_THROW(SimulateLanding(model, config, nullptr, point), InputError);
}

TEST(LandingSimulation, InvalidConfigIsAnInputError) {
  const LongitudinalModel model = Ance();
  LandingConfig config;
  config.flare_height_m = 0.5;  // below the wheels
  EXPECT_THROW(SimulateLanding(model, config), InputError);
  config = LandingConfig{};
  config.start_speed_mps = 20.0;  // below the stall speed
  EXPECT_THROW(SimulateLanding(model, config), InputError);
  config = LandingConfig{};
  config.q_weights[3] = -1.0;
  try {
    SimulateLanding(model, config);
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_EQ(error.key(), "q_weights.delta_theta");
  }
}

}  // namespace
}  // namespace gesweep
