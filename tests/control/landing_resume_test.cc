// ResumeLanding against its oracle, the unbroken SimulateLanding (tested in landing_simulation_test.cc
// and paper_landing_test.cc): a turbulent landing saved at a step of the approach, of the flare and
// just before its touchdown and flown on with its own noise lands where the unbroken one does, bit for
// bit (RK4's steps end on the noise's breakpoints, k·dt exactly, whatever time they start from; the
// extremes, read also on a 0.05 s grid that restarts at the checkpoint, agree here too); flown on with other
// noise it reads none of the noise held before the checkpoint (a point whose earlier samples are absurd gives
// the same landing bit for bit); a checkpoint that does not fit the config is refused. The observer sees
// every RK4 step on the noise's grid.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/common/errors.h"
#include "engine/control/landing_simulation.h"
#include "engine/disturbance/run_noise.h"
#include "tests/testing/test_paths.h"

namespace gesweep {
namespace {

LongitudinalModel Ance() {
  return LongitudinalModel(LoadAircraftFile(testing::AnceAircraftPath()), ModelOptions{});
}

// A turbulent landing from 30 m in a 15 m/s headwind at 20 ft.
LandingConfig Turbulent(std::uint64_t run_index) {
  LandingConfig c;
  c.start_height_m = 30.0;
  c.output_interval_s = 0.0;
  c.disturbance.wind_20ft_mps = -15.433333;
  c.disturbance.turbulence = TurbulenceModel::kDryden;
  c.seed = 2026;
  c.run_index = run_index;
  return c;
}

// The landing flown whole, with checkpoints saved at the first step past each of `times_s` and at
// every step (the last few kept), and the step times seen.
struct Watched {
  LandingResult result;
  std::vector<LandingCheckpoint> saved;
  std::vector<LandingCheckpoint> last_steps;
  std::vector<double> step_times_s;
};

Watched FlyWatched(const LongitudinalModel& plant, const LandingConfig& config, std::vector<double> times_s) {
  Watched w;
  std::size_t next = 0;
  const LandingObserver observer = [&](const LandingStep& step) {
    w.step_times_s.push_back(step.time_s());
    if (next < times_s.size() && step.time_s() >= times_s[next]) {
      w.saved.push_back(step.Checkpoint());
      ++next;
    }
    if (step.height_m() < 1.5) {
      w.last_steps.push_back(step.Checkpoint());
      if (w.last_steps.size() > 3) w.last_steps.erase(w.last_steps.begin());
    }
  };
  w.result = SimulateLanding(plant, config, nullptr, {}, &observer);
  return w;
}

TEST(LandingResumeTest, FlownOnWithItsOwnNoiseLandsWhereTheUnbrokenLandingDoes) {
  const LongitudinalModel plant = Ance();
  const LandingConfig config = Turbulent(3);
  const Watched whole = FlyWatched(plant, config, {5.0, 0.0});
  ASSERT_EQ(whole.result.outcome, LandingOutcome::kLanded) << whole.result.message;
  // The observer saw the start and every grid step of 0.01 s (a step cut at the flare switch and the
  // touchdown are the only others).
  ASSERT_GT(whole.step_times_s.size(), 100u);
  EXPECT_EQ(whole.step_times_s.front(), 0.0);
  EXPECT_EQ(whole.step_times_s[1], 0.01);  // the first breakpoint, 1 x 0.01 s
  EXPECT_EQ(whole.step_times_s.back(), whole.result.touchdown_time_s);

  // A checkpoint in the flare: the first step past the flare switch.
  const double flare_s = whole.result.flare_start_time_s;
  ASSERT_TRUE(std::isfinite(flare_s));
  const Watched again = FlyWatched(plant, config, {5.0, flare_s + 0.5});
  ASSERT_EQ(again.saved.size(), 2u);
  EXPECT_EQ(again.saved[1].flight.phase, LandingPhase::kFlare);
  std::vector<LandingCheckpoint> points = again.saved;
  ASSERT_EQ(again.last_steps.size(), 3u);
  points.push_back(again.last_steps[0]);  // two steps before the touchdown
  for (const LandingCheckpoint& c : points) {
    SCOPED_TRACE("resumed at t = " + std::to_string(c.time_s));
    const LandingResult r = ResumeLanding(plant, config, c);
    ASSERT_EQ(r.outcome, LandingOutcome::kLanded) << r.message;
    EXPECT_EQ(r.touchdown_time_s, whole.result.touchdown_time_s);
    EXPECT_EQ(r.touchdown_sink_rate_mps, whole.result.touchdown_sink_rate_mps);
    EXPECT_EQ(r.touchdown_pitch_deg, whole.result.touchdown_pitch_deg);
    EXPECT_EQ(r.touchdown_distance_past_transmitter_m, whole.result.touchdown_distance_past_transmitter_m);
    EXPECT_EQ(r.flare_start_time_s, whole.result.flare_start_time_s);
    EXPECT_EQ(r.max_abs_elevator_deg, whole.result.max_abs_elevator_deg);
    EXPECT_EQ(r.min_speed_mps, whole.result.min_speed_mps);
    EXPECT_EQ(r.saturated_time_s, whole.result.saturated_time_s);
  }
}

TEST(LandingResumeTest, ABranchReadsNoNoiseHeldBeforeItsCheckpoint) {
  const LongitudinalModel plant = Ance();
  const LandingConfig config = Turbulent(5);
  const Watched whole = FlyWatched(plant, config, {8.0});
  ASSERT_EQ(whole.saved.size(), 1u);
  const LandingCheckpoint& c = whole.saved[0];

  // Another run index's noise from the checkpoint on: a point holding RunNoise(2026, 77)'s samples from
  // the checkpoint's sample on, and 40 (a 40-sigma gust) before it.
  LandingConfig branch = config;
  branch.run_index = 77;
  const LandingResult by_stream = ResumeLanding(plant, branch, c);
  ASSERT_EQ(by_stream.outcome, LandingOutcome::kLanded) << by_stream.message;
  EXPECT_NE(by_stream.touchdown_sink_rate_mps, whole.result.touchdown_sink_rate_mps);

  const std::uint64_t dimension = LandingNoiseDimension(plant.aircraft(), config);
  const RunNoise noise(2026, 77);
  const auto first_sample = static_cast<std::uint64_t>(std::llround(c.time_s / 0.01));
  std::vector<double> point(dimension, 40.0);
  for (std::uint64_t k = first_sample; NoisePointIndex(NoiseStream::kTurbulenceW, k) < dimension; ++k) {
    point[NoisePointIndex(NoiseStream::kTurbulenceU, k)] = noise.StandardNormal(NoiseStream::kTurbulenceU, k);
    point[NoisePointIndex(NoiseStream::kTurbulenceW, k)] = noise.StandardNormal(NoiseStream::kTurbulenceW, k);
  }
  const LandingResult by_point = ResumeLanding(plant, config, c, nullptr, point);
  EXPECT_EQ(by_point.outcome, by_stream.outcome);
  EXPECT_EQ(by_point.touchdown_time_s, by_stream.touchdown_time_s);
  EXPECT_EQ(by_point.touchdown_sink_rate_mps, by_stream.touchdown_sink_rate_mps);
  EXPECT_EQ(by_point.max_abs_pitch_rate_degps, by_stream.max_abs_pitch_rate_degps);
}

TEST(LandingResumeTest, ACheckpointThatDoesNotFitTheConfigIsRefused) {
  const LongitudinalModel plant = Ance();
  const Watched whole = FlyWatched(plant, Turbulent(1), {4.0});
  ASSERT_EQ(whole.saved.size(), 1u);
  LandingConfig still = Turbulent(1);
  still.disturbance.turbulence = TurbulenceModel::kNone;
  still.disturbance.wind_20ft_mps = 0.0;
  EXPECT_THROW(ResumeLanding(plant, still, whole.saved[0]), InputError);
  LandingCheckpoint empty;
  EXPECT_THROW(ResumeLanding(plant, Turbulent(1), empty), InputError);
}

}  // namespace
}  // namespace gesweep
