// How far ahead a landing's touchdown sink rate is decided (docs/dispersion.md, "What the hard
// landing is made of"). Not a test: a minute of CPU.
//
//   risk_touchdown_memory STUDY N SEED
//
// Flies N landings of the study's first cell with u ~ N(0, I) (std::mt19937_64, not the engine's
// streams), its series every noise sample interval, and prints:
// - the touchdown time's quantiles and the touchdown sink rate's mean, standard deviation and largest;
// - for each time-to-go T, over the landings: the correlation of the sink rate at T before touchdown
//   with the touchdown sink rate, and the standard deviation left about their least-squares line (the
//   touchdown sink rate's spread once the state at T is known, through its sink rate).
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/risk/landing_risk.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"
#include "engine/sweep/sweep_plan.h"
#include "tests/risk/risk_program_columns.h"

namespace {

using gesweep::risk::programs::SchemaColumn;

constexpr double kTimesToGo[] = {0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 1.0, 2.0};
constexpr int kOffsets = sizeof(kTimesToGo) / sizeof(kTimesToGo[0]);

struct Landing {
  double touchdown_s = NAN, sink = NAN;
  double before[kOffsets];
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: risk_touchdown_memory STUDY N SEED\n");
    return 2;
  }
  const int n = std::atoi(argv[2]);
  const std::uint64_t seed = std::strtoull(argv[3], nullptr, 10);
  if (n < 10) {
    std::fprintf(stderr, "risk_touchdown_memory: expected N >= 10\n");
    return 2;
  }
  try {
    const gesweep::SweepPlan plan = gesweep::risk::programs::SeriesPlanOnNoiseGrid(argv[1]);
    const double interval = gesweep::risk::CellSampleInterval(plan, 0);
    const int sink_series = SchemaColumn(plan, "series/landing/sink_rate_mps");
    const int touchdown = SchemaColumn(plan, "results/landing/touchdown_time_s");
    const int touchdown_sink = SchemaColumn(plan, "results/landing/touchdown_sink_rate_mps");
    std::vector<double> times;
    for (const auto& axis : plan.schema().axes) {
      if (axis.path == "series/landing/time_s") times = axis.times_s;
    }
    const auto d = static_cast<std::size_t>(gesweep::risk::CellDimension(plan, 0));
    std::vector<Landing> landings(static_cast<std::size_t>(n));
    // One workspace and result block per thread, reused by its landings.
    struct Slot {
      explicit Slot(const gesweep::SweepPlan& p) : workspace(p) { block.Allocate(p); }
      gesweep::RunWorkspace workspace;
      gesweep::ResultBlock block;
    };
    tbb::enumerable_thread_specific<Slot> slots([&] { return Slot(plan); });
    tbb::parallel_for(0, n, [&](int i) {
      Slot& slot = slots.local();
      gesweep::RunWorkspace& workspace = slot.workspace;
      gesweep::ResultBlock& block = slot.block;
      block.Reset(plan, 0);
      std::mt19937_64 engine(seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(i));
      std::normal_distribution<double> normal;
      std::vector<double> u(d);
      for (double& x : u) x = normal(engine);
      gesweep::risk::ExecuteCellRun(plan, 0, workspace, block, u);
      Landing& l = landings[static_cast<std::size_t>(i)];
      l.touchdown_s = block.results[static_cast<std::size_t>(touchdown)][0];
      l.sink = block.results[static_cast<std::size_t>(touchdown_sink)][0];
      for (int k = 0; k < kOffsets; ++k) {
        // The series sample nearest to T before touchdown.
        const double t = l.touchdown_s - kTimesToGo[k];
        const auto j = static_cast<std::size_t>(std::llround(t / interval));
        l.before[k] = std::isfinite(t) && t >= 0 && j < times.size()
                          ? block.results[static_cast<std::size_t>(sink_series)][j]
                          : NAN;
      }
    });
    std::vector<const Landing*> landed;
    for (const auto& l : landings) {
      if (std::isfinite(l.touchdown_s) && std::isfinite(l.sink)) landed.push_back(&l);
    }
    if (landed.size() < 3) {
      std::fprintf(stderr,
                   "risk_touchdown_memory: %s: %zu of %d landings touched down; expected at least 3\n",
                   argv[1], landed.size(), n);
      return 2;
    }
    std::vector<double> t;
    double mean = 0, m2 = 0, largest = -INFINITY;
    for (const Landing* l : landed) {
      t.push_back(l->touchdown_s);
      mean += l->sink;
      largest = std::max(largest, l->sink);
    }
    mean /= static_cast<double>(landed.size());
    for (const Landing* l : landed) m2 += (l->sink - mean) * (l->sink - mean);
    std::sort(t.begin(), t.end());
    const auto q = [&](double f) {
      return t[static_cast<std::size_t>(f * static_cast<double>(t.size() - 1))];
    };
    std::printf("# %s: %zu of %d landings touched down (seed %llu)\n", argv[1], landed.size(), n,
                static_cast<unsigned long long>(seed));
    std::printf(
        "# touchdown time, s: min %.1f, 1 %% %.1f, 10 %% %.1f, median %.1f, 90 %% %.1f, 99 %% %.1f, max "
        "%.1f\n",
        q(0), q(0.01), q(0.1), q(0.5), q(0.9), q(0.99), q(1));
    std::printf("# touchdown sink rate: mean %.3f m/s, standard deviation %.3f m/s, largest %.3f m/s\n", mean,
                std::sqrt(m2 / static_cast<double>(landed.size() - 1)), largest);
    std::printf(
        "| time to go, s | correlation of the sink rate then with the touchdown's | spread left, m/s |\n");
    std::printf("|---|---|---|\n");
    for (int k = 0; k < kOffsets; ++k) {
      double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, count = 0;
      for (const Landing* l : landed) {
        const double x = l->before[k], y = l->sink;
        if (!std::isfinite(x)) continue;
        sx += x;
        sy += y;
        sxx += x * x;
        syy += y * y;
        sxy += x * y;
        count += 1;
      }
      const double cxx = sxx - sx * sx / count, cyy = syy - sy * sy / count, cxy = sxy - sx * sy / count;
      const double r = cxy / std::sqrt(cxx * cyy);
      const double left = std::sqrt(cyy * (1 - r * r) / (count - 2));
      std::printf("| %.2f | %.3f | %.3f |\n", kTimesToGo[k], r, left);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "risk_touchdown_memory: %s\n", e.what());
    return 2;
  }
  return 0;
}
