// SimulateLandingBatch (turbulent landings in SIMD lanes) against its oracle, SimulateLanding (tested in
// landing_simulation_test.cc and paper_landing_test.cc, and itself unchanged by the lanes): every
// result field and every series sample bit for bit, for every lane width, whichever landings share a
// batch and in whatever order, with landings ending at different steps (touchdowns from different
// heights, winds and seeds, a stall, a time limit in flight, a failed design), through the flare and
// its compensator reset, the pitch-rate gust, the fixed height reference, a noise point, stored series,
// and mixed with landings the lanes do not take; on every instruction set of the lanes this CPU runs
// (sse2, avx2, avx512), each skipped with a message when the CPU lacks it.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/common/errors.h"
#include "engine/control/landing_simulation.h"
#include "engine/disturbance/run_noise.h"
#include "tests/testing/test_paths.h"

namespace gesweep {

void PrintTo(LanesIsa isa, std::ostream* os) { *os << ToString(isa); }

namespace {

// Bit-for-bit equality of two doubles (NaN equal to the same NaN, +0 and -0 different).
bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

#define EXPECT_SAME_BITS(field, what)           \
  EXPECT_TRUE(SameBits(batch.field, one.field)) \
      << (what) << ": " #field " " << batch.field << " vs " << one.field

void ExpectSameSample(const LandingSample& batch, const LandingSample& one, const std::string& what) {
  EXPECT_SAME_BITS(time_s, what);
  EXPECT_EQ(batch.phase, one.phase) << what;
  EXPECT_SAME_BITS(height_m, what);
  EXPECT_SAME_BITS(reference_height_m, what);
  EXPECT_SAME_BITS(tracking_error_m, what);
  EXPECT_SAME_BITS(speed_mps, what);
  EXPECT_SAME_BITS(delta_w_mps, what);
  EXPECT_SAME_BITS(pitch_rate_radps, what);
  EXPECT_SAME_BITS(pitch_rad, what);
  EXPECT_SAME_BITS(sink_rate_mps, what);
  EXPECT_SAME_BITS(elevator_rad, what);
  EXPECT_SAME_BITS(elevator_command_rad, what);
  EXPECT_SAME_BITS(compensator, what);
  EXPECT_SAME_BITS(error_integral, what);
  EXPECT_SAME_BITS(distance_past_transmitter_m, what);
  EXPECT_SAME_BITS(u_g_mps, what);
  EXPECT_SAME_BITS(w_g_mps, what);
  EXPECT_SAME_BITS(q_g_radps, what);
}

void ExpectSameResult(const LandingResult& batch, const LandingResult& one, const std::string& what) {
  EXPECT_EQ(batch.outcome, one.outcome) << what;
  EXPECT_EQ(batch.message, one.message) << what;
  EXPECT_EQ(batch.design.status, one.design.status) << what;
  for (std::size_t j = 0; j < one.design.gain.size(); ++j) EXPECT_SAME_BITS(design.gain[j], what);
  EXPECT_SAME_BITS(design.design_height_m, what);
  EXPECT_SAME_BITS(design.closed_loop_max_real_per_s, what);
  EXPECT_SAME_BITS(flare_time_constant_s, what);
  EXPECT_SAME_BITS(flare_height_m, what);
  EXPECT_SAME_BITS(glide_slope_deg, what);
  EXPECT_SAME_BITS(plant_fixed_reference_height_m, what);
  EXPECT_EQ(batch.plant_h_derivatives, one.plant_h_derivatives) << what;
  EXPECT_SAME_BITS(time_limit_s, what);
  EXPECT_SAME_BITS(touchdown_time_s, what);
  EXPECT_SAME_BITS(touchdown_distance_past_transmitter_m, what);
  EXPECT_SAME_BITS(touchdown_sink_rate_mps, what);
  EXPECT_SAME_BITS(touchdown_pitch_deg, what);
  EXPECT_SAME_BITS(touchdown_speed_mps, what);
  EXPECT_SAME_BITS(touchdown_airspeed_mps, what);
  EXPECT_SAME_BITS(flare_start_time_s, what);
  EXPECT_SAME_BITS(glide_path_error_at_flare_m, what);
  EXPECT_SAME_BITS(max_abs_elevator_deg, what);
  EXPECT_SAME_BITS(max_abs_elevator_command_deg, what);
  EXPECT_SAME_BITS(max_abs_pitch_rate_degps, what);
  EXPECT_SAME_BITS(flare_max_abs_elevator_deg, what);
  EXPECT_SAME_BITS(flare_max_abs_pitch_rate_degps, what);
  EXPECT_SAME_BITS(saturated_time_s, what);
  EXPECT_SAME_BITS(longest_saturation_s, what);
  EXPECT_SAME_BITS(min_speed_mps, what);
  EXPECT_SAME_BITS(max_speed_mps, what);
  EXPECT_SAME_BITS(final_time_s, what);
  EXPECT_SAME_BITS(final_height_m, what);
  EXPECT_EQ(batch.accepted_steps, one.accepted_steps) << what;
  EXPECT_EQ(batch.rejected_steps, one.rejected_steps) << what;
  EXPECT_EQ(batch.rhs_calls, one.rhs_calls) << what;
  EXPECT_EQ(batch.cancelled, one.cancelled) << what;
  ASSERT_EQ(batch.series.size(), one.series.size()) << what;
  for (std::size_t k = 0; k < one.series.size(); ++k) {
    ExpectSameSample(batch.series[k], one.series[k], what + ", sample " + std::to_string(k));
    if (::testing::Test::HasFailure()) return;  // one sample's failures say enough
  }
}

#undef EXPECT_SAME_BITS

LongitudinalModel Ance(bool h_derivatives) {
  ModelOptions options;
  options.h_derivatives = h_derivatives;
  return LongitudinalModel(LoadAircraftFile(testing::AnceAircraftPath()), options);
}

// A turbulent landing from `height_m` in a headwind (negative) or tailwind of `wind_mps` at 20 ft.
LandingConfig Turbulent(double height_m, double wind_mps, std::uint64_t seed, std::uint64_t run_index) {
  LandingConfig c;
  c.start_height_m = height_m;
  c.output_interval_s = 0.0;
  c.disturbance.wind_20ft_mps = wind_mps;
  c.disturbance.turbulence = TurbulenceModel::kDryden;
  c.seed = seed;
  c.run_index = run_index;
  return c;
}

class LandingLanesTest : public ::testing::Test {
 protected:
  // The batch: landings that end at different steps and in each way the model allows, and two the
  // lanes do not take. The noise point lives as long as the fixture.
  std::vector<LandingBatchRun> Runs() {
    std::vector<LandingBatchRun> runs;
    auto add = [&](const LongitudinalModel& plant, const LandingConfig& config) {
      runs.push_back({&plant, config, {}});
    };
    const double heights[] = {30.0, 45.0, 60.0, 25.0, 80.0, 35.0};
    const double winds[] = {-7.717, -15.433, -3.0, 4.0, -10.0, -12.0};
    for (int k = 0; k < 6; ++k) {
      LandingConfig c = Turbulent(heights[k], winds[k], 2026 + static_cast<std::uint64_t>(k % 2),
                                  static_cast<std::uint64_t>(17 * k + 3));
      c.start_speed_mps = 45.0 + 3.0 * k;
      c.glide_slope_deg = 2.0 + 0.3 * k;
      if (k == 1) c.disturbance.pitch_rate_gust = true;
      if (k == 2) c.reset_compensator_at_flare = true;
      if (k == 3) c.output_interval_s = 0.1;  // a stored series
      if (k == 4) {
        c.plant_height_reference = PlantHeightReference::kFixedHeight;
        c.plant_fixed_reference_height_m = 20.0;
      }
      add(k % 3 == 2 ? without_ : with_, c);
    }
    {  // a time limit in flight
      LandingConfig c = Turbulent(40.0, -7.717, 7, 1);
      c.time_limit_s = 3.21;
      add(with_, c);
    }
    {  // a stall: slow, with the free-flight gain (landing_simulation_test's), in a gusty headwind
      LandingConfig c = Turbulent(40.0, -7.717, 7, 2);
      c.start_speed_mps = 30.0;
      c.design_height_m = std::numeric_limits<double>::infinity();
      add(with_, c);
    }
    {  // a failed design: complete at once, no lane
      LandingConfig c = Turbulent(40.0, -7.717, 7, 3);
      c.q_weights.fill(0.0);
      add(with_, c);
    }
    {  // flown from a noise point (the risk driver's landings)
      LandingConfig c = Turbulent(30.0, -15.433333, 2027, 11);
      c.glide_slope_deg = 3.0;
      point_.assign(LandingNoiseDimension(with_.aircraft(), c), 0.0);
      for (std::size_t j = 0; j < point_.size(); ++j)
        point_[j] = std::sin(0.37 * static_cast<double>(j) + 0.1);
      runs.push_back({&with_, c, point_});
    }
    {  // not in lanes: turbulence flown by dopri5, and still air
      LandingConfig c = Turbulent(30.0, -7.717, 9, 4);
      c.turbulent_integrator = IntegratorKind::kDopri5;
      add(with_, c);
      LandingConfig still;
      still.start_height_m = 30.0;
      still.output_interval_s = 0.0;
      add(without_, still);
    }
    return runs;
  }

  LongitudinalModel with_ = Ance(true);
  LongitudinalModel without_ = Ance(false);
  std::vector<double> point_;
};

class LandingLanesIsaTest : public LandingLanesTest, public ::testing::WithParamInterface<LanesIsa> {
 protected:
  void SetUp() override {
    if (!LanesIsaSupported(GetParam())) {
      GTEST_SKIP() << "this CPU does not run " << ToString(GetParam()) << " (or its operating system does "
                   << "not save its registers): its lanes are not tested here";
    }
  }
};

TEST_P(LandingLanesIsaTest, EveryWidthGivesEveryLandingsScalarResultBitForBit) {
  const std::vector<LandingBatchRun> runs = Runs();
  std::vector<LandingResult> one;
  for (const LandingBatchRun& run : runs) {
    one.push_back(SimulateLanding(*run.plant, run.config, nullptr, run.noise_point));
  }
  // The set must exercise what the lanes do differently from one landing: landings ending at
  // different steps, in each way, through the flare, and a series.
  int landed = 0, stalled = 0, in_flight = 0, failed = 0, flared = 0;
  std::vector<long> steps;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    landed += one[i].outcome == LandingOutcome::kLanded;
    stalled += one[i].outcome == LandingOutcome::kStall;
    in_flight += one[i].outcome == LandingOutcome::kNoTouchdown;
    failed += one[i].outcome == LandingOutcome::kDesignFailed;
    flared += !std::isnan(one[i].flare_start_time_s);
    if (LandingRunUsesLanes(*runs[i].plant, runs[i].config)) steps.push_back(one[i].accepted_steps);
  }
  EXPECT_GE(landed, 7);
  EXPECT_EQ(stalled, 1);
  EXPECT_EQ(in_flight, 1);
  EXPECT_EQ(failed, 1);
  EXPECT_GE(flared, 7);
  std::sort(steps.begin(), steps.end());
  EXPECT_EQ(std::unique(steps.begin(), steps.end()) - steps.begin(), static_cast<long>(steps.size()))
      << "the landings in lanes should end at different steps";
  EXPECT_FALSE(LandingRunUsesLanes(*runs[runs.size() - 2].plant, runs[runs.size() - 2].config));
  EXPECT_FALSE(LandingRunUsesLanes(*runs.back().plant, runs.back().config));

  for (int width : {1, 2, 4, 8}) {
    const std::vector<LandingResult> batch = SimulateLandingBatch(runs, width, nullptr, GetParam());
    ASSERT_EQ(batch.size(), runs.size());
    for (std::size_t i = 0; i < runs.size(); ++i) {
      ExpectSameResult(batch[i], one[i],
                       std::string(ToString(GetParam())) + " width " + std::to_string(width) + ", landing " +
                           std::to_string(i));
    }
  }
  // In reverse order, and each landing alone among idle lanes: another set of lane companions.
  std::vector<LandingBatchRun> reversed(runs.rbegin(), runs.rend());
  for (int width : {4, 8}) {
    const std::vector<LandingResult> batch = SimulateLandingBatch(reversed, width, nullptr, GetParam());
    for (std::size_t i = 0; i < runs.size(); ++i) {
      ExpectSameResult(batch[runs.size() - 1 - i], one[i],
                       std::string(ToString(GetParam())) + " reversed, width " + std::to_string(width) +
                           ", landing " + std::to_string(i));
    }
  }
  for (std::size_t i = 0; i < runs.size(); i += 3) {
    const std::vector<LandingResult> batch = SimulateLandingBatch({&runs[i], 1}, 8, nullptr, GetParam());
    ExpectSameResult(batch[0], one[i],
                     std::string(ToString(GetParam())) + " alone, landing " + std::to_string(i));
  }
}

INSTANTIATE_TEST_SUITE_P(Isa, LandingLanesIsaTest,
                         ::testing::Values(LanesIsa::kSse2, LanesIsa::kAvx2, LanesIsa::kAvx512),
                         [](const ::testing::TestParamInfo<LanesIsa>& info) {
                           return std::string(ToString(info.param));
                         });

TEST_F(LandingLanesTest, ACancelledBatchMarksItsLandingsCancelled) {
  std::vector<LandingBatchRun> runs = Runs();
  runs.resize(4);
  std::atomic<bool> cancel{true};
  const std::vector<LandingResult> batch = SimulateLandingBatch(runs, 4, &cancel);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const LandingResult one = SimulateLanding(*runs[i].plant, runs[i].config, &cancel);
    EXPECT_TRUE(batch[i].cancelled) << i;
    ExpectSameResult(batch[i], one, "cancelled landing " + std::to_string(i));
  }
}

TEST_F(LandingLanesTest, ABadLandingIsRefusedBeforeAnyIsFlown) {
  std::vector<LandingBatchRun> runs = Runs();
  runs[1].config.start_speed_mps = -1.0;
  EXPECT_THROW(SimulateLandingBatch(runs, 4), InputError);
}

}  // namespace
}  // namespace gesweep
