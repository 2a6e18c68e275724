// How smooth the landing's limit state is along the moves the conditional sampler makes
// (docs/dispersion.md, "How rough the landing's limit state is"). Not a test: seconds to minutes of CPU.
//
//   risk_roughness STUDY LIMIT SEED SIGMA_MAX STEPS [SIGMA_MIN]
//
// From u0 ~ N(0, I) (std::mt19937_64 seeded by SEED, not the engine's streams), along the
// Crank-Nicolson path of the conditional sampler
//   u(sigma) = sqrt(1 - sigma^2) u0 + sigma xi,  sigma = SIGMA_MIN + (SIGMA_MAX - SIGMA_MIN) k / STEPS,
// k = 0 .. STEPS, with xi ~ N(0, I) drawn once, it flies the study's first cell and prints sigma, g
// and the touchdown time, one line each, then the largest jump of g between neighbouring sigmas
// against the median one: a smooth g has jumps of about one size (its slope times the sigma step); a
// first passage that moves to another dip of the path jumps by far more, however fine the steps.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "engine/risk/landing_risk.h"
#include "engine/sweep/study.h"
#include "engine/sweep/sweep_plan.h"
#include "tests/risk/risk_program_columns.h"

int main(int argc, char** argv) {
  if (argc != 6 && argc != 7) {
    std::fprintf(stderr, "usage: risk_roughness STUDY LIMIT SEED SIGMA_MAX STEPS [SIGMA_MIN]\n");
    return 2;
  }
  const int limit = std::atoi(argv[2]);
  const std::uint64_t seed = std::strtoull(argv[3], nullptr, 10);
  const double sigma_max = std::atof(argv[4]);
  const int steps = std::atoi(argv[5]);
  const double sigma_min = argc == 7 ? std::atof(argv[6]) : 0.0;
  if (!(sigma_max > 0 && sigma_max <= 1) || steps < 2 || !(sigma_min >= 0 && sigma_min < sigma_max)) {
    std::fprintf(stderr, "risk_roughness: expected 0 <= SIGMA_MIN < SIGMA_MAX <= 1 and STEPS >= 2\n");
    return 2;
  }
  try {
    gesweep::Study study = gesweep::LoadStudy(argv[1]);
    const gesweep::SweepPlan plan(std::move(study), gesweep::ShardSpec{});
    const gesweep::risk::RiskSpec spec = gesweep::risk::ReadRiskSpec(plan);
    const auto d = static_cast<std::size_t>(gesweep::risk::CellDimension(plan, 0));
    const int final_time = gesweep::risk::programs::EvaluationColumn(plan, "final_time_s");
    std::mt19937_64 engine(seed);
    std::normal_distribution<double> normal;
    std::vector<double> u0(d), xi(d);
    for (double& v : u0) v = normal(engine);
    for (double& v : xi) v = normal(engine);
    std::vector<double> g(static_cast<std::size_t>(steps) + 1), touchdown(g.size());
    const auto sigma_at = [&](std::size_t k) {
      return sigma_min + (sigma_max - sigma_min) * static_cast<double>(k) / steps;
    };
    tbb::parallel_for(std::size_t{0}, g.size(), [&](std::size_t k) {
      const double sigma = sigma_at(k);
      const double rho = std::sqrt(1 - sigma * sigma);
      std::vector<double> u(d);
      for (std::size_t i = 0; i < d; ++i) u[i] = rho * u0[i] + sigma * xi[i];
      const auto e = gesweep::risk::FlyPoint(plan, 0, limit, spec, u);
      g[k] = e.g;
      touchdown[k] = final_time >= 0 ? e.values[static_cast<std::size_t>(final_time)] : NAN;
    });
    std::vector<double> jumps;
    for (std::size_t k = 0; k < g.size(); ++k) {
      std::printf("%.9f %.9g %.4f\n", sigma_at(k), g[k], touchdown[k]);
      if (k > 0) jumps.push_back(std::abs(g[k] - g[k - 1]));
    }
    std::vector<double> sorted(jumps);
    std::sort(sorted.begin(), sorted.end());
    std::printf("# largest jump %.4g, median jump %.4g, ratio %.1f; g from %.4g to %.4g\n", sorted.back(),
                sorted[sorted.size() / 2], sorted.back() / sorted[sorted.size() / 2],
                *std::min_element(g.begin(), g.end()), *std::max_element(g.begin(), g.end()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "risk_roughness: %s\n", e.what());
    return 2;
  }
  return 0;
}
