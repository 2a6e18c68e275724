#include "engine/sweep/run_cost.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "engine/common/errors.h"
#include "engine/sweep/runner.h"

namespace gesweep {
namespace {

using Clock = std::chrono::steady_clock;

// The golden-ratio (Weyl) sequence: an even stride would alias with a grid axis whose length it
// divides (every sample at one height, say).
constexpr double kGoldenRatioFraction = 0.6180339887498949;
// How often the watchdog looks at the external stop flag.
constexpr auto kStopPollInterval = std::chrono::milliseconds(10);

struct Burst {
  std::int64_t runs = 0;
  double seconds = 0;
};

struct ThreadResult {
  std::vector<Burst> bursts;
  Burst warmup;
  bool cut = false;          // a run was stopped at the deadline
  double longest_cut_s = 0;  // how long the stopped burst had run
};

// The sink of MeasurePipelineStart's sweep of no batch: never called.
class NoSink final : public ResultSink {
 public:
  void Write(const ResultBlock&) override { GESWEEP_UNREACHABLE(); }
};

// Runs design runs first .. first + burst - 1 of the shard as the sweep runs them (one at a time, or
// as one group in `lanes` lanes: RunsInLanes) until one is stopped at `expired`; returns the runs
// finished, and sets `cut` when one was stopped.
std::int64_t FlyBurst(const SweepPlan& plan, std::int64_t first, std::int64_t burst, int lanes,
                      const std::atomic<bool>& expired, RunWorkspace& workspace, ResultBlock& block,
                      bool& cut) {
  auto pending = [&](std::int64_t r) {
    return block.status[static_cast<std::size_t>(r)] == static_cast<std::int8_t>(RunStatus::kPending);
  };
  cut = false;
  if (!RunsInLanes(plan, lanes)) {
    for (std::int64_t r = 0; r < burst; ++r) {
      ExecuteRun(plan, plan.first_run() + first + r, workspace, block, static_cast<int>(r), &expired);
      cut = pending(r);
      if (cut) return r;
    }
    return burst;
  }
  for (std::int64_t r = 0; r < burst; ++r)
    block.design_index[static_cast<std::size_t>(r)] = plan.first_run() + first + r;
  ExecuteRuns(plan, workspace, block, 0, static_cast<int>(burst), lanes, &expired);
  std::int64_t done = 0;
  for (std::int64_t r = 0; r < burst; ++r) {
    cut = cut || pending(r);
    done += pending(r) ? 0 : 1;
  }
  return done;
}

// One thread's sampling: bursts of `burst` runs spread over the shard by the golden-ratio sequence
// (burst numbers from `next_burst`), the first a warm-up, until `expired` or the shard's runs are
// timed (`timed_total`, shared by the threads).
void SampleBursts(const SweepPlan& plan, std::int64_t burst, int lanes, const std::atomic<bool>& expired,
                  std::atomic<std::int64_t>& next_burst, std::atomic<std::int64_t>& timed_total,
                  ThreadResult& out) {
  const std::int64_t runs = plan.run_count();
  ResultBlock block;
  block.Allocate(plan);
  block.Reset(plan, 0);
  RunWorkspace workspace(plan);
  bool warm = false;
  while (!expired.load() && timed_total.load() < runs) {
    const std::int64_t k = next_burst.fetch_add(1);
    const double where = std::fmod((static_cast<double>(k) + 0.5) * kGoldenRatioFraction, 1.0);
    const std::int64_t first =
        std::min<std::int64_t>(runs - burst, static_cast<std::int64_t>(where * static_cast<double>(runs)));
    const auto burst_start = Clock::now();
    bool cut = false;
    const std::int64_t done = FlyBurst(plan, first, burst, lanes, expired, workspace, block, cut);
    const double seconds = std::chrono::duration<double>(Clock::now() - burst_start).count();
    if (cut) {
      // Stopped at the deadline: the burst took at least this long.
      out.cut = out.cut || done == 0;
      if (done == 0) out.longest_cut_s = std::max(out.longest_cut_s, seconds);
      if (done > 0 && !warm) out.warmup = {done, seconds};
      break;
    }
    if (!warm) {
      out.warmup = {done, seconds};
      warm = true;
      continue;
    }
    out.bursts.push_back({done, seconds});
    timed_total.fetch_add(done);
  }
}

// The threads' bursts summed into the estimate's counts and seconds per run (from the warm-up bursts
// when no timed one finished; at least a cut run's time when only cut runs are left). Returns each
// timed burst's seconds per run.
std::vector<double> SummariseBursts(const std::vector<ThreadResult>& results, RunCostEstimate& estimate) {
  std::vector<double> per_run;  // each timed burst's seconds per run
  double seconds = 0;
  double longest_cut_s = 0;
  bool cut_alone = false;
  Burst warmup;
  for (const ThreadResult& r : results) {
    for (const Burst& b : r.bursts) {
      per_run.push_back(b.seconds / static_cast<double>(b.runs));
      seconds += b.seconds;
      estimate.timed_runs += b.runs;
    }
    warmup.runs += r.warmup.runs;
    warmup.seconds += r.warmup.seconds;
    cut_alone = cut_alone || r.cut;
    longest_cut_s = std::max(longest_cut_s, r.longest_cut_s);
  }
  estimate.warmup_runs = warmup.runs;
  estimate.timed_bursts = static_cast<std::int64_t>(per_run.size());
  if (estimate.timed_runs > 0) {
    estimate.seconds_per_run = seconds / static_cast<double>(estimate.timed_runs);
  } else if (warmup.runs > 0) {
    // Only warm-up bursts finished within the budget: the best there is (cold, so on the high side).
    estimate.seconds_per_run = warmup.seconds / static_cast<double>(warmup.runs);
  }
  if (cut_alone && estimate.timed_runs == 0) {
    // A run that did not finish within the budget: runs take at least that long.
    estimate.seconds_per_run = std::max(estimate.seconds_per_run, longest_cut_s);
    estimate.lower_bound = true;
  }
  return per_run;
}

// The 95 % interval of the seconds per run, from the spread of three or more timed bursts (else the
// estimate itself at both ends).
void SetSecondsPerRunInterval(const std::vector<double>& per_run, RunCostEstimate& estimate) {
  estimate.seconds_per_run_low = estimate.seconds_per_run_high = estimate.seconds_per_run;
  SetInterval95(per_run, estimate.seconds_per_run, estimate.seconds_per_run_low,
                estimate.seconds_per_run_high);
}

}  // namespace

void SetInterval95(const std::vector<double>& per_run, double center, double& low, double& high) {
  if (per_run.size() < 3) return;
  // z of a two-sided 95 % normal interval.
  constexpr double kZ95 = 1.959963984540054;
  double mean = 0;
  for (double y : per_run) mean += y;
  mean /= static_cast<double>(per_run.size());
  double variance = 0;
  for (double y : per_run) variance += (y - mean) * (y - mean);
  variance /= static_cast<double>(per_run.size() - 1);
  const double half_width = kZ95 * std::sqrt(variance / static_cast<double>(per_run.size()));
  low = std::max(0.0, center - half_width);
  high = center + half_width;
}

RunCostEstimate EstimateRunCost(const SweepPlan& plan, const RunCostOptions& options,
                                const std::atomic<bool>* stop) {
  GESWEEP_DEMAND(options.threads >= 1 && options.budget_s > 0 && options.burst_runs >= 1);
  const auto start = Clock::now();
  const auto deadline =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.budget_s));
  const std::int64_t runs = plan.run_count();
  const std::int64_t burst = std::min<std::int64_t>({options.burst_runs, plan.chunk_runs(), runs});

  // The sample runs' cancellation flag: set at the deadline or when `stop` is.
  std::atomic<bool> stopped{stop != nullptr && stop->load()};
  std::atomic<bool> expired{stopped.load()};
  std::mutex mutex;
  std::condition_variable wake;
  bool finished = false;
  std::thread watchdog([&] {
    std::unique_lock<std::mutex> lock(mutex);
    while (!finished) {
      if (stop != nullptr && stop->load()) {
        stopped.store(true);
        break;
      }
      if (Clock::now() >= deadline) break;
      wake.wait_until(lock, std::min(deadline, Clock::now() + kStopPollInterval));
    }
    expired.store(true);
  });

  std::atomic<std::int64_t> next_burst{0};
  // A shard no larger than what the budget can sample is measured once over: sampling more would
  // take longer than the sweep itself.
  std::atomic<std::int64_t> timed_total{0};
  std::vector<ThreadResult> results(static_cast<std::size_t>(options.threads));
  auto sample = [&](ThreadResult& out) {
    SampleBursts(plan, burst, options.lanes, expired, next_burst, timed_total, out);
  };
  std::vector<std::thread> workers;
  for (int t = 1; t < options.threads; ++t)
    workers.emplace_back(sample, std::ref(results[static_cast<std::size_t>(t)]));
  sample(results[0]);
  for (auto& worker : workers) worker.join();
  {
    std::lock_guard<std::mutex> lock(mutex);
    finished = true;
  }
  wake.notify_all();
  watchdog.join();

  RunCostEstimate estimate;
  estimate.stopped = stopped.load() || (stop != nullptr && stop->load());
  estimate.measured_s = std::chrono::duration<double>(Clock::now() - start).count();
  const std::vector<double> per_run = SummariseBursts(results, estimate);
  SetSecondsPerRunInterval(per_run, estimate);
  const double scale = static_cast<double>(runs) / options.threads;
  estimate.estimated_seconds = estimate.seconds_per_run * scale;
  estimate.estimated_seconds_low = estimate.seconds_per_run_low * scale;
  estimate.estimated_seconds_high = estimate.lower_bound ? INFINITY : estimate.seconds_per_run_high * scale;
  return estimate;
}

double MeasurePipelineStart(const SweepPlan& plan, int threads) {
  GESWEEP_DEMAND(threads >= 1);
  const std::vector<std::int64_t> no_batch;
  NoSink sink;
  RunnerOptions options;
  options.threads = threads;
  const auto start = Clock::now();
  RunSweep(plan, no_batch, sink, options, nullptr);
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double SteadyWallPerRun(const SweepTimeParts& parts, int threads, int cores) {
  GESWEEP_DEMAND(threads >= 1 && cores >= 1);
  const double work = parts.compute_s_per_run + parts.encode_s_per_run;
  const int busy = std::min(threads + 1, cores);
  return std::max({work / threads, parts.store_s_per_run, (work + parts.store_s_per_run) / busy});
}

double SweepSeconds(const SweepTimeParts& parts, std::int64_t runs, int chunk_runs, int threads, int cores) {
  GESWEEP_DEMAND(runs >= 0 && chunk_runs >= 1 && threads >= 1 && cores >= 1);
  const std::int64_t first = std::min<std::int64_t>(chunk_runs, runs);
  const double one_batch_per_run =
      parts.compute_s_per_run / threads + parts.encode_s_per_run + parts.store_s_per_run;
  return static_cast<double>(first) * one_batch_per_run +
         static_cast<double>(runs - first) * SteadyWallPerRun(parts, threads, cores) + parts.fixed_s;
}

}  // namespace gesweep
