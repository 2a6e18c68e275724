// A sink-rate limit's probability by splitting with restarts (RESTART: Villen-Altamirano and
// Villen-Altamirano, 1991 and Operations Research 42, 1994), each branch flown on from a checkpoint
// of the landing (ResumeLanding), not from the start (docs/dispersion.md, "Splitting with restarts").
// Not a test: minutes of CPU.
//
//   risk_restart [--threads T] [--cell C] STUDY LIMITS A_PER_S N SEED THRESHOLDS SPLITS [REPETITIONS]
//
// LIMITS "3.05" or "1.83,2.43,3.05" (sink rates, m/s, each estimated from the same landings),
// C: the cell of the study's design (default 0; studies/paper/landing_risk.toml: 0 with the
// h-derivatives, 1 without).
// THRESHOLDS "T1,T2,...,TM" (ascending, m/s) and SPLITS "R1,R2,...,RM" (integers >= 1).
//
// The importance function of a landing at a step is xi = sink rate - A_PER_S * (H - H_touch), the
// sink rate the wheels would meet if it decayed by A_PER_S per metre of height left; at the
// touchdown xi is the touchdown sink rate. A landing (weight 1, level 0) flies from the start. When
// a path of level l steps to xi >= T(l+1) it enters level l+1: R(l+1) - 1 retrials are flown on from
// its checkpoint there with fresh noise (ResumeLanding with a run index of their own), and it and
// they carry weight 1 / (R1 ... R(l+1)). A retrial born at level b is stopped when its xi falls
// below T(b); a path born below level l that falls below T(l) goes back to level l - 1 and its
// weight. A touchdown past a limit adds the path's weight to its landing's score Y for that limit. No split
// at a touchdown (the touchdown is the end). Y is unbiased for P(sink rate > limit) whatever the thresholds
// (the retrials of a split are conditionally independent copies of the path from its state there; the path
// itself is one of them), and the N landings' Y are independent: the estimate is their mean, its standard
// error their standard deviation / sqrt(N), measured, not stated. The landings' own touchdowns are plain
// Monte Carlo on the same N.
// A landing's tree is a function of (SEED, its index) alone, so the estimates are the same on any
// number of threads (tests/risk/risk_restart_threads_test.py).
// Cost: the flown time of every path and retrial in units of the landings' mean flown time
// ("landings"), and the wall time beside that of the N landings alone.
// Checks first that the program's landing is the study's: the first 3 landings flown through the
// study (ExecuteCellRun) and here touch down at the same time and sink rate bit for bit, or exit 2.
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/analyses/parameter_catalog.h"
#include "engine/control/landing_simulation.h"
#include "engine/disturbance/run_noise.h"
#include "engine/risk/landing_risk.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"
#include "engine/sweep/sweep_plan.h"
#include "tests/risk/risk_program_columns.h"

namespace {

using gesweep::LandingCheckpoint;
using gesweep::LandingConfig;
using gesweep::LandingObserver;
using gesweep::LandingOutcome;
using gesweep::LandingResult;
using gesweep::LandingStep;
using gesweep::LongitudinalModel;

std::vector<double> ParseList(const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(std::stod(item));
  return values;
}

struct Design {
  std::vector<double> limits;
  double a = 0;
  double wheels_m = 0;
  std::vector<double> threshold;  // T[1..M] at 1..M; T[0] = -inf
  std::vector<int> split;         // R[1..M]
  std::vector<double> weight;     // 1 / (R1 ... Rl) for l = 0..M
  int levels() const { return static_cast<int>(split.size()) - 1; }
};

// One landing and its tree of retrials.
struct Tree {
  std::vector<double> y;   // per limit, the score: weights of the touchdowns past it
  std::vector<int> plain;  // per limit, whether the landing itself (the path of level 0) passed it
  double landing_s = 0;    // the landing's own flown time
  double flown_s = 0;      // every path's flown time
  long retrials = 0;
  std::vector<double> entries;  // per level: the weighted count of entries
};

class Restart {
 public:
  Restart(const LongitudinalModel& plant, const LandingConfig& config, const Design& d, std::uint64_t seed)
      : plant_(plant), config_(config), d_(d), seed_(seed) {}

  Tree Fly(std::uint64_t landing) const {
    Tree tree;
    tree.entries.assign(static_cast<std::size_t>(d_.levels() + 1), 0.0);
    tree.y.assign(d_.limits.size(), 0.0);
    tree.plain.assign(d_.limits.size(), 0);
    std::uint64_t counter = 0;
    LandingConfig config = config_;
    config.seed = seed_;
    config.run_index = landing;
    Path path{0, 0, false};
    std::atomic<bool> stop{false};
    const LandingObserver observer = [&](const LandingStep& s) {
      Observe(s, path, stop, tree, landing, counter);
    };
    const LandingResult r = gesweep::SimulateLanding(plant_, config, &stop, {}, &observer);
    tree.landing_s = r.final_time_s;
    tree.flown_s += r.final_time_s;
    Score(r, path, tree);
    for (std::size_t k = 0; k < d_.limits.size(); ++k) {
      tree.plain[k] = r.outcome == LandingOutcome::kLanded && r.touchdown_sink_rate_mps > d_.limits[k];
    }
    return tree;
  }

 private:
  struct Path {
    int birth;
    int level;
    bool killed;
  };

  void Score(const LandingResult& r, const Path& path, Tree& tree) const {
    if (r.cancelled || r.outcome != LandingOutcome::kLanded) return;
    for (std::size_t k = 0; k < d_.limits.size(); ++k) {
      if (r.touchdown_sink_rate_mps > d_.limits[k])
        tree.y[k] += d_.weight[static_cast<std::size_t>(path.level)];
    }
  }

  void Observe(const LandingStep& s, Path& path, std::atomic<bool>& stop, Tree& tree, std::uint64_t landing,
               std::uint64_t& counter) const {
    if (path.killed) return;
    const double xi = s.sink_rate_mps() - d_.a * (s.height_m() - d_.wheels_m);
    while (path.level > path.birth && xi < d_.threshold[static_cast<std::size_t>(path.level)]) --path.level;
    if (path.birth > 0 && xi < d_.threshold[static_cast<std::size_t>(path.birth)]) {
      path.killed = true;
      stop.store(true, std::memory_order_relaxed);
      return;
    }
    if (s.height_m() <= d_.wheels_m) return;  // the touchdown: no split
    while (path.level < d_.levels() && xi >= d_.threshold[static_cast<std::size_t>(path.level + 1)]) {
      ++path.level;
      tree.entries[static_cast<std::size_t>(path.level)] +=
          d_.weight[static_cast<std::size_t>(path.level - 1)];
      const int copies = d_.split[static_cast<std::size_t>(path.level)] - 1;
      if (copies == 0) continue;
      const LandingCheckpoint checkpoint = s.Checkpoint();
      for (int c = 0; c < copies; ++c) Retrial(checkpoint, path.level, tree, landing, counter);
    }
  }

  void Retrial(const LandingCheckpoint& from, int level, Tree& tree, std::uint64_t landing,
               std::uint64_t& counter) const {
    if (++tree.retrials > 20'000'000) throw std::runtime_error("more than 2e7 retrials in one landing");
    LandingConfig config = config_;
    config.seed = seed_ ^ 0x5245535441525421ULL;  // "RESTART!": the retrials' streams
    config.run_index = (landing << 32) + counter++;
    Path path{level, level, false};
    std::atomic<bool> stop{false};
    const LandingObserver observer = [&](const LandingStep& s) {
      Observe(s, path, stop, tree, landing, counter);
    };
    const LandingResult r = gesweep::ResumeLanding(plant_, config, from, &stop, {}, &observer);
    tree.flown_s += r.final_time_s - from.time_s;
    if (!path.killed) Score(r, path, tree);
  }

  const LongitudinalModel& plant_;
  const LandingConfig& config_;
  const Design& d_;
  std::uint64_t seed_;
};

}  // namespace

int main(int argc, char** argv) {
  int threads = 0;        // 0: every core
  std::int64_t cell = 0;  // of the study's design
  while (argc > 2 && (std::string(argv[1]) == "--threads" || std::string(argv[1]) == "--cell")) {
    const bool is_threads = std::string(argv[1]) == "--threads";
    const long long value = std::atoll(argv[2]);
    if (value < (is_threads ? 1 : 0)) {
      std::fprintf(stderr, "risk_restart: %s %s: expected an integer >= %d\n", argv[1], argv[2],
                   is_threads ? 1 : 0);
      return 2;
    }
    if (is_threads) {
      threads = static_cast<int>(value);
    } else {
      cell = value;
    }
    argv += 2;
    argc -= 2;
  }
  if (argc != 8 && argc != 9) {
    std::fprintf(stderr,
                 "usage: risk_restart [--threads T] [--cell C] STUDY LIMITS A_PER_S N SEED THRESHOLDS SPLITS "
                 "[REPETITIONS]\n");
    return 2;
  }
  Design d;
  d.limits = ParseList(argv[2]);
  d.a = std::atof(argv[3]);
  const int n = std::atoi(argv[4]);
  const std::uint64_t seed = std::strtoull(argv[5], nullptr, 10);
  const int repetitions = argc == 9 ? std::atoi(argv[8]) : 1;
  const std::vector<double> thresholds = ParseList(argv[6]);
  const std::vector<double> splits = ParseList(argv[7]);
  if (n < 10 || repetitions < 1 || d.limits.empty() || thresholds.empty() ||
      thresholds.size() != splits.size() || !(d.a >= 0)) {
    std::fprintf(stderr,
                 "risk_restart: expected N >= 10, REPETITIONS >= 1, A_PER_S >= 0 and as many SPLITS as "
                 "THRESHOLDS (got %zu and %zu)\n",
                 thresholds.size(), splits.size());
    return 2;
  }
  d.threshold.push_back(-INFINITY);
  d.split.push_back(1);
  d.weight.push_back(1.0);
  for (std::size_t i = 0; i < thresholds.size(); ++i) {
    const double r = splits[i];
    if (!(r >= 1) || r != std::floor(r) || thresholds[i] <= d.threshold.back()) {
      std::fprintf(
          stderr, "risk_restart: expected ascending THRESHOLDS and integer SPLITS >= 1 (level %zu)\n", i + 1);
      return 2;
    }
    d.threshold.push_back(thresholds[i]);
    d.split.push_back(static_cast<int>(r));
    d.weight.push_back(d.weight.back() / r);
  }
  try {
    const gesweep::SweepPlan plan(gesweep::LoadStudy(argv[1]), gesweep::ShardSpec{});
    gesweep::RunWorkspace workspace(plan);
    if (cell >= gesweep::risk::CellCount(plan)) {
      std::fprintf(stderr, "risk_restart: %s: --cell %lld: the study has %lld cells\n", argv[1],
                   static_cast<long long>(cell), static_cast<long long>(gesweep::risk::CellCount(plan)));
      return 2;
    }
    workspace.parameters = gesweep::risk::CellParameters(plan, cell);
    const LongitudinalModel& plant = workspace.Model(plan);
    d.wheels_m = plant.aircraft().wheel_contact_height_m;
    // The study's landing (studies/bench/landing_risk_hard.toml and its kind): the start, the wind,
    // shear and turbulence of its cell, every other setting the default; checked below.
    const gesweep::RunParameters& p = workspace.parameters;
    auto at = [&](const char* name) {
      const auto id = gesweep::FindParameter(name);
      if (!id) throw std::runtime_error(std::string("no run parameter ") + name);
      return p[static_cast<std::size_t>(*id)];
    };
    LandingConfig config;
    config.start_height_m = at("height_m");
    config.start_speed_mps = at("speed_mps");
    config.output_interval_s = 0.0;
    config.disturbance.wind_20ft_mps = at("wind_20ft_mps");
    config.disturbance.turbulence = gesweep::TurbulenceModel::kDryden;
    config.disturbance.wind_shear = gesweep::WindShear::kLogarithmic;

    // The check: the first landings through the study and here.
    {
      const int sink = gesweep::risk::programs::SchemaColumn(plan, "results/landing/touchdown_sink_rate_mps");
      const int time = gesweep::risk::programs::SchemaColumn(plan, "results/landing/touchdown_time_s");
      gesweep::ResultBlock block;
      block.Allocate(plan);
      const auto dimension = gesweep::risk::CellDimension(plan, cell);
      for (std::uint64_t k = 0; k < 3; ++k) {
        std::vector<double> u(dimension);
        const gesweep::RunNoise noise(seed, k);
        for (std::uint64_t j = 0; j < dimension; ++j)
          u[j] = noise.StandardNormal(gesweep::NoiseStream::kInitialState, 1000 + j);
        block.Reset(plan, 0);
        gesweep::risk::ExecuteCellRun(plan, cell, workspace, block, u);
        const LandingResult r = gesweep::SimulateLanding(plant, config, nullptr, u);
        const double s = block.results[static_cast<std::size_t>(sink)][0];
        const double t = block.results[static_cast<std::size_t>(time)][0];
        if (!(s == r.touchdown_sink_rate_mps && t == r.touchdown_time_s)) {
          std::fprintf(
              stderr,
              "risk_restart: %s: the program's landing is not the study's (touchdown %.17g s, %.17g m/s "
              "against %.17g s, %.17g m/s); expected a study like studies/bench/landing_risk_hard.toml\n",
              argv[1], r.touchdown_time_s, r.touchdown_sink_rate_mps, t, s);
          return 2;
        }
      }
    }

    std::printf(
        "# %s, cell %lld (%s): P(touchdown sink rate > %s m/s), xi = sink rate - %g /s (H - %.4g m), N = %d, "
        "seed %llu\n",
        argv[1], static_cast<long long>(cell), gesweep::risk::CellLabel(plan, cell).c_str(), argv[2], d.a,
        d.wheels_m, n, static_cast<unsigned long long>(seed));
    std::printf("# levels:");
    for (int l = 1; l <= d.levels(); ++l) std::printf(" T%d = %g (R = %d)", l, d.threshold[l], d.split[l]);
    std::printf("\n");
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    gesweep::risk::programs::RepetitionTally tally;
    for (int rep = 0; rep < repetitions; ++rep) {
      const std::uint64_t rep_seed = seed + static_cast<std::uint64_t>(rep) * 1'000'003ULL;
      const Restart restart(plant, config, d, rep_seed);
      std::vector<Tree> trees(static_cast<std::size_t>(n));
      const auto started = std::chrono::steady_clock::now();
      arena.execute([&] {
        tbb::parallel_for(0, n, [&](int i) {
          trees[static_cast<std::size_t>(i)] = restart.Fly(static_cast<std::uint64_t>(i));
        });
      });
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      double landing_s = 0, flown_s = 0;
      long retrials = 0;
      std::vector<double> entries(static_cast<std::size_t>(d.levels() + 1), 0.0);
      for (const Tree& t : trees) {
        landing_s += t.landing_s;
        flown_s += t.flown_s;
        retrials += t.retrials;
        for (std::size_t l = 0; l < entries.size(); ++l) entries[l] += t.entries[l];
      }
      const double cost = flown_s / (landing_s / n);
      double last = 0;
      for (std::size_t k = 0; k < d.limits.size(); ++k) {
        double sum = 0, sum2 = 0, plain = 0;
        long scored = 0;
        for (const Tree& t : trees) {
          sum += t.y[k];
          sum2 += t.y[k] * t.y[k];
          plain += t.plain[k];
          scored += t.y[k] > 0 ? 1 : 0;
        }
        const double mean = sum / n;
        const double var = (sum2 - n * mean * mean) / (n - 1);
        const double se = std::sqrt(std::max(var, 0.0) / n);
        std::printf(
            "run %d, sink rate > %g m/s: P = %.4g, standard error %.3g, CoV %.3f, 95 %% [%.3g, %.3g]; %ld of "
            "%d "
            "landings scored; plain on the same landings %g/%d = %.3g\n",
            rep, d.limits[k], mean, se, mean > 0 ? se / mean : NAN, mean - 1.96 * se, mean + 1.96 * se,
            scored, n, plain, n, plain / n);
        last = mean;
      }
      std::printf("  cost: %.0f landings of flown time (%ld retrials), %.1f s wall; entries per landing:",
                  cost, retrials, wall);
      for (int l = 1; l <= d.levels(); ++l) std::printf(" %.3g", entries[static_cast<std::size_t>(l)] / n);
      std::printf("\n");
      std::fflush(stdout);
      tally.Add(last, static_cast<long long>(cost));  // the last limit
    }
    tally.Print();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "risk_restart: %s\n", e.what());
    return 2;
  }
  return 0;
}
