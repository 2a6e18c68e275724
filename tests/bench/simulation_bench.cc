// Benchmarks of the open-loop kernel (docs/simulation.md, "Performance"). The targets of issue 3:
// one 30 s RK4 run at 0.015 s (2000 steps) with the derivatives re-evaluated at every stage costs at
// most 3x the same run with A frozen at its initial value, and at most 60 us on one core.
#include <benchmark/benchmark.h>

#include <optional>
#include <random>
#include <string>

#include "engine/aircraft/aircraft.h"
#include "engine/aircraft/atmosphere.h"
#include "engine/simulation/derivative_kernel.h"
#include "engine/simulation/open_loop.h"

namespace gesweep {
namespace {

const Aircraft& Ance() {
  static const Aircraft aircraft = LoadAircraftFile(GESWEEP_SOURCE_DIR "/studies/aircraft/ance.toml");
  return aircraft;
}

const LongitudinalModel& Model(Interpolation interpolation) {
  static const LongitudinalModel linear(Ance(), ModelOptions{});
  static const LongitudinalModel pchip(Ance(), [] {
    ModelOptions options;
    options.interpolation = Interpolation::kPchip;
    return options;
  }());
  return interpolation == Interpolation::kLinear ? linear : pchip;
}

// The paper's run (Fig. 4) from the 2.9987 m start for 30 s: 2000 RK4 steps of 0.015 s.
OpenLoopConfig PaperRun() {
  OpenLoopConfig config;
  config.start_height_m = 2.9987;
  config.reference_speed_mps = 32.0208;
  config.duration_s = 30.0;
  return config;
}

void Report(benchmark::State& state, const OpenLoopResult& result) {
  state.counters["steps"] = static_cast<double>(result.summary.steps);
  state.counters["rhs_calls"] = static_cast<double>(result.summary.rhs_calls);
  // Seconds per right-hand-side call, integrator overhead included (printed with an SI prefix).
  state.counters["time_per_rhs"] =
      benchmark::Counter(static_cast<double>(result.summary.rhs_calls),
                         benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void Run(benchmark::State& state, const LongitudinalModel& model, const OpenLoopConfig& config) {
  OpenLoopResult result;
  for (auto _ : state) {
    result = SimulateOpenLoop(model, config);
    benchmark::DoNotOptimize(result.summary.final_state.data());
  }
  Report(state, result);
}

// 64 runs of the paper's 30 s run from heights spread over the table (1.5 to 14 m, so the lanes sit in
// different segments), flown one at a time by SimulateOpenLoop (width 0) or in lanes of the given
// width by SimulateOpenLoopBatch on the given instruction set (docs/performance.md, "Batched time
// responses", issue 28). An instruction set this CPU lacks is reported as skipped.
void BM_Rk4_30s_Batch(benchmark::State& state, std::optional<LanesIsa> isa) {
  constexpr int kRuns = 64;
  const int width = static_cast<int>(state.range(0));
  if (isa && !LanesIsaSupported(*isa)) {
    state.SkipWithError(("this CPU does not run " + std::string(ToString(*isa))).c_str());
    return;
  }
  std::vector<OpenLoopBatchRun> runs(kRuns);
  for (int i = 0; i < kRuns; ++i) {
    runs[static_cast<std::size_t>(i)].model = &Model(Interpolation::kLinear);
    runs[static_cast<std::size_t>(i)].config = PaperRun();
    runs[static_cast<std::size_t>(i)].config.start_height_m = 1.5 + 12.5 * i / (kRuns - 1);
  }
  long steps = 0;
  for (auto _ : state) {
    steps = 0;
    if (width == 0) {
      for (const auto& run : runs) {
        const OpenLoopResult result = SimulateOpenLoop(*run.model, run.config);
        steps += result.summary.steps;
        benchmark::DoNotOptimize(result.summary.final_state.data());
      }
    } else {
      const std::vector<OpenLoopResult> results = SimulateOpenLoopBatch(runs, width, nullptr, isa);
      for (const auto& result : results) steps += result.summary.steps;
      benchmark::DoNotOptimize(results.data());
    }
  }
  state.counters["steps"] = static_cast<double>(steps);
  state.counters["time_per_run"] =
      benchmark::Counter(kRuns, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK_CAPTURE(BM_Rk4_30s_Batch, one_at_a_time, std::nullopt)->Arg(0)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Rk4_30s_Batch, sse2, LanesIsa::kSse2)
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->Arg(8)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Rk4_30s_Batch, avx2, LanesIsa::kAvx2)
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->Arg(8)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Rk4_30s_Batch, avx512, LanesIsa::kAvx512)
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->Arg(8)
    ->Unit(benchmark::kMillisecond);

// The target: re-evaluation at every stage (linear table, fast path).
void BM_Rk4_30s_Reevaluated(benchmark::State& state) {
  Run(state, Model(Interpolation::kLinear), PaperRun());
}
BENCHMARK(BM_Rk4_30s_Reevaluated)->Unit(benchmark::kMicrosecond);

// The floor: the same run with A and B frozen at (H0, u0).
void BM_Rk4_30s_Frozen(benchmark::State& state) {
  OpenLoopConfig config = PaperRun();
  config.freeze_derivatives = true;
  Run(state, Model(Interpolation::kLinear), config);
}
BENCHMARK(BM_Rk4_30s_Frozen)->Unit(benchmark::kMicrosecond);

// The generic path: LongitudinalModel::DerivativesAt (table lookup by binary search, pow for rho).
void BM_Rk4_30s_GenericPath(benchmark::State& state) {
  OpenLoopConfig config = PaperRun();
  config.generic_derivative_path = true;
  Run(state, Model(Interpolation::kLinear), config);
}
BENCHMARK(BM_Rk4_30s_GenericPath)->Unit(benchmark::kMicrosecond);

// PCHIP interpolation, which always takes the generic path.
void BM_Rk4_30s_Pchip(benchmark::State& state) { Run(state, Model(Interpolation::kPchip), PaperRun()); }
BENCHMARK(BM_Rk4_30s_Pchip)->Unit(benchmark::kMicrosecond);

// Adaptive Dormand-Prince at rtol 1e-6, atol 1e-9 (breakpoints honoured).
void BM_Dopri5_30s_Reevaluated(benchmark::State& state) {
  OpenLoopConfig config = PaperRun();
  config.integrator.kind = IntegratorKind::kDopri5;
  Run(state, Model(Interpolation::kLinear), config);
}
BENCHMARK(BM_Dopri5_30s_Reevaluated)->Unit(benchmark::kMicrosecond);

// The 300 s paper run with a series every 0.015 s (what `gesweep simulate` does by default).
void BM_Rk4_300s_WithSeries(benchmark::State& state) {
  OpenLoopConfig config = PaperRun();
  config.duration_s = 300.0;
  config.series_interval_s = 0.015;
  Run(state, Model(Interpolation::kLinear), config);
}
BENCHMARK(BM_Rk4_300s_WithSeries)->Unit(benchmark::kMicrosecond);

// One evaluation of the fast kernel (LinearDerivativeTable::Equation1) at heights drawn across the
// ground-effect range: a new segment most of the time, so this is its worst case.
void BM_Equation1Kernel(benchmark::State& state) {
  const LinearDerivativeTable table(Model(Interpolation::kLinear));
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> offset(-2.0, 11.0);
  std::vector<double> offsets(1024);
  for (double& h : offsets) h = offset(random);
  int hint = 0;
  std::size_t i = 0;
  double x[5] = {0.1, -0.2, 0.01, 0.02, 0.0};
  double dxdt[5];
  for (auto _ : state) {
    x[4] = offsets[i++ & 1023];
    table.Equation1(2.9987, 32.0208, x, 0.01, dxdt, hint);
    benchmark::DoNotOptimize(dxdt);
  }
}
BENCHMARK(BM_Equation1Kernel);

void BM_DensityPolynomial(benchmark::State& state) {
  const DensityPolynomial density(0.0);
  double h = 2.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(h);
    double rho = density.At(h);
    benchmark::DoNotOptimize(rho);
  }
}
BENCHMARK(BM_DensityPolynomial);

void BM_IsaDensityPow(benchmark::State& state) {
  double h = 2.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(h);
    double rho = IsaDensity(h);
    benchmark::DoNotOptimize(rho);
  }
}
BENCHMARK(BM_IsaDensityPow);

}  // namespace
}  // namespace gesweep

BENCHMARK_MAIN();
