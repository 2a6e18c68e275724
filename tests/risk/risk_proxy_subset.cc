// Subset simulation of a touchdown sink-rate limit on a score that is continuous in the noise
// (docs/dispersion.md, "What the hard landing is made of"). Not a test: minutes of CPU.
//
//   risk_proxy_subset STUDY LOWERED_WHEELS_M LIMIT_MPS A_PER_S N SEED REPETITIONS [CHECKS]
//
// STUDY is the landing (its first cell), with its design height and time limit given in
// [analyses.landing] (tests/risk/landing_risk_hard_pinned.toml). The proxy is the same study with the
// aircraft's wheel-contact height lowered to LOWERED_WHEELS_M, so that the flight goes on below the
// real touchdown height H_t; with the design height and the time limit pinned, the proxy's path is the
// real one up to the real touchdown (checked on CHECKS plain landings, default 20: the real
// touchdown's time and sink rate against the proxy's first crossing of H_t).
// On the proxy's series (every noise sample interval):
//   s_first = the sink rate at the first downward crossing of H_t, interpolated linearly in H between
//             the two samples around it: the real touchdown's sink rate (up to that interpolation);
//   Z       = the largest of s - A |H - H_t| over the samples and of the sink rate at every crossing
//             of H_t: a maximum of functions continuous in the noise, which does not jump when a dip
//             of the flare grazes H_t (the path goes on either way). It can still jump where a dip
//             grazes the lowered wheels, which end the flight, but there s - A |H - H_t| is
//             A (H_t - LOWERED_WHEELS_M) below the sink rate (2.4 m/s at A = 5 /s and 0.3 m);
//   F       = s_first > LIMIT_MPS, the real event; F implies Z >= s_first > LIMIT_MPS.
// The limit state is g = LIMIT_MPS + 100 - (Z + 100 * 1{F}): its intermediate levels climb on Z, and
// its failure set {g <= 0} is F. Subset simulation (engine/rare/subset_simulation.h, p0 = 0.1, N per
// level, pCN) then gives P(F) with its stated CoV; the repetitions (seeds SEED + r) their measured
// CoV.
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/rare/subset_simulation.h"
#include "engine/risk/landing_risk.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"
#include "engine/sweep/sweep_plan.h"
#include "tests/risk/risk_program_columns.h"

namespace {

using gesweep::risk::programs::SchemaColumn;

constexpr double kBonus = 100;

struct Score {
  double z = -INFINITY, s_first = NAN, t_first = NAN, touchdown_s = NAN, touchdown_sink = NAN;
};

class Scorer {
 public:
  Scorer(const gesweep::SweepPlan& plan, double h_t, double a)
      : plan_(plan), h_t_(h_t), a_(a), slots_([this] { return Slot(plan_); }) {
    height_ = SchemaColumn(plan_, "series/landing/height_m");
    sink_ = SchemaColumn(plan_, "series/landing/sink_rate_mps");
    touchdown_ = SchemaColumn(plan_, "results/landing/touchdown_time_s");
    touchdown_sink_ = SchemaColumn(plan_, "results/landing/touchdown_sink_rate_mps");
    for (const auto& axis : plan_.schema().axes) {
      if (axis.path == "series/landing/time_s") times_ = axis.times_s;
    }
  }

  Score Fly(std::span<const double> u) {
    Slot& slot = slots_.local();
    slot.block.Reset(plan_, 0);
    gesweep::risk::ExecuteCellRun(plan_, 0, slot.workspace, slot.block, u);
    Score s;
    s.touchdown_s = slot.block.results[static_cast<std::size_t>(touchdown_)][0];
    s.touchdown_sink = slot.block.results[static_cast<std::size_t>(touchdown_sink_)][0];
    const double* h = slot.block.results[static_cast<std::size_t>(height_)].data();
    const double* v = slot.block.results[static_cast<std::size_t>(sink_)].data();
    for (std::size_t i = 0; i < times_.size(); ++i) {
      if (!std::isfinite(h[i]) || !std::isfinite(v[i])) break;
      s.z = std::max(s.z, v[i] - a_ * std::abs(h[i] - h_t_));
      if (i > 0 && h[i - 1] >= h_t_ && h[i] < h_t_) {
        const double f = (h[i - 1] - h_t_) / (h[i - 1] - h[i]);
        const double at = v[i - 1] + f * (v[i] - v[i - 1]);
        s.z = std::max(s.z, at);
        if (std::isnan(s.s_first)) {
          s.s_first = at;
          s.t_first = times_[i - 1] + f * (times_[i] - times_[i - 1]);
        }
      }
    }
    return s;
  }

 private:
  struct Slot {
    explicit Slot(const gesweep::SweepPlan& plan) : workspace(plan) { block.Allocate(plan); }
    gesweep::RunWorkspace workspace;
    gesweep::ResultBlock block;
  };
  const gesweep::SweepPlan& plan_;
  double h_t_, a_;
  tbb::enumerable_thread_specific<Slot> slots_;
  int height_ = -1, sink_ = -1, touchdown_ = -1, touchdown_sink_ = -1;
  std::vector<double> times_;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 8 && argc != 9) {
    std::fprintf(
        stderr,
        "usage: risk_proxy_subset STUDY LOWERED_WHEELS_M LIMIT_MPS A_PER_S N SEED REPETITIONS [CHECKS]\n");
    return 2;
  }
  const double wheels = std::atof(argv[2]);
  const double limit = std::atof(argv[3]);
  const double a = std::atof(argv[4]);
  const int n = std::atoi(argv[5]);
  const std::uint64_t seed = std::strtoull(argv[6], nullptr, 10);
  const int repetitions = std::atoi(argv[7]);
  const int checks = argc == 9 ? std::atoi(argv[8]) : 20;
  if (!(wheels > 0) || !(limit > 0) || !(a >= 0) || n < 10 || n % 10 != 0 || repetitions < 1 || checks < 0) {
    std::fprintf(
        stderr,
        "risk_proxy_subset: expected LOWERED_WHEELS_M > 0, LIMIT_MPS > 0, A_PER_S >= 0, N a multiple of 10, "
        "REPETITIONS >= 1, CHECKS >= 0\n");
    return 2;
  }
  try {
    const gesweep::SweepPlan real = gesweep::risk::programs::SeriesPlanOnNoiseGrid(argv[1]);
    const gesweep::SweepPlan proxy = gesweep::risk::programs::SeriesPlanOnNoiseGrid(
        argv[1], [&](gesweep::Study& study) { study.aircraft->wheel_contact_height_m = wheels; });
    const auto d = gesweep::risk::CellDimension(real, 0);
    if (gesweep::risk::CellDimension(proxy, 0) != d) {
      throw std::runtime_error("the proxy's noise dimension differs from the landing's (its time limit?)");
    }
    // H_t: the real still-air landing's touchdown height.
    const std::vector<double> origin(d, 0.0);
    double h_t = NAN;
    {
      gesweep::RunWorkspace workspace(real);
      gesweep::ResultBlock block;
      block.Allocate(real);
      block.Reset(real, 0);
      gesweep::risk::ExecuteCellRun(real, 0, workspace, block, origin);
      h_t = block.results[static_cast<std::size_t>(SchemaColumn(real, "results/landing/final_height_m"))][0];
    }
    if (!(wheels < h_t)) {
      std::fprintf(stderr,
                   "risk_proxy_subset: LOWERED_WHEELS_M = %g: expected below the touchdown height %.4f m\n",
                   wheels, h_t);
      return 2;
    }
    Scorer real_scorer(real, h_t, a), proxy_scorer(proxy, h_t, a);
    // The proxy reproduces the real landing up to its touchdown.
    double worst_sink = 0, worst_time = 0;
    std::mt19937_64 engine(seed);
    std::normal_distribution<double> normal;
    for (int c = 0; c < checks; ++c) {
      std::vector<double> u(d);
      for (double& x : u) x = normal(engine);
      const Score r = real_scorer.Fly(u), p = proxy_scorer.Fly(u);
      worst_sink = std::max(worst_sink, std::abs(r.touchdown_sink - p.s_first));
      worst_time = std::max(worst_time, std::abs(r.touchdown_s - p.t_first));
      if (!(std::abs(r.touchdown_sink - p.s_first) < 0.05)) {
        std::printf(
            "# check %d: real touchdown %.4f s at %.5f m/s, proxy's first crossing %.4f s at %.5f m/s\n", c,
            r.touchdown_s, r.touchdown_sink, p.t_first, p.s_first);
      }
    }
    std::printf(
        "# %s, wheels lowered to %.3f m: limit %.3f m/s, A %.3g /s, N %d, H_t %.4f m, dimension %lld; %d "
        "checks: largest "
        "|sink - s_first| %.2e m/s, |time| %.2e s\n",
        argv[1], wheels, limit, a, n, h_t, static_cast<long long>(d), checks, worst_sink, worst_time);
    if (!(worst_sink < 0.02) || !(worst_time < 0.01)) {
      std::fprintf(
          stderr,
          "risk_proxy_subset: %s: the lowered-wheels landing does not follow the real one to its touchdown "
          "(sink rate off by %.3g m/s, time by %.3g s; expected below 0.02 m/s and 0.01 s): are "
          "[analyses.landing] design_height_m and time_limit_s given?\n",
          argv[1], worst_sink, worst_time);
      return 2;
    }
    std::printf(
        "| repetition | P | stated CoV | levels | landings | ancestors at the last level | status |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    std::fflush(stdout);
    gesweep::risk::programs::RepetitionTally tally;
    for (int r = 0; r < repetitions; ++r) {
      gesweep::rare::SubsetOptions options;
      options.level_probability = 0.1;
      options.samples_per_level = n;
      options.max_levels = 14;
      options.seed = seed + static_cast<std::uint64_t>(r);
      options.min_chains = 10;
      const auto g = gesweep::rare::ParallelLimitState([&](std::span<const double> u) {
        const Score s = proxy_scorer.Fly(u);
        if (!std::isfinite(s.z)) return std::numeric_limits<double>::quiet_NaN();
        const bool failed = std::isfinite(s.s_first) && s.s_first > limit;
        return limit + kBonus - (s.z + (failed ? kBonus : 0.0));
      });
      const auto result = gesweep::rare::RunSubsetSimulation(g, static_cast<int>(d), options);
      std::printf("| %d | %.4g | %.3f | %zu | %lld | %lld | %d |\n", r, result.probability,
                  result.coefficient_of_variation, result.levels.size(),
                  static_cast<long long>(result.evaluations),
                  static_cast<long long>(result.levels.back().ancestors), static_cast<int>(result.status));
      std::printf("#   thresholds (limit + 100 - b):");
      for (const auto& level : result.levels) std::printf(" %.3f", limit + kBonus - level.threshold);
      std::printf("; acceptance:");
      for (const auto& level : result.levels) std::printf(" %.2f", level.acceptance_rate);
      std::printf("; ancestors:");
      for (const auto& level : result.levels) std::printf(" %lld", static_cast<long long>(level.ancestors));
      std::printf("\n");
      std::fflush(stdout);
      tally.Add(result.probability, result.evaluations);
    }
    tally.Print();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "risk_proxy_subset: %s\n", e.what());
    return 2;
  }
  return 0;
}
