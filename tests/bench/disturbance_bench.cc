// The cost of the moving atmosphere (docs/disturbance.md): one DisturbanceField::Evaluate, and a 30 s
// flight of Eq. (1) at 30 m and 52.21 m/s (the landing's speed) in still air and in 30 kt Dryden
// turbulence with the noise held over Δt_n (filters integrated as extra states, the sample instants
// as breakpoints), with RK4 at 0.015 s and with dopri5 at the landing's tolerances (1e-3, 1e-6).
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/disturbance/disturbance_field.h"
#include "engine/disturbance/mean_wind.h"
#include "engine/simulation/derivative_kernel.h"
#include "engine/simulation/integrator.h"

namespace gesweep {
namespace {

const LongitudinalModel& Model() {
  static const LongitudinalModel model(LoadAircraftFile(GESWEEP_SOURCE_DIR "/studies/aircraft/ance.toml"),
                                       ModelOptions{});
  return model;
}
const LinearDerivativeTable& Table() {
  static const LinearDerivativeTable table(Model());
  return table;
}

constexpr double kStartHeight_m = 30.0;
constexpr double kSpeed_mps = 52.21;
constexpr double kDuration_s = 30.0;

DisturbanceOptions Moderate(double sample_interval_s) {
  DisturbanceOptions o;
  o.wind_20ft_mps = -15.433;  // 30 kt headwind with shear, σ_w = 1.54 m/s
  o.turbulence = TurbulenceModel::kDryden;
  o.turbulence_sample_interval_s = sample_interval_s;
  return o;
}

// Still air on today's fast kernel (the floor).
struct StillAir {
  static constexpr int kDimension = 5;
  static constexpr int kEventCount = 0;
  int hint = 0;
  void Derivative(double, const OdeState<5>& x, int, OdeState<5>& dxdt) {
    Table().Equation1(kStartHeight_m, kSpeed_mps, x.data(), 0.0, dxdt.data(), hint);
  }
  void EventValues(double, const OdeState<5>&, int, std::array<double, 0>&) const {}
  EventAction OnEvent(int, double, const OdeState<5>&, int) { return EventAction::kContinue; }
  void OnStep(double, const OdeState<5>&, int) {}
  void OnOutput(double, const OdeState<5>&, int) {}
};

// Eq. (1) in air-relative form (table derivatives at the airspeed) with the field's 5 states.
struct InTurbulence {
  static constexpr int kDimension = 10;
  static constexpr int kEventCount = 0;
  const DisturbanceField* field;
  const std::vector<DisturbanceField::Segment>* table;
  int hint = 0;
  void Derivative(double, const OdeState<10>& x, int segment, OdeState<10>& dxdt) {
    DisturbanceField::State xf, dxf;
    std::copy(x.begin() + 5, x.end(), xf.begin());
    const double h = kStartHeight_m + x[kDeltaH];
    const AirMotion air = field->Evaluate((*table)[segment], h, kSpeed_mps + x[kDeltaU], xf, dxf);
    const DimensionalDerivatives d = Table().DerivativesAt(h, air.airspeed_mps, hint);
    const Vector5d x5(x[0], x[1], x[2], x[3], x[4]);
    const Vector5d d5 = AirRelativeDerivative(
        d, kSpeed_mps, x5, 0.0, AirVelocity{air.u_g_mps, air.w_g_mps, air.q_g_radps, air.w_g_dot_mps2});
    for (int i = 0; i < 5; ++i) dxdt[i] = d5[i];
    std::copy(dxf.begin(), dxf.end(), dxdt.begin() + 5);
  }
  void EventValues(double, const OdeState<10>&, int, std::array<double, 0>&) const {}
  EventAction OnEvent(int, double, const OdeState<10>&, int) { return EventAction::kContinue; }
  void OnStep(double, const OdeState<10>&, int) {}
  void OnOutput(double, const OdeState<10>&, int) {}
};

// kind 0: RK4 at the paper's 0.015 s; 1: dopri5 at the landing's tolerances; 2: RK4 with its step
// equal to Δt_n (every breakpoint on the grid: no split steps).
IntegratorOptions Options(int kind, double sample_interval_s = 0.0) {
  IntegratorOptions io;
  if (kind == 2) io.step_s = sample_interval_s;
  if (kind == 1) {
    io.kind = IntegratorKind::kDopri5;
    io.relative_tolerance = 1e-3;
    io.absolute_tolerance = 1e-6;
    io.max_step_s = 1.0;
  }
  return io;
}

template <int N>
void Report(benchmark::State& state, const IntegrationResult<N>& r) {
  state.counters["steps"] = static_cast<double>(r.accepted_steps + r.rejected_steps);
  state.counters["rhs_calls"] = static_cast<double>(r.rhs_calls);
}

void BM_Flight30s_StillAir(benchmark::State& state) {
  IntegrationResult<5> r;
  for (auto _ : state) {
    StillAir problem;
    r = Integrate(problem, OdeState<5>{0.5, 0.0, 0.0, 0.0, 0.0}, 0.0, kDuration_s, {},
                  Options(static_cast<int>(state.range(0))));
    benchmark::DoNotOptimize(r.final_state.data());
  }
  Report(state, r);
}
BENCHMARK(BM_Flight30s_StillAir)->ArgName("integrator")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// range(0): the integrator kind of Options; range(1): Δt_n in µs. The field, breakpoints and segment table
// are built inside the timed loop: they are part of every run's cost.
void BM_Flight30s_Turbulent(benchmark::State& state) {
  const DisturbanceOptions options = Moderate(static_cast<double>(state.range(1)) * 1e-6);
  IntegrationResult<10> r;
  std::uint64_t run = 0;
  for (auto _ : state) {
    const DisturbanceField field(options, 1, run++);
    const std::vector<double> breakpoints = field.Breakpoints(0.0, kDuration_s);
    const std::vector<DisturbanceField::Segment> table = field.SegmentTable(breakpoints, 0.0);
    InTurbulence problem{&field, &table};
    OdeState<10> x0{};
    const DisturbanceField::State xf = field.InitialState();
    std::copy(xf.begin(), xf.end(), x0.begin() + 5);
    x0[kDeltaU] = MeanWindAt(options.wind_20ft_mps, kStartHeight_m, options.wind_shear);  // airspeed u0
    r = Integrate(problem, x0, 0.0, kDuration_s, breakpoints,
                  Options(static_cast<int>(state.range(0)), options.turbulence_sample_interval_s));
    benchmark::DoNotOptimize(r.final_state.data());
  }
  Report(state, r);
}
BENCHMARK(BM_Flight30s_Turbulent)
    ->ArgNames({"integrator", "dt_n_us"})
    ->ArgsProduct({{0, 1, 2}, {2500, 5000, 10000, 15000, 30000}})
    ->Unit(benchmark::kMicrosecond);

// One evaluation of the field (shear, Dryden scales, filters, cached noise) at heights across the
// landing's last 30 m, with the noise sample changing every 4 calls (RK4's stages).
void BM_FieldEvaluate(benchmark::State& state) {
  const DisturbanceField field(Moderate(0.005), 1, 0);
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> height(0.8, 30.0);
  std::vector<double> heights(1024);
  for (double& h : heights) h = height(random);
  DisturbanceField::State x = field.InitialState(), dx;
  std::size_t i = 0;
  for (auto _ : state) {
    const DisturbanceField::Segment segment{static_cast<std::int64_t>(i / 4), false};
    const AirMotion m = field.Evaluate(segment, heights[i++ & 1023], 52.0, x, dx);
    benchmark::DoNotOptimize(m);
    benchmark::DoNotOptimize(dx);
  }
}
BENCHMARK(BM_FieldEvaluate);

// The per-sample noise alone (two Box–Muller normals, as at every new sample instant).
void BM_HeldNoisePair(benchmark::State& state) {
  const DisturbanceField field(Moderate(0.005), 1, 0);
  std::int64_t k = 0;
  for (auto _ : state) {
    double u = field.HeldNoise(NoiseStream::kTurbulenceU, k);
    double w = field.HeldNoise(NoiseStream::kTurbulenceW, k++);
    benchmark::DoNotOptimize(u);
    benchmark::DoNotOptimize(w);
  }
}
BENCHMARK(BM_HeldNoisePair);

}  // namespace
}  // namespace gesweep

BENCHMARK_MAIN();
