// SimulateOpenLoopBatch (many open-loop runs in SIMD lanes) against its oracle, SimulateOpenLoop
// (tested in open_loop_test.cc against the generic model path, the matrix exponential and closed
// forms): every run's summary bit for bit, for every lane width, whichever runs share a batch and in
// whatever order, with runs ending early (touchdown, stall), late (the time limit), at different
// steps and breakpoints, on two models, and mixed with runs the lanes do not take; on every
// instruction set of the lanes this CPU runs (sse2, avx2, avx512), each skipped with a message when
// the CPU lacks it.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

#include "engine/simulation/derivative_kernel.h"
#include "engine/simulation/open_loop.h"
#include "engine/simulation/open_loop_lanes.h"

namespace gesweep {

// The instruction set by name in the parameterized tests' messages.
void PrintTo(LanesIsa isa, std::ostream* os) { *os << ToString(isa); }

namespace {

constexpr double kPaperSpeed_mps = 32.0208;
constexpr double kRadPerDeg = std::numbers::pi / 180.0;

const Aircraft& Ance() {
  static const Aircraft aircraft = LoadAircraftFile(GESWEEP_SOURCE_DIR "/studies/aircraft/ance.toml");
  return aircraft;
}

// Bit-for-bit equality of two doubles (NaN equal to the same NaN, +0 and -0 different).
bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void ExpectSameSummary(const OpenLoopSummary& batch, const OpenLoopSummary& one, const std::string& what) {
  EXPECT_EQ(batch.end_event, one.end_event) << what;
  EXPECT_TRUE(SameBits(batch.end_time_s, one.end_time_s))
      << what << ": " << batch.end_time_s << " vs " << one.end_time_s;
  EXPECT_TRUE(SameBits(batch.min_height_m, one.min_height_m)) << what;
  EXPECT_TRUE(SameBits(batch.min_height_time_s, one.min_height_time_s)) << what;
  EXPECT_TRUE(SameBits(batch.max_abs_pitch_rate_radps, one.max_abs_pitch_rate_radps)) << what;
  for (int c = 0; c < 5; ++c) {
    EXPECT_TRUE(SameBits(batch.final_state[c], one.final_state[c]))
        << what << ": component " << c << " " << batch.final_state[c] << " vs " << one.final_state[c];
  }
  EXPECT_TRUE(SameBits(batch.final_height_m, one.final_height_m)) << what;
  EXPECT_TRUE(SameBits(batch.final_speed_mps, one.final_speed_mps)) << what;
  EXPECT_EQ(batch.steps, one.steps) << what;
  EXPECT_EQ(batch.rejected_steps, one.rejected_steps) << what;
  EXPECT_EQ(batch.rhs_calls, one.rhs_calls) << what;
  EXPECT_EQ(batch.message, one.message) << what;
  EXPECT_EQ(batch.cancelled, one.cancelled) << what;
}

// A spread of runs: heights from near the wheels to free flight, speeds from near the stall up,
// every input kind, inputs starting on and between grid points, other steps and time limits.
std::vector<OpenLoopBatchRun> Runs(const LongitudinalModel& with, const LongitudinalModel& without) {
  std::vector<OpenLoopBatchRun> runs;
  std::mt19937_64 random(20261204);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const ElevatorInputKind kinds[] = {ElevatorInputKind::kPulse, ElevatorInputKind::kStep,
                                     ElevatorInputKind::kDoublet, ElevatorInputKind::kNone};
  for (int k = 0; k < 37; ++k) {
    OpenLoopBatchRun run;
    run.model = k % 3 == 2 ? &without : &with;
    OpenLoopConfig& c = run.config;
    c.start_height_m = 1.2 + 20.0 * unit(random) * unit(random);
    c.reference_speed_mps = 26.0 + 14.0 * unit(random);
    c.elevator.kind = kinds[k % 4];
    c.elevator.amplitude_rad = (k % 5 == 0 ? -8.0 : 5.0) * kRadPerDeg * unit(random);
    c.elevator.duration_s = 0.1 + 0.4 * unit(random);
    c.elevator.start_s = k % 2 == 0 ? 0.0 : 0.5 * unit(random);  // off the grid: a breakpoint inside a step
    c.duration_s = k % 7 == 0 ? 3.0 + 2.0 * unit(random) : 40.0;
    c.integrator.step_s = k % 4 == 3 ? 0.01 : 0.015;
    c.initial_offsets.delta_normal_velocity_mps = 0.5 * (unit(random) - 0.5);
    if (k % 6 == 1) {  // towards the stall: just above it, nose up, high above the ground
      c.start_height_m = 12.0 + 2.0 * unit(random);
      c.reference_speed_mps = 25.0 + unit(random);
      c.elevator.kind = ElevatorInputKind::kStep;
      c.elevator.amplitude_rad = -(2.0 + 4.0 * unit(random)) * kRadPerDeg;
    }
    runs.push_back(run);
  }
  return runs;
}

class OpenLoopBatchTest : public ::testing::Test {
 protected:
  LongitudinalModel with_{Ance(), ModelOptions{}};
  LongitudinalModel without_{Ance(), [] {
                               ModelOptions o;
                               o.h_derivatives = false;
                               return o;
                             }()};
};

// The tests below run once per instruction set, skipped on a CPU without it.
class OpenLoopBatchIsaTest : public OpenLoopBatchTest, public ::testing::WithParamInterface<LanesIsa> {
 protected:
  void SetUp() override {
    if (!LanesIsaSupported(GetParam())) {
      GTEST_SKIP() << "this CPU does not run " << ToString(GetParam()) << " (or its operating system does "
                   << "not save its registers): its lanes are not tested here";
    }
  }
  std::string Name() const { return std::string(ToString(GetParam())); }
};

TEST_P(OpenLoopBatchIsaTest, EveryWidthGivesEveryRunsScalarResultBitForBit) {
  const std::vector<OpenLoopBatchRun> runs = Runs(with_, without_);
  std::vector<OpenLoopResult> one;
  for (const auto& run : runs) one.push_back(SimulateOpenLoop(*run.model, run.config));
  // The set must exercise what the lanes do differently from one run: runs ending early, at the
  // time limit, and after the others.
  int touchdowns = 0, limits = 0, stalls = 0;
  for (const auto& r : one) {
    touchdowns += r.summary.end_event == OpenLoopEndEvent::kTouchdown;
    limits += r.summary.end_event == OpenLoopEndEvent::kTimeLimit;
    stalls += r.summary.end_event == OpenLoopEndEvent::kStall;
  }
  EXPECT_GE(touchdowns, 3);
  EXPECT_GE(limits, 3);
  EXPECT_GE(stalls, 1);
  for (int width : kOpenLoopBatchWidths) {
    const std::vector<OpenLoopResult> batch = SimulateOpenLoopBatch(runs, width, nullptr, GetParam());
    ASSERT_EQ(batch.size(), runs.size());
    for (std::size_t i = 0; i < runs.size(); ++i) {
      ExpectSameSummary(batch[i].summary, one[i].summary,
                        Name() + ", width " + std::to_string(width) + ", run " + std::to_string(i));
    }
  }
}

TEST_P(OpenLoopBatchIsaTest, ARunsResultDoesNotDependOnTheRunsBesideIt) {
  std::vector<OpenLoopBatchRun> runs = Runs(with_, without_);
  std::vector<OpenLoopResult> one;
  for (const auto& run : runs) one.push_back(SimulateOpenLoop(*run.model, run.config));
  for (int width : {4, 8}) {
    std::vector<OpenLoopBatchRun> reversed(runs.rbegin(), runs.rend());
    const std::vector<OpenLoopResult> backward = SimulateOpenLoopBatch(reversed, width, nullptr, GetParam());
    for (std::size_t i = 0; i < runs.size(); ++i) {
      ExpectSameSummary(
          backward[runs.size() - 1 - i].summary, one[i].summary,
          Name() + ", width " + std::to_string(width) + ", run " + std::to_string(i) + " reversed");
    }
  }
  // Alone in a batch of 8: seven idle lanes beside it.
  for (std::size_t i : {0u, 5u, 11u}) {
    const std::vector<OpenLoopResult> alone =
        SimulateOpenLoopBatch(std::span(&runs[i], 1), 8, nullptr, GetParam());
    ExpectSameSummary(alone[0].summary, one[i].summary, Name() + ", run " + std::to_string(i) + " alone");
  }
}

// Eq. (1)'s kernel of the instruction set on W lanes against the scalar kernel, lane by lane: lanes on
// two tables, in different segments, some outside the density polynomial's band.
template <int W>
void ExpectKernelLanesAreTheScalarKernel(LanesIsa isa, const LinearDerivativeTable& a,
                                         const LinearDerivativeTable& b) {
  const lanes::RkKernels<lanes::StepArrays<W>> kernels = lanes::KernelsFor<lanes::OpenLoopKernels, W>(isa);
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  // One set of arrays for every trial: the kernel keeps the lanes' gathered segments across calls
  // (StepArrays::gathered), and the lanes change tables and segments from trial to trial.
  lanes::StepArrays<W> lanes;
  for (int trial = 0; trial < 200; ++trial) {
    for (int i = 0; i < W; ++i) {
      lanes.table[i] = (trial / 3 + i) % 2 == 0 ? &a : &b;  // kept for three trials
      lanes.h0[i] = (trial + i) % 17 == 0 ? 800.0 : 5.0 + 4.0 * unit(random);
      lanes.u0[i] = 32.0 + 5.0 * unit(random);
      for (int c = 0; c < 5; ++c) lanes.x[c][i] = (c == 4 ? 4.0 : 1.0) * unit(random);
      lanes.elevator[i] = 0.1 * unit(random);
      lanes.hint[i] = 0;
    }
    kernels.derivatives(lanes);
    for (int i = 0; i < W; ++i) {
      double xi[5], di[5];
      for (int c = 0; c < 5; ++c) xi[c] = lanes.x[c][i];
      int hint = 0;
      lanes.table[i]->Equation1(lanes.h0[i], lanes.u0[i], xi, lanes.elevator[i], di, hint);
      for (int c = 0; c < 5; ++c) {
        EXPECT_TRUE(SameBits(lanes.f[c][i], di[c])) << ToString(isa) << ", width " << W << ", trial " << trial
                                                    << ", lane " << i << ", component " << c;
      }
    }
  }
}

TEST_P(OpenLoopBatchIsaTest, Equation1OnEachLaneIsTheScalarKernelBitForBit) {
  const LinearDerivativeTable a(with_), b(without_);
  ExpectKernelLanesAreTheScalarKernel<1>(GetParam(), a, b);
  ExpectKernelLanesAreTheScalarKernel<2>(GetParam(), a, b);
  ExpectKernelLanesAreTheScalarKernel<4>(GetParam(), a, b);
  ExpectKernelLanesAreTheScalarKernel<8>(GetParam(), a, b);
}

INSTANTIATE_TEST_SUITE_P(EveryIsa, OpenLoopBatchIsaTest,
                         ::testing::Values(LanesIsa::kSse2, LanesIsa::kAvx2, LanesIsa::kAvx512),
                         [](const ::testing::TestParamInfo<LanesIsa>& info) {
                           return std::string(ToString(info.param));
                         });

TEST_F(OpenLoopBatchTest, RunsTheLanesDoNotTakeAreFlownOneAtATimeInPlace) {
  std::vector<OpenLoopBatchRun> runs = Runs(with_, without_);
  runs.resize(12);
  runs[3].config.integrator.kind = IntegratorKind::kDopri5;
  runs[6].config.disturbance.wind_20ft_mps = -5.0;
  runs[9].config.freeze_derivatives = true;
  runs[10].config.series_interval_s = 0.1;
  EXPECT_FALSE(OpenLoopRunUsesLanes(*runs[3].model, runs[3].config));
  EXPECT_FALSE(OpenLoopRunUsesLanes(*runs[6].model, runs[6].config));
  EXPECT_FALSE(OpenLoopRunUsesLanes(*runs[9].model, runs[9].config));
  EXPECT_FALSE(OpenLoopRunUsesLanes(*runs[10].model, runs[10].config));
  EXPECT_TRUE(OpenLoopRunUsesLanes(*runs[0].model, runs[0].config));
  const std::vector<OpenLoopResult> batch = SimulateOpenLoopBatch(runs, 2);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const OpenLoopResult one = SimulateOpenLoop(*runs[i].model, runs[i].config);
    ExpectSameSummary(batch[i].summary, one.summary, "run " + std::to_string(i));
    EXPECT_EQ(batch[i].series.time_s.size(), one.series.time_s.size());
  }
}

TEST_F(OpenLoopBatchTest, ACancelledBatchCancelsEveryRunAsOneRunIs) {
  const std::vector<OpenLoopBatchRun> runs = Runs(with_, without_);
  std::atomic<bool> cancel{true};
  const std::vector<OpenLoopResult> batch = SimulateOpenLoopBatch(runs, 4, &cancel);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const OpenLoopResult one = SimulateOpenLoop(*runs[i].model, runs[i].config, &cancel);
    EXPECT_TRUE(batch[i].summary.cancelled);
    ExpectSameSummary(batch[i].summary, one.summary, "run " + std::to_string(i));
  }
}

TEST_F(OpenLoopBatchTest, ABadConfigIsRefusedBeforeAnyRunIsFlown) {
  std::vector<OpenLoopBatchRun> runs = Runs(with_, without_);
  runs[4].config.start_height_m = 0.1;  // below the wheels
  EXPECT_THROW(SimulateOpenLoopBatch(runs, 4), InputError);
}

// The flags Linux reports for the CPU (/proc/cpuinfo), which it clears for registers it does not save.
std::optional<std::string> CpuFlags() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("flags", 0) == 0) return " " + line.substr(line.find(':') + 1) + " ";
  }
  return std::nullopt;
}

TEST(LanesIsaTest, TheInstructionSetsSupportedAreThoseLinuxReports) {
  const std::optional<std::string> flags = CpuFlags();
  if (!flags) GTEST_SKIP() << "no flags line in /proc/cpuinfo";
  auto has = [&](const char* flag) {
    return flags->find(" " + std::string(flag) + " ") != std::string::npos;
  };
  EXPECT_TRUE(LanesIsaSupported(LanesIsa::kSse2));
  EXPECT_EQ(LanesIsaSupported(LanesIsa::kAvx2), has("avx2"));
  EXPECT_EQ(LanesIsaSupported(LanesIsa::kAvx512), has("avx512f") && has("avx512dq") && has("avx512vl"));
  EXPECT_EQ(SupportedLanesIsas().front(), LanesIsa::kSse2);
}

// Sets GESWEEP_LANES_ISA for one test, and unsets it after.
class ForcedIsa {
 public:
  explicit ForcedIsa(const char* value) { setenv(kLanesIsaVariable, value, 1); }
  ~ForcedIsa() { unsetenv(kLanesIsaVariable); }
  ForcedIsa(const ForcedIsa&) = delete;
  ForcedIsa& operator=(const ForcedIsa&) = delete;
};

TEST(LanesIsaTest, UnforcedTheWidestInstructionSetWhoseVectorFitsTheWidthIsChosen) {
  unsetenv(kLanesIsaVariable);
  const bool avx2 = LanesIsaSupported(LanesIsa::kAvx2), avx512 = LanesIsaSupported(LanesIsa::kAvx512);
  EXPECT_EQ(ChooseLanesIsa(1), LanesIsa::kSse2);
  EXPECT_EQ(ChooseLanesIsa(2), LanesIsa::kSse2);
  EXPECT_EQ(ChooseLanesIsa(4), avx2 ? LanesIsa::kAvx2 : LanesIsa::kSse2);
  EXPECT_EQ(ChooseLanesIsa(8), avx512 ? LanesIsa::kAvx512 : avx2 ? LanesIsa::kAvx2 : LanesIsa::kSse2);
}

TEST(LanesIsaTest, TheEnvironmentForcesAnInstructionSetThisCpuRuns) {
  for (LanesIsa isa : SupportedLanesIsas()) {
    const ForcedIsa forced(std::string(ToString(isa)).c_str());
    for (int width : kOpenLoopBatchWidths) EXPECT_EQ(ChooseLanesIsa(width), isa) << ToString(isa);
  }
  {
    const ForcedIsa forced("");
    EXPECT_EQ(ChooseLanesIsa(2), LanesIsa::kSse2);  // empty: as unset
  }
  for (const char* wrong : {"AVX2", "avx512f", "neon", " sse2"}) {
    const ForcedIsa forced(wrong);
    try {
      ChooseLanesIsa(4);
      ADD_FAILURE() << wrong << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), "environment");
      EXPECT_EQ(e.key(), "GESWEEP_LANES_ISA");
      EXPECT_NE(e.expected().find("sse2, avx2 or avx512"), std::string::npos) << e.expected();
    }
  }
}

TEST(LanesIsaTest, AnInstructionSetThisCpuLacksIsRefusedBeforeAnyRunIsFlown) {
  std::optional<LanesIsa> lacking;
  for (LanesIsa isa : {LanesIsa::kAvx2, LanesIsa::kAvx512}) {
    if (!LanesIsaSupported(isa)) lacking = isa;
  }
  if (!lacking) GTEST_SKIP() << "this CPU runs every instruction set of the lanes";
  const ForcedIsa forced(std::string(ToString(*lacking)).c_str());
  const LongitudinalModel model(Ance(), ModelOptions{});
  std::vector<OpenLoopBatchRun> runs(1);
  runs[0].model = &model;
  runs[0].config.start_height_m = 5.0;
  runs[0].config.reference_speed_mps = 32.0;
  EXPECT_THROW(SimulateOpenLoopBatch(runs, 4), InputError);
}

TEST_F(OpenLoopBatchTest, ABatchForcedByTheEnvironmentGivesTheScalarResults) {
  std::vector<OpenLoopBatchRun> runs = Runs(with_, without_);
  runs.resize(9);
  for (LanesIsa isa : SupportedLanesIsas()) {
    const ForcedIsa forced(std::string(ToString(isa)).c_str());
    const std::vector<OpenLoopResult> batch = SimulateOpenLoopBatch(runs, 8);
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const OpenLoopResult one = SimulateOpenLoop(*runs[i].model, runs[i].config);
      ExpectSameSummary(batch[i].summary, one.summary,
                        std::string(ToString(isa)) + ", run " + std::to_string(i));
    }
  }
  const ForcedIsa forced("sse4");
  EXPECT_THROW(SimulateOpenLoopBatch(runs, 8), InputError);
}

}  // namespace
}  // namespace gesweep
