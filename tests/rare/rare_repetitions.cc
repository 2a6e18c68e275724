/// rare_repetitions [REPETITIONS] [CASE ...]: independent repetitions of subset simulation on the
/// analytic limit states of tests/rare/analytic_limit_states.h, one markdown table row per case:
/// the truth, the mean estimate and its z-score against the truth, the CoV measured across the
/// repetitions, the mean stated CoV (sum of squares) and its ratio to the measured one, the mean
/// fully-correlated bound, the 95 % intervals' coverage, and the mean evaluations.
/// Run by scripts/rare_repetitions (docs/dispersion.md); repetition r uses seed 1000 + r.
/// The repetitions run in parallel (oneTBB); each is bit-identical however they are scheduled.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <string>
#include <vector>

#include "engine/rare/subset_simulation.h"
#include "tests/rare/analytic_limit_states.h"

namespace {

using namespace gesweep::rare;
using namespace gesweep::rare::testing;

enum class Kind { kLinear, kChiSquare, kSeries };

struct Case {
  std::string name;
  int dimension;
  Kind kind;
  double parameter;  // beta for the linear and series states, the target probability for the chi-square one
  int samples;       // N per level
  ConditionalSampler sampler;
  int windows = 0;  // series: K windows of dimension / K coordinates
};

const std::vector<Case>& Cases() {
  static const std::vector<Case> cases = {
      {"linear_b3.0_d10", 10, Kind::kLinear, 3.0, 1000, ConditionalSampler::kCrankNicolson},
      {"linear_b5.2_d10", 10, Kind::kLinear, 5.2, 1000, ConditionalSampler::kCrankNicolson},
      {"linear_b5.2_d1000", 1000, Kind::kLinear, 5.2, 1000, ConditionalSampler::kCrankNicolson},
      {"linear_b5.2_d10000", 10000, Kind::kLinear, 5.2, 1000, ConditionalSampler::kCrankNicolson},
      {"linear_b5.2_d1000_mma", 1000, Kind::kLinear, 5.2, 1000, ConditionalSampler::kModifiedMetropolis},
      {"chi2_p1e-6_d10", 10, Kind::kChiSquare, 1e-6, 1000, ConditionalSampler::kCrankNicolson},
      {"chi2_p1e-6_d1000", 1000, Kind::kChiSquare, 1e-6, 1000, ConditionalSampler::kCrankNicolson},
      {"chi2_p1e-6_d10000", 10000, Kind::kChiSquare, 1e-6, 1000, ConditionalSampler::kCrankNicolson},
      {"series_k20_b4.5_d1000", 1000, Kind::kSeries, 4.5, 1000, ConditionalSampler::kCrankNicolson, 20},
      {"series_k100_b5_d10000", 10000, Kind::kSeries, 5.0, 1000, ConditionalSampler::kCrankNicolson, 100},
  };
  return cases;
}

}  // namespace

int main(int argc, char** argv) {
  const int repetitions = argc > 1 ? std::atoi(argv[1]) : 100;
  if (repetitions < 2) {
    std::fprintf(stderr, "rare_repetitions: command line: REPETITIONS = %s: an integer >= 2\n", argv[1]);
    return 2;
  }
  std::vector<std::string> wanted(argv + std::min(argc, 2), argv + argc);
  std::printf(
      "| case | d | N | truth | mean estimate | bias | z of mean | measured CoV | mean stated CoV | "
      "stated / measured | mean CoV bound | 95 %% coverage | mean levels | mean evaluations | CPU s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Case& c : Cases()) {
    if (!wanted.empty() && std::find(wanted.begin(), wanted.end(), c.name) == wanted.end()) continue;
    double truth = 0;
    std::function<double(std::span<const double>)> g;
    if (c.kind == Kind::kLinear) {
      truth = LinearTruth(c.parameter);
      g = [beta = c.parameter](std::span<const double> u) { return LinearLimitState(u, beta); };
    } else if (c.kind == Kind::kSeries) {
      truth = SeriesTruth(c.windows, c.parameter);
      g = [beta = c.parameter, k = c.windows, length = c.dimension / c.windows](std::span<const double> u) {
        return SeriesLimitState(u, k, length, beta);
      };
    } else {
      const double threshold = ChiSquareThreshold(c.dimension, c.parameter);
      truth = ChiSquareTruth(c.dimension, threshold);
      g = [threshold](std::span<const double> u) { return ChiSquareLimitState(u, threshold); };
    }
    const LimitStateBatch batch = ParallelLimitState(g);
    std::vector<SubsetResult> results(static_cast<std::size_t>(repetitions));
    const std::clock_t cpu0 = std::clock();
    tbb::parallel_for(0, repetitions, [&](int r) {
      SubsetOptions options;
      options.samples_per_level = c.samples;
      options.sampler = c.sampler;
      options.seed = 1000 + static_cast<std::uint64_t>(r);
      results[static_cast<std::size_t>(r)] = RunSubsetSimulation(batch, c.dimension, options);
    });
    const double cpu = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
    double sum = 0, sum2 = 0, stated = 0, bound = 0, evaluations = 0, levels = 0;
    int covered = 0, converged = 0;
    for (const auto& result : results) {
      if (result.status != SubsetResult::Status::kConverged) continue;
      ++converged;
      sum += result.probability;
      sum2 += result.probability * result.probability;
      stated += result.coefficient_of_variation;
      bound += result.coefficient_of_variation_upper;
      evaluations += static_cast<double>(result.evaluations);
      levels += static_cast<double>(result.levels.size());
      covered += (result.interval_95_low <= truth && truth <= result.interval_95_high) ? 1 : 0;
    }
    const double k = converged;
    const double mean = sum / k;
    const double sd = std::sqrt(std::max(0.0, (sum2 - k * mean * mean) / (k - 1)));
    const double measured = sd / mean;
    const double z = (mean - truth) / (sd / std::sqrt(k));
    std::printf(
        "| %s | %d | %d | %.4g | %.4g | %+.1f %% | %+.2f | %.3f | %.3f | %.2f | %.3f | %d / %d | %.2f | %.0f "
        "| %.0f |\n",
        c.name.c_str(), c.dimension, c.samples, truth, mean, 100 * (mean - truth) / truth, z, measured,
        stated / k, (stated / k) / measured, bound / k, covered, converged, levels / k, evaluations / k, cpu);
    if (converged != repetitions) {
      std::printf("| %s: %d of %d repetitions did not converge (level cap or failed evaluations) |\n",
                  c.name.c_str(), repetitions - converged, repetitions);
    }
    std::fflush(stdout);
  }
  return 0;
}
