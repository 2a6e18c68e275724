// The paper's open-loop experiment (Section IV, Fig. 4; docs/model.md §7) against the paper's own
// claims. The 2.9987 m case, where this engine disagrees with the paper, is documented in
// docs/simulation.md rather than tested (its numbers would come from the code under test).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "engine/simulation/open_loop.h"

namespace gesweep {
namespace {

constexpr double kPaperSpeed_mps = 32.0208;

const Aircraft& Ance() {
  static const Aircraft aircraft = LoadAircraftFile(GESWEEP_SOURCE_DIR "/studies/aircraft/ance.toml");
  return aircraft;
}

OpenLoopConfig PaperConfig(double start_height_m) {
  OpenLoopConfig config;
  config.start_height_m = start_height_m;
  config.reference_speed_mps = kPaperSpeed_mps;
  return config;  // +5° for 0.2 s, RK4 at 0.015 s, 300 s: docs/model.md §7's defaults
}

class PaperFigure4Test : public ::testing::TestWithParam<double> {};

TEST_P(PaperFigure4Test, LowStartsTouchDown) {
  // Paper, Section IV: "for starting heights equal to or lower than 2.5935 m, the airplane sinks
  // to the ground".
  const LongitudinalModel model(Ance(), ModelOptions{});
  const OpenLoopSummary s = SimulateOpenLoop(model, PaperConfig(GetParam())).summary;
  EXPECT_EQ(s.end_event, OpenLoopEndEvent::kTouchdown) << "H0 = " << GetParam();
  EXPECT_LT(s.end_time_s, 300.0);
}
INSTANTIATE_TEST_SUITE_P(TableA2, PaperFigure4Test,
                         ::testing::Values(1.0374, 1.2968, 1.5561, 2.0748, 2.5935));

class PaperFigure4HighTest : public ::testing::TestWithParam<double> {};

TEST_P(PaperFigure4HighTest, HighStartsStayAirborneAndConverge) {
  // Paper: "For greater heights [than 2.9987 m], the aircraft shows a convergent and damped
  // response": no touchdown or stall in 300 s, and the oscillation decays (the largest |q| in the
  // last 100 s is below that in 10–110 s, after the short period).
  const LongitudinalModel model(Ance(), ModelOptions{});
  OpenLoopConfig config = PaperConfig(GetParam());
  config.series_interval_s = 0.015;
  const OpenLoopResult result = SimulateOpenLoop(model, config);
  EXPECT_EQ(result.summary.end_event, OpenLoopEndEvent::kTimeLimit) << "H0 = " << GetParam();
  double early = 0, late = 0;
  for (std::size_t j = 0; j < result.series.time_s.size(); ++j) {
    const double t = result.series.time_s[j];
    const double q = std::abs(result.series.pitch_rate_radps[j]);
    if (t >= 10 && t <= 110) early = std::max(early, q);
    if (t >= 200) late = std::max(late, q);
  }
  EXPECT_LT(late, early) << "H0 = " << GetParam();
}
INSTANTIATE_TEST_SUITE_P(TableA2, PaperFigure4HighTest, ::testing::Values(5.5922, 8.1857, 10.779, 13.373));

}  // namespace
}  // namespace gesweep
