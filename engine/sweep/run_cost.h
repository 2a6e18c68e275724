#pragma once
/// The dry run's time estimate (docs/sweep.md, "Dry run"): sample runs of a plan, timed within a
/// wall-time budget whatever the study, on as many threads as the sweep will use.
///
/// How. Each thread first runs one warm-up burst (model built, caches and code paged in; not
/// counted), then bursts of a few consecutive design runs -- consecutive, as the sweep runs them,
/// so that the per-worker model cache behaves as in the sweep -- starting at points of the
/// golden-ratio sequence over the shard (no grid axis aliases with it), until the budget is spent or
/// as many runs as the shard holds were timed (a small sweep is measured once over, not for the
/// whole budget). Every sample run gets a
/// cancellation flag that fires at the deadline (or when `stop` is set), so even a single run
/// longer than the budget cannot make the estimate overrun it. The estimate is the mean time per
/// run on one thread, under the contention of the others, times the run count over the threads;
/// its spread is the 95 % interval of that mean from the bursts' scatter.

#include <atomic>
#include <cstdint>
#include <vector>

#include "engine/sweep/sweep_plan.h"

namespace gesweep {

/// Options of EstimateRunCost.
struct RunCostOptions {
  int threads = 1;        ///< threads the sweep will use (and the sampling uses)
  double budget_s = 2.0;  ///< wall time for the whole measurement, warm-up included; > 0
  int burst_runs = 8;     ///< consecutive runs per sample (cut to the plan's batch size)
  int lanes = 1;  ///< the sweep's lane width (RunnerOptions::lanes): a burst is run as the sweep runs it
};

/// What EstimateRunCost measured.
struct RunCostEstimate {
  double seconds_per_run = 0;      ///< mean time of one run on one thread
  double seconds_per_run_low = 0;  ///< 95 % interval of that mean (equal to it with < 3 bursts)
  double seconds_per_run_high = 0;
  double estimated_seconds = 0;  ///< seconds_per_run x the shard's runs / threads
  double estimated_seconds_low = 0;
  double estimated_seconds_high = 0;
  std::int64_t timed_runs = 0;  ///< runs the estimate is made of
  std::int64_t timed_bursts = 0;
  std::int64_t warmup_runs = 0;  ///< runs of the warm-up bursts (not in the estimate unless alone)
  double measured_s = 0;         ///< wall time the measurement took
  /// A sample run was stopped at the deadline before it finished: runs are so long that the
  /// estimate is a lower bound (seconds_per_run is at least the time that run had taken).
  bool lower_bound = false;
  /// `stop` was set (SIGINT/SIGTERM) before the budget was used up.
  bool stopped = false;
};

/// Measures a plan's run cost within options.budget_s of wall time (plus the time one thread takes
/// to notice the deadline: at most one integration step or one fast analysis). Nothing is written.
/// `stop` (may be null) ends the measurement early.
RunCostEstimate EstimateRunCost(const SweepPlan& plan, const RunCostOptions& options,
                                const std::atomic<bool>* stop = nullptr);

/// The 95 % interval of a mean time per run `center` from the scatter of the per-run times of three
/// or more bursts or batches (`per_run`): low = max(0, center - h), high = center + h, h = z95 s / sqrt(n),
/// s the sample standard deviation. With fewer than three, `low` and `high` are left as they are.
/// EstimateRunCost's interval and MeasureWriteCost's (engine/archive/write_cost.h).
void SetInterval95(const std::vector<double>& per_run, double center, double& low, double& high);

/// Wall time, s, RunSweep takes on `threads` threads for `plan` when there is no batch to run: its
/// fixed cost, whatever the sweep's size -- the pool of batch buffers allocated (sized as the
/// sweep's), the writer thread started and joined, the task arena (on the process's first use of
/// TBB, its scheduler too). Runs nothing, writes nothing. Call it before anything else uses TBB in
/// the process, as the sweep's RunSweep is the first use in `gesweep run`.
double MeasurePipelineStart(const SweepPlan& plan, int threads);

/// The measured parts of a sweep's wall time (docs/sweep.md, "Dry run"), all in seconds.
struct SweepTimeParts {
  double compute_s_per_run = 0;  ///< one run on one worker thread, with every worker busy
  double encode_s_per_run = 0;   ///< a worker encoding a run's share of its batch
  double store_s_per_run = 0;    ///< the one writer thread storing a run's share of a batch
  double fixed_s = 0;            ///< once per sweep, whatever its size (archive set-up, pipeline, close)
};

/// Wall time per run at the pipeline's steady rate, s: the slowest of the workers' share
/// (compute + encode) / threads, the writer's store, and both sharing the cores,
/// (compute + encode + store) / min(threads + 1, cores). threads >= 1, cores >= 1.
double SteadyWallPerRun(const SweepTimeParts& parts, int threads, int cores);

/// Wall time of a sweep of `runs` runs in batches of `chunk_runs`, s: one batch (min(chunk_runs,
/// runs) runs) passes through the whole pipeline -- computed on every thread, encoded by one
/// worker, stored by the writer: rows x (compute / threads + encode + store) -- while the other
/// runs go at SteadyWallPerRun; plus fixed_s. The first term is what a short sweep, of one or a
/// few batches, cannot overlap. runs >= 0, chunk_runs >= 1, threads >= 1, cores >= 1.
double SweepSeconds(const SweepTimeParts& parts, std::int64_t runs, int chunk_runs, int threads, int cores);

}  // namespace gesweep
