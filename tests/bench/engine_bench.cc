// Microbenchmarks of the engine's per-run analyses (issue 9; docs/performance.md): one eigen-analysis
// with mode identification, one boundary search, one right-hand-side evaluation, one landing, one
// LQR design, and the runs the NumPy/SciPy peer (scripts/peer/bench_peer.py) times, on the same
// inputs, so that `./scripts/bench --peer` can print engine/peer ratios from one invocation.
//
// The Peer_* benchmarks mirror bench_peer.py figure by figure; keep their inputs in step with its
// defaults (scripts/bench passes the same values to the peer explicitly):
//   modes height 2.0748 m, open-loop start 5.5922 m, u0 32.0208 m/s, 5° for 0.2 s, 30 s.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/control/landing_simulation.h"
#include "engine/control/riccati.h"
#include "engine/modal/boundary.h"
#include "engine/modal/hurwitz.h"
#include "engine/modal/modal_analysis.h"
#include "engine/simulation/derivative_kernel.h"
#include "engine/simulation/open_loop.h"

extern "C" void dgebal_(const char* job, const int* n, double* a, const int* lda, int* ilo, int* ihi,
                        double* scale, int* info, std::size_t job_length);

namespace gesweep {
namespace {

// The peer's inputs (scripts/peer/bench_peer.py defaults).
constexpr double kModesHeight_m = 2.0748;
constexpr double kOpenLoopHeight_m = 5.5922;
constexpr double kSpeed_mps = 32.0208;
constexpr double kPulse_deg = 5.0;
constexpr double kPulse_s = 0.2;
constexpr double kDuration_s = 30.0;
constexpr double kRk4Step_s = 0.015;
// The landing of the paper (Section III): from 500 m at 52.21 m/s (LandingConfig's defaults).
constexpr double kLandingSpeed_mps = 52.21;

const Aircraft& Ance() {
  static const Aircraft aircraft = LoadAircraftFile(GESWEEP_SOURCE_DIR "/studies/aircraft/ance.toml");
  return aircraft;
}

const LongitudinalModel& Model() {
  static const LongitudinalModel model(Ance(), ModelOptions{});
  return model;
}

// Heights spread over the ground-effect range and above it, as a sweep visits them: wheel contact
// (0.788 m) to 14 m, so the table lookups and the mode classification see every case.
const std::vector<double>& SweepHeights() {
  static const std::vector<double> heights = [] {
    std::vector<double> h(1024);
    std::mt19937_64 random(11);
    std::uniform_real_distribution<double> height(0.79, 14.0);
    for (double& x : h) x = height(random);
    return h;
  }();
  return heights;
}

// --- Eigen-analysis with mode identification (the per-run work of a `modes` sweep) ---

// A(H, u0) from the table (docs/model.md §4-§5), then eigenvalues, modes and σ (§6), at heights across the
// range. Runs on 1 and 2 threads; items_per_second is the rate over all threads (wall clock).
void BM_Modes(benchmark::State& state) {
  const LongitudinalModel& model = Model();
  const std::vector<double>& heights = SweepHeights();
  std::size_t i = static_cast<std::size_t>(state.thread_index()) * 512;
  for (auto _ : state) {
    const ModalAnalysis modal = AnalyzeModes(model.StateMatrix(heights[i++ & 1023], kSpeed_mps));
    benchmark::DoNotOptimize(modal.stability_margin_per_s);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Modes)->Threads(1)->Threads(2)->UseRealTime();

// The same with another eigenvalue solver: Eigen's EigenSolver after dgebal (the path before the
// fixed-size kernel, issue 16), and LAPACK's small-matrix QR (dgebal + dgehd2 + dlahqr).
void RunModesWith(benchmark::State& state, EigenvalueSolver solver) {
  const LongitudinalModel& model = Model();
  const std::vector<double>& heights = SweepHeights();
  std::size_t i = 0;
  for (auto _ : state) {
    const ModalAnalysis modal = AnalyzeModes(model.StateMatrix(heights[i++ & 1023], kSpeed_mps), solver);
    benchmark::DoNotOptimize(modal.stability_margin_per_s);
  }
  state.SetItemsProcessed(state.iterations());
}
void BM_ModesEigen(benchmark::State& state) { RunModesWith(state, EigenvalueSolver::kEigen); }
BENCHMARK(BM_ModesEigen);
void BM_ModesLapack(benchmark::State& state) { RunModesWith(state, EigenvalueSolver::kLapack); }
BENCHMARK(BM_ModesLapack);

// The eigenvalues alone of the sweep heights' matrices (built beforehand), by each solver. Counter
// `sweeps`: the fixed-size kernel's mean double-shift sweeps per matrix.
void RunEigenvaluesOnly(benchmark::State& state, EigenvalueSolver solver) {
  std::vector<Matrix5d> matrices;
  double sweeps = 0;
  for (double h : SweepHeights()) {
    matrices.push_back(Model().StateMatrix(h, kSpeed_mps));
    EigenvalueReport report;
    Eigenvalues5(matrices.back(), solver, &report);
    sweeps += report.iterations;
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const auto values = Eigenvalues5(matrices[i++ & 1023], solver);
    benchmark::DoNotOptimize(values.data());
  }
  state.counters["sweeps"] = sweeps / static_cast<double>(matrices.size());
}
void BM_EigenvaluesFixedSize(benchmark::State& state) {
  RunEigenvaluesOnly(state, EigenvalueSolver::kFixedSize);
}
BENCHMARK(BM_EigenvaluesFixedSize);
void BM_EigenvaluesEigen(benchmark::State& state) { RunEigenvaluesOnly(state, EigenvalueSolver::kEigen); }
BENCHMARK(BM_EigenvaluesEigen);

// The kernel's balancing (a port of dgebal job 'S', the same D) against LAPACK's dgebal itself.
void BM_Balance5(benchmark::State& state) {
  const Matrix5d a0 = Model().StateMatrix(kModesHeight_m, kSpeed_mps);
  for (auto _ : state) {
    Matrix5d a = a0;
    benchmark::DoNotOptimize(a.data());
    const BalancedMatrix5 balanced = Balance5(a);
    benchmark::DoNotOptimize(balanced.matrix.data());
  }
}
BENCHMARK(BM_Balance5);
void BM_Dgebal(benchmark::State& state) {
  const Matrix5d a0 = Model().StateMatrix(kModesHeight_m, kSpeed_mps);
  for (auto _ : state) {
    Matrix5d a = a0;
    benchmark::DoNotOptimize(a.data());
    const int n = 5;
    int ilo = 0, ihi = 0, info = 0;
    double scale[5];
    dgebal_("S", &n, a.data(), &n, &ilo, &ihi, scale, &info, 1);
    benchmark::DoNotOptimize(a.data());
  }
}
BENCHMARK(BM_Dgebal);

// The parts: building A(H, u0), and the eigen-analysis of a fixed A.
void BM_StateMatrix(benchmark::State& state) {
  const LongitudinalModel& model = Model();
  const std::vector<double>& heights = SweepHeights();
  std::size_t i = 0;
  for (auto _ : state) {
    Matrix5d a = model.StateMatrix(heights[i++ & 1023], kSpeed_mps);
    benchmark::DoNotOptimize(a.data());
  }
}
BENCHMARK(BM_StateMatrix);

// --- A candidate for engine/modal (docs/performance.md, "Modes"): balance A before the QR ---
//
// AnalyzeModes spends ~95 % of its time in Eigen's EigenSolver (Hessenberg reduction + Francis QR on
// dynamic-size blocks). A has entries from 1e-3 (Mh) to 32 (u0) and the QR needs many sweeps to
// converge; balancing it first (a diagonal similarity by powers of two, exact in floating point:
// Parlett & Reinsch 1969, EISPACK's balanc, LAPACK's dgebal without permutations, and what
// numpy.linalg.eigvals does through dgeev) cuts the sweeps. These benchmarks measured that change
// (bare Eigen, then Eigen after a hand-written Parlett-Reinsch balance) before AnalyzeModes adopted
// it, balancing with LAPACK's dgebal; BM_Modes measures AnalyzeModes as it is.

// Balances A in place by the Parlett-Reinsch iteration with radix 2 (row and column 1-norms of the
// off-diagonal part brought within a factor 2 of each other). Same eigenvalues, exactly.
void BalanceInPlace(Matrix5d& a) {
  constexpr double kRadix = 2.0;
  constexpr double kRadixSquared = kRadix * kRadix;
  constexpr double kImprovement = 0.95;  // EISPACK balanc's threshold for taking a step
  bool converged = false;
  while (!converged) {
    converged = true;
    for (int i = 0; i < 5; ++i) {
      double c = 0, r = 0;
      for (int j = 0; j < 5; ++j) {
        if (j == i) continue;
        c += std::abs(a(j, i));
        r += std::abs(a(i, j));
      }
      if (c == 0 || r == 0) continue;
      const double s = c + r;
      double f = 1;
      double g = r / kRadix;
      while (c < g) {
        f *= kRadix;
        c *= kRadixSquared;
      }
      g = r * kRadix;
      while (c > g) {
        f /= kRadix;
        c /= kRadixSquared;
      }
      if ((c + r) / f < kImprovement * s) {
        converged = false;
        a.row(i) /= f;
        a.col(i) *= f;
      }
    }
  }
}

// The eigenvalues AnalyzeModes computes, without and with balancing.
Eigen::Matrix<std::complex<double>, 5, 1> EigenvaluesUnbalanced(const Matrix5d& a) {
  return Eigen::EigenSolver<Matrix5d>(a, false).eigenvalues();
}
Eigen::Matrix<std::complex<double>, 5, 1> EigenvaluesBalanced(Matrix5d a) {
  BalanceInPlace(a);
  return Eigen::EigenSolver<Matrix5d>(a, false).eigenvalues();
}

// Largest distance from an eigenvalue of `a` to the nearest of `b`, relative to max(1, |λ|).
double SpectrumDistance(const Eigen::Matrix<std::complex<double>, 5, 1>& a,
                        const Eigen::Matrix<std::complex<double>, 5, 1>& b) {
  double worst = 0;
  for (int i = 0; i < 5; ++i) {
    double nearest = INFINITY;
    for (int j = 0; j < 5; ++j) nearest = std::min(nearest, std::abs(a[i] - b[j]));
    worst = std::max(worst, nearest / std::max(1.0, std::abs(a[i])));
  }
  return worst;
}

// Counter `agreement`: the largest relative difference between the two spectra over the sweep
// heights (the peer test's tolerance is 1e-9).
template <bool kBalanced>
void BM_EigenvaluesOnly(benchmark::State& state) {
  const LongitudinalModel& model = Model();
  const std::vector<double>& heights = SweepHeights();
  std::vector<Matrix5d> matrices;
  double agreement = 0;
  for (double h : heights) {
    matrices.push_back(model.StateMatrix(h, kSpeed_mps));
    agreement = std::max(agreement, SpectrumDistance(EigenvaluesUnbalanced(matrices.back()),
                                                     EigenvaluesBalanced(matrices.back())));
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const auto values =
        kBalanced ? EigenvaluesBalanced(matrices[i++ & 1023]) : EigenvaluesUnbalanced(matrices[i++ & 1023]);
    benchmark::DoNotOptimize(values.data());
  }
  state.counters["agreement"] = agreement;
}
BENCHMARK(BM_EigenvaluesOnly<false>)->Name("BM_EigenvaluesOnly_AsNow");
BENCHMARK(BM_EigenvaluesOnly<true>)->Name("BM_EigenvaluesOnly_Balanced");

void BM_Balance(benchmark::State& state) {
  const Matrix5d a0 = Model().StateMatrix(kModesHeight_m, kSpeed_mps);
  for (auto _ : state) {
    Matrix5d a = a0;
    benchmark::DoNotOptimize(a.data());
    BalanceInPlace(a);
    benchmark::DoNotOptimize(a.data());
  }
}
BENCHMARK(BM_Balance);

// --- One boundary search (docs/model.md §6) at 32.0208 m/s: the certified Hurwitz finder (default) and
// the former sampled search (σ at ~280 heights, TOMS 748 at the sign change), side by side ---

void RunBoundary(benchmark::State& state, BoundaryMethod method,
                 EigenvalueSolver solver = EigenvalueSolver::kFixedSize) {
  BoundaryOptions options;
  options.method = method;
  options.eigenvalue_solver = solver;
  BoundaryResult result;
  for (auto _ : state) {
    result = FindBoundary(Model(), kSpeed_mps, options);
    benchmark::DoNotOptimize(result.height_m);
  }
  state.counters["eigen_analyses"] = result.margin_evaluations;
  state.counters["characteristic_polynomials"] = result.polynomial_evaluations;
  state.counters["boundary_m"] = result.height_m.value_or(NAN);
  state.counters["certified"] = result.certified ? 1 : 0;
}
void BM_Boundary(benchmark::State& state) { RunBoundary(state, BoundaryMethod::kHurwitz); }
BENCHMARK(BM_Boundary)->Unit(benchmark::kMicrosecond);
void BM_BoundarySampled(benchmark::State& state) { RunBoundary(state, BoundaryMethod::kSampled); }
BENCHMARK(BM_BoundarySampled)->Unit(benchmark::kMicrosecond);
// The sampled search exactly as it was before issue 16 (Eigen's EigenSolver for every σ): the
// reference of the target (1/20 of it).
void BM_BoundarySampledEigen(benchmark::State& state) {
  RunBoundary(state, BoundaryMethod::kSampled, EigenvalueSolver::kEigen);
}
BENCHMARK(BM_BoundarySampledEigen)->Unit(benchmark::kMicrosecond);

// The Hurwitz finder's unit of work: one characteristic polynomial of A (Hessenberg + recurrence).
void BM_CharacteristicPolynomial(benchmark::State& state) {
  Matrix5d a = Model().StateMatrix(kModesHeight_m, kSpeed_mps);
  for (auto _ : state) {
    benchmark::DoNotOptimize(a.data());
    const CharacteristicCoefficients c = CharacteristicPolynomial(a);
    benchmark::DoNotOptimize(c.data());
  }
}
BENCHMARK(BM_CharacteristicPolynomial);

// --- One right-hand-side evaluation of the open loop (docs/model.md §7), in the integrator's pattern:
// consecutive calls at nearby heights, so the segment hint usually hits (the worst case, a new
// segment each call, is BM_Equation1Kernel in simulation_bench.cc) ---

void BM_Rhs(benchmark::State& state) {
  const LinearDerivativeTable table(Model());
  double x[5] = {0.3, -0.01, 0.02, 0.003, -0.5};
  double dxdt[5];
  int hint = table.SegmentOf(kOpenLoopHeight_m - 0.5);
  for (auto _ : state) {
    benchmark::DoNotOptimize(x);
    table.Equation1(kOpenLoopHeight_m, kSpeed_mps, x, 0.0, dxdt, hint);
    benchmark::DoNotOptimize(dxdt);
  }
}
BENCHMARK(BM_Rhs);

// The same through the generic path: LongitudinalModel::DerivativesAt, then A·x + B·δe.
void BM_RhsGeneric(benchmark::State& state) {
  const LongitudinalModel& model = Model();
  Vector5d x;
  x << 0.3, -0.01, 0.02, 0.003, -0.5;
  for (auto _ : state) {
    benchmark::DoNotOptimize(x.data());
    const DimensionalDerivatives d = model.DerivativesAt(kOpenLoopHeight_m + x[4], kSpeed_mps + x[0]);
    Vector5d dxdt = AssembleStateMatrix(d, kSpeed_mps) * x;
    benchmark::DoNotOptimize(dxdt.data());
  }
}
BENCHMARK(BM_RhsGeneric);

// --- One landing (docs/model.md §8): LQR design (SLICOT) + dopri5 flight from 500 m to touchdown ---

void RunLanding(benchmark::State& state, bool h_derivatives) {
  ModelOptions options;
  options.h_derivatives = h_derivatives;
  const LongitudinalModel plant(Ance(), options);
  LandingConfig config;
  config.start_speed_mps = kLandingSpeed_mps;
  config.output_interval_s = 0.0;  // summary only, as a sweep without series
  LandingResult result;
  for (auto _ : state) {
    result = SimulateLanding(plant, config);
    benchmark::DoNotOptimize(result.touchdown_time_s);
  }
  state.counters["landed"] = result.outcome == LandingOutcome::kLanded ? 1 : 0;
  state.counters["steps"] = static_cast<double>(result.accepted_steps);
  state.counters["rhs_calls"] = static_cast<double>(result.rhs_calls);
}
void BM_Landing(benchmark::State& state) { RunLanding(state, true); }
BENCHMARK(BM_Landing)->Unit(benchmark::kMicrosecond);
void BM_LandingNoHDerivatives(benchmark::State& state) { RunLanding(state, false); }
BENCHMARK(BM_LandingNoHDerivatives)->Unit(benchmark::kMicrosecond);

// ================= The peer's figures, on the peer's inputs (bench_peer.py) =================

// modes: A(H, u0) from the table + eigenvalues + identification at one height.
void BM_Peer_modes(benchmark::State& state) {
  const LongitudinalModel& model = Model();
  for (auto _ : state) {
    double h = kModesHeight_m;
    benchmark::DoNotOptimize(h);
    const ModalAnalysis modal = AnalyzeModes(model.StateMatrix(h, kSpeed_mps));
    benchmark::DoNotOptimize(modal.stability_margin_per_s);
  }
}
BENCHMARK(BM_Peer_modes);

// eigen_analysis: eigenvalues + identification of a fixed A.
void BM_Peer_eigen_analysis(benchmark::State& state) {
  Matrix5d a = Model().StateMatrix(kModesHeight_m, kSpeed_mps);
  for (auto _ : state) {
    benchmark::DoNotOptimize(a.data());
    const ModalAnalysis modal = AnalyzeModes(a);
    benchmark::DoNotOptimize(modal.stability_margin_per_s);
  }
}
BENCHMARK(BM_Peer_eigen_analysis);

// rhs: one open-loop right-hand side at the peer's state (x = [0.3, -0.01, 0.02, 0.003, -0.5] at
// t = 0.1 s, inside the 5° pulse).
void BM_Peer_rhs(benchmark::State& state) {
  const LinearDerivativeTable table(Model());
  double x[5] = {0.3, -0.01, 0.02, 0.003, -0.5};
  double dxdt[5];
  const double elevator_rad = kPulse_deg * std::numbers::pi / 180.0;
  int hint = table.SegmentOf(kOpenLoopHeight_m - 0.5);
  for (auto _ : state) {
    benchmark::DoNotOptimize(x);
    table.Equation1(kOpenLoopHeight_m, kSpeed_mps, x, elevator_rad, dxdt, hint);
    benchmark::DoNotOptimize(dxdt);
  }
}
BENCHMARK(BM_Peer_rhs);

OpenLoopConfig PeerRun() {
  OpenLoopConfig config;
  config.start_height_m = kOpenLoopHeight_m;
  config.reference_speed_mps = kSpeed_mps;
  config.elevator.amplitude_rad = kPulse_deg * std::numbers::pi / 180.0;
  config.elevator.duration_s = kPulse_s;
  config.duration_s = kDuration_s;
  config.integrator.step_s = kRk4Step_s;
  return config;
}

void RunOpenLoop(benchmark::State& state, const OpenLoopConfig& config) {
  OpenLoopResult result;
  for (auto _ : state) {
    result = SimulateOpenLoop(Model(), config);
    benchmark::DoNotOptimize(result.summary.final_state.data());
  }
  if (result.summary.end_event != OpenLoopEndEvent::kTimeLimit)
    state.SkipWithError("the run did not last 30 s");
  state.counters["steps"] = static_cast<double>(result.summary.steps);
  state.counters["rhs_calls"] = static_cast<double>(result.summary.rhs_calls);
}

// open_loop_rk4: plain RK4 at 0.015 s, the pulse sampled at each stage's time (no breakpoints), as
// the peer's simulate_rk4(..., breakpoints=False).
void BM_Peer_open_loop_rk4(benchmark::State& state) {
  OpenLoopConfig config = PeerRun();
  config.integrator.honour_breakpoints = false;
  RunOpenLoop(state, config);
}
BENCHMARK(BM_Peer_open_loop_rk4)->Unit(benchmark::kMicrosecond);

// The same run with A and B frozen at (H0, u0): the floor of the open-loop target, on the peer's run.
void BM_Peer_open_loop_rk4_frozen(benchmark::State& state) {
  OpenLoopConfig config = PeerRun();
  config.integrator.honour_breakpoints = false;
  config.freeze_derivatives = true;
  RunOpenLoop(state, config);
}
BENCHMARK(BM_Peer_open_loop_rk4_frozen)->Unit(benchmark::kMicrosecond);

// open_loop_solve_ivp_rtol...: the engine's Dormand-Prince 5(4) (the method of solve_ivp's RK45) at
// the same tolerances, the pulse end a breakpoint (the peer restarts solve_ivp there).
void RunDopri5(benchmark::State& state, double rtol, double atol) {
  OpenLoopConfig config = PeerRun();
  config.integrator.kind = IntegratorKind::kDopri5;
  config.integrator.relative_tolerance = rtol;
  config.integrator.absolute_tolerance = atol;
  RunOpenLoop(state, config);
}
void BM_Peer_open_loop_solve_ivp_rtol1e_3(benchmark::State& state) { RunDopri5(state, 1e-3, 1e-6); }
BENCHMARK(BM_Peer_open_loop_solve_ivp_rtol1e_3)->Unit(benchmark::kMicrosecond);
void BM_Peer_open_loop_solve_ivp_rtol1e_6(benchmark::State& state) { RunDopri5(state, 1e-6, 1e-9); }
BENCHMARK(BM_Peer_open_loop_solve_ivp_rtol1e_6)->Unit(benchmark::kMicrosecond);

// lqr: the Riccati solution and gain for Eq. (1) at 2.0748 m, 32.0208 m/s, Q = I5, R = 1 (SLICOT
// SB02OD with the engine's stabilisability/detectability checks, against solve_continuous_are).
void BM_Peer_lqr(benchmark::State& state) {
  const Eigen::MatrixXd a = Model().StateMatrix(kModesHeight_m, kSpeed_mps);
  const Eigen::MatrixXd b = Model().InputMatrix(kModesHeight_m, kSpeed_mps);
  const Eigen::MatrixXd q = Eigen::MatrixXd::Identity(5, 5);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(1, 1);
  LqrResult result;
  for (auto _ : state) {
    result = Lqr(a, b, q, r);
    benchmark::DoNotOptimize(result.K.data());
  }
  if (!result.ok()) state.SkipWithError(result.message.c_str());
}
BENCHMARK(BM_Peer_lqr)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace gesweep

BENCHMARK_MAIN();
