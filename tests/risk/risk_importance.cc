// An estimate of one limit's probability of a risk study by importance sampling at a linearised
// design point, independent of subset simulation (docs/dispersion.md, "A check by importance
// sampling at a linearised design point", which has the commands). Not a test: minutes of CPU.
//
//   risk_importance STUDY LIMIT WINDOW_S DELTA ITERATIONS N SEED [SCALE [SHIFTS STEP_S]]
//
// 1. The still-air landing (u = 0) of the study's first cell: its limit state g0 and touchdown time.
// 2. The gradient of g over the noise held in the last WINDOW_S seconds before that touchdown (both
//    streams, every sample), by central differences of +-DELTA per coordinate: 4 landings per sample
//    held. The coordinates outside the window are taken as having no effect (their gradient 0).
// 3. FORM: with g linear, g(u) = g0 + a.u, P = Phi(-beta), beta = g0 / |a| (the first-order
//    reliability estimate), at the design point u* = -g0 a / |a|^2; then ITERATIONS steps of
//    Hasofer-Lind-Rackwitz-Fiessler, each a new gradient (as in 2, around the current point u) and
//    u <- ((a.u - g(u)) / |a|^2) a, so that u* is the point of g = 0 nearest the origin of the
//    linearised state there.
// 4. Importance sampling with the density N(u*, I): N landings u = u* + z, z ~ N(0, I) from
//    std::mt19937_64 seeded by (SEED, i), weight w = phi(u) / phi(u - u*) = exp(-u*.z - |u*|^2 / 2);
//    P = mean(1{g <= 0} w), its standard error from the sample, and the effective sample size
//    (sum w)^2 / sum w^2 of the failures. Unbiased for any u*; the window and the linearisation only
//    decide its variance. A failed landing (NaN g) counts as no failure and is reported.
//    SCALE (default 1) multiplies u*. SHIFTS > 0 makes the density an equal mixture of N(u*_s, I),
//    s = -SHIFTS..SHIFTS, u*_s being u* moved by s * STEP_S in time (its held samples renumbered),
//    since a gust that changes the sink rate also moves the touchdown (a first passage); the weight
//    is then phi(u) / sum_s (phi(u - u*_s) / (2 SHIFTS + 1)).
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "engine/disturbance/run_noise.h"
#include "engine/risk/landing_risk.h"
#include "engine/sweep/study.h"
#include "engine/sweep/sweep_plan.h"
#include "tests/risk/risk_program_columns.h"

namespace {

using gesweep::NoisePointIndex;
using gesweep::NoiseStream;

double Phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

}  // namespace

int Run(const std::string& study_path, int limit, double window_s, double delta, int iterations, long n,
        std::uint64_t seed, double scale_factor, int shifts, double step_s);

int main(int argc, char** argv) {
  if (argc != 8 && argc != 9 && argc != 11) {
    std::fprintf(
        stderr,
        "usage: risk_importance STUDY LIMIT WINDOW_S DELTA ITERATIONS N SEED [SCALE [SHIFTS STEP_S]]\n");
    return 2;
  }
  const int limit = std::atoi(argv[2]);
  const double window_s = std::atof(argv[3]);
  const double delta = std::atof(argv[4]);
  const int iterations = std::atoi(argv[5]);
  const long n = std::atol(argv[6]);
  const std::uint64_t seed = std::strtoull(argv[7], nullptr, 10);
  const double scale_factor = argc >= 9 ? std::atof(argv[8]) : 1.0;
  const int shifts = argc == 11 ? std::atoi(argv[9]) : 0;
  const double step_s = argc == 11 ? std::atof(argv[10]) : 0.0;
  if (!(window_s > 0) || !(delta > 0) || iterations < 0 || n < 2 || !(scale_factor > 0) || shifts < 0 ||
      !(step_s >= 0) || (shifts > 0 && !(step_s > 0))) {
    std::fprintf(stderr,
                 "risk_importance: expected WINDOW_S > 0, DELTA > 0, ITERATIONS >= 0, N >= 2, SCALE > 0, "
                 "SHIFTS >= 0 and STEP_S > 0 with SHIFTS > 0\n");
    return 2;
  }
  try {
    return Run(argv[1], limit, window_s, delta, iterations, n, seed, scale_factor, shifts, step_s);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "risk_importance: %s\n", e.what());
    return 2;
  }
}

int Run(const std::string& study_path, int limit, double window_s, double delta, int iterations, long n,
        std::uint64_t seed, double scale_factor, int shifts, double step_s) {
  gesweep::Study study = gesweep::LoadStudy(study_path);
  const gesweep::SweepPlan plan(std::move(study), gesweep::ShardSpec{});
  const gesweep::risk::RiskSpec spec = gesweep::risk::ReadRiskSpec(plan);
  const std::int64_t cell = 0;
  const auto d = static_cast<std::size_t>(gesweep::risk::CellDimension(plan, cell));
  const double dt = gesweep::risk::CellSampleInterval(plan, cell);
  const int final_time = gesweep::risk::programs::EvaluationColumn(plan, "final_time_s");
  if (final_time < 0) {
    std::fprintf(stderr, "%s: no final_time_s column\n", study_path.c_str());
    return 2;
  }
  auto fly = [&](const std::vector<double>& u) {
    return gesweep::risk::FlyPoint(plan, cell, limit, spec, u);
  };

  // 1. The still-air landing.
  const std::vector<double> origin(d, 0.0);
  const auto still = fly(origin);
  const double g0 = still.g;
  const double touchdown_s = still.values[static_cast<std::size_t>(final_time)];
  std::printf("dimension %zu, sample interval %g s; u = 0: g0 = %.6g, touchdown at %.3f s\n", d, dt, g0,
              touchdown_s);

  // 2. The gradient over the window.
  const auto last = static_cast<std::uint64_t>(std::floor(touchdown_s / dt));
  const auto first = static_cast<std::uint64_t>(std::max(0.0, std::floor((touchdown_s - window_s) / dt)));
  std::vector<std::size_t> coordinates;
  for (std::uint64_t k = first; k <= last; ++k) {
    for (const NoiseStream s : {NoiseStream::kTurbulenceU, NoiseStream::kTurbulenceW}) {
      const auto c = static_cast<std::size_t>(NoisePointIndex(s, k));
      if (c < d) coordinates.push_back(c);
    }
  }
  // The gradient of g around `at` over the window's coordinates.
  auto gradient_at = [&](const std::vector<double>& at, std::vector<double>& gradient) {
    gradient.assign(d, 0.0);
    std::atomic<long> failed{0};
    tbb::parallel_for(std::size_t{0}, coordinates.size(), [&](std::size_t j) {
      std::vector<double> u(at);
      const std::size_t c = coordinates[j];
      u[c] = at[c] + delta;
      const double plus = fly(u).g;
      u[c] = at[c] - delta;
      const double minus = fly(u).g;
      if (std::isfinite(plus) && std::isfinite(minus)) {
        gradient[c] = (plus - minus) / (2 * delta);
      } else {
        ++failed;
      }
    });
    return failed.load();
  };
  std::vector<double> gradient;
  long failed_gradient = gradient_at(origin, gradient);
  double norm2 = 0;
  for (const double a : gradient) norm2 += a * a;
  double beta = g0 / std::sqrt(norm2);
  std::printf(
      "gradient over %zu coordinates (samples %llu..%llu, %.2f s), delta %g: |a| = %.6g, %ld failed\n",
      coordinates.size(), static_cast<unsigned long long>(first), static_cast<unsigned long long>(last),
      window_s, delta, std::sqrt(norm2), failed_gradient);
  std::printf("FORM at u = 0: beta = %.4f, P = Phi(-beta) = %.4g\n", beta, Phi(-beta));

  // 3. The design point: the linearised one, then HL-RF steps.
  std::vector<double> shift(d, 0.0);
  for (std::size_t c = 0; c < d; ++c) shift[c] = -g0 * gradient[c] / norm2;
  for (int it = 0; it < iterations; ++it) {
    const double g = fly(shift).g;
    failed_gradient = gradient_at(shift, gradient);
    norm2 = 0;
    double a_dot_u = 0;
    for (std::size_t c = 0; c < d; ++c) {
      norm2 += gradient[c] * gradient[c];
      a_dot_u += gradient[c] * shift[c];
    }
    const double scale = (a_dot_u - g) / norm2;
    for (std::size_t c = 0; c < d; ++c) shift[c] = scale * gradient[c];
    beta = std::sqrt(scale * scale * norm2);
    std::printf(
        "HL-RF step %d: g at the point %.4g, |a| %.4g (%ld failed), new beta %.4f (Phi(-beta) = %.4g)\n",
        it + 1, g, std::sqrt(norm2), failed_gradient, beta, Phi(-beta));
  }
  for (double& v : shift) v *= scale_factor;
  std::printf("design point (x %g): g there %.4g\n", scale_factor, fly(shift).g);

  // The mixture's components: u* moved by s samples of `step` (sparse: u* is zero outside the window).
  const auto step = static_cast<std::int64_t>(std::llround(step_s / dt));
  struct Entry {
    std::size_t c;
    double v;
  };
  std::vector<std::vector<Entry>> components;
  for (int s = -shifts; s <= shifts; ++s) {
    std::vector<Entry> component;
    for (std::uint64_t k = first; k <= last; ++k) {
      const std::int64_t moved = static_cast<std::int64_t>(k) + s * step;
      if (moved < 0) continue;
      for (const NoiseStream stream : {NoiseStream::kTurbulenceU, NoiseStream::kTurbulenceW}) {
        const auto from = static_cast<std::size_t>(NoisePointIndex(stream, k));
        const auto to = static_cast<std::size_t>(NoisePointIndex(stream, static_cast<std::uint64_t>(moved)));
        if (from < d && to < d && shift[from] != 0) component.push_back({to, shift[from]});
      }
    }
    components.push_back(std::move(component));
  }
  std::vector<double> component_norm2;
  for (const auto& component : components) {
    double norm = 0;
    for (const Entry& e : component) norm += e.v * e.v;
    component_norm2.push_back(norm);
  }
  std::printf("mixture of %zu components, %g s apart; |u*| = %.4f\n", components.size(), step_s,
              std::sqrt(component_norm2[static_cast<std::size_t>(shifts)]));

  // 4. Importance sampling from the mixture.
  std::vector<double> weight(static_cast<std::size_t>(n), 0.0);
  std::vector<char> failed(static_cast<std::size_t>(n), 0);
  std::vector<std::size_t> component_of(static_cast<std::size_t>(n), 0);
  tbb::parallel_for(long{0}, n, [&](long i) {
    std::mt19937_64 engine(seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(i));
    std::normal_distribution<double> normal;
    const auto picked = static_cast<std::size_t>(engine() % components.size());
    component_of[static_cast<std::size_t>(i)] = picked;
    std::vector<double> u(d);
    for (std::size_t c = 0; c < d; ++c) u[c] = normal(engine);
    for (const Entry& e : components[picked]) u[e.c] += e.v;
    const double g = fly(u).g;
    if (!std::isfinite(g)) {
      failed[static_cast<std::size_t>(i)] = 1;
      return;
    }
    if (g > 0) return;
    // phi(u) / q(u) = 1 / mean_s exp(u*_s . u - |u*_s|^2 / 2), summed from the largest exponent.
    std::vector<double> exponents;
    for (std::size_t s = 0; s < components.size(); ++s) {
      double dot = 0;
      for (const Entry& e : components[s]) dot += e.v * u[e.c];
      exponents.push_back(dot - 0.5 * component_norm2[s]);
    }
    const double top = *std::max_element(exponents.begin(), exponents.end());
    double mean = 0;
    for (const double x : exponents) mean += std::exp(x - top);
    mean /= static_cast<double>(exponents.size());
    weight[static_cast<std::size_t>(i)] = std::exp(-top) / mean;
  });
  double sum = 0, sum2 = 0;
  long hits = 0, failures = 0;
  for (long i = 0; i < n; ++i) {
    const double w = weight[static_cast<std::size_t>(i)];
    sum += w;
    sum2 += w * w;
    hits += w > 0 ? 1 : 0;
    failures += failed[static_cast<std::size_t>(i)];
  }
  // Where the estimate comes from: failures and weight by the component drawn.
  std::vector<long> hits_by(components.size(), 0);
  std::vector<double> weight_by(components.size(), 0.0);
  for (long i = 0; i < n; ++i) {
    if (weight[static_cast<std::size_t>(i)] > 0) {
      ++hits_by[component_of[static_cast<std::size_t>(i)]];
      weight_by[component_of[static_cast<std::size_t>(i)]] += weight[static_cast<std::size_t>(i)];
    }
  }
  for (std::size_t s = 0; s < components.size(); ++s) {
    std::printf("  shift %+.2f s: %ld past the limit, %.1f %% of the weight\n",
                (static_cast<double>(s) - shifts) * step_s, hits_by[s],
                sum > 0 ? 100 * weight_by[s] / sum : 0.0);
  }
  const double p = sum / static_cast<double>(n);
  const double variance = (sum2 / static_cast<double>(n) - p * p) / static_cast<double>(n - 1);
  const double se = std::sqrt(std::max(0.0, variance));
  const double ess = sum2 > 0 ? sum * sum / sum2 : 0;
  std::printf(
      "importance sampling: %ld landings, %ld past the limit, %ld failed; P = %.4g, standard error %.3g "
      "(CoV %.3f), 95 %% [%.4g, %.4g]; effective sample size of the failures %.1f\n",
      n, hits, failures, p, se, p > 0 ? se / p : 0.0, p - 1.96 * se, p + 1.96 * se, ess);
  return 0;
}
