#pragma once
/// The parallel runner (docs/sweep.md, "Runner"). oneTBB schedules the runs of a plan in batches
/// (one batch = one HDF5 chunk of every column), each worker thread with its own workspace; finished
/// batches go through a bounded queue to ONE writer thread, which hands them to a ResultSink (the
/// HDF5 archive; the runner knows nothing of HDF5). A fixed pool of batch buffers bounds memory
/// whatever the run count. Every run's result depends only on its design row, so the archive is
/// the same bit for bit whatever the thread count or sharding.

#include <atomic>
#include <cstdint>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "engine/sweep/sweep_plan.h"

namespace gesweep {

/// Status of a run, as stored in /runs/status.
enum class RunStatus : std::int8_t {
  kPending = 0,  ///< not (completely) written yet: a resumed sweep runs it
  kOk = 1,
  kFailed = 2,  ///< a numerical failure or an exception; the message says why
};

/// One batch of consecutive runs of a shard, column by column.
struct ResultBlock {
  std::int64_t block_index = 0;  ///< batch number within the shard
  std::int64_t first_row = 0;    ///< shard-local row of its first run (block_index · chunk_runs)
  int rows = 0;
  std::vector<std::int64_t> design_index;
  std::vector<std::uint64_t> run_id;
  std::vector<std::int8_t> status;
  std::vector<std::string> message;
  std::vector<std::vector<double>> design;   ///< [design column][row]
  std::vector<std::vector<double>> results;  ///< [output column][row · doubles_per_run]

  /// Sizes the buffers for `plan` (capacity chunk_runs rows).
  void Allocate(const SweepPlan& plan);
  /// Prepares it for batch `block_index` of `plan`: row count, design indices, NaN-filled results.
  void Reset(const SweepPlan& plan, std::int64_t block_index);
};

/// Receives finished batches. Write is called from the one writer thread only, in no particular
/// batch order; it may throw (e.g. disk full), which stops the sweep.
class ResultSink {
 public:
  virtual ~ResultSink() = default;
  virtual void Write(const ResultBlock& block) = 0;
};

/// The per-thread state of the workers: the parameter vector, the design row, and a cache of the
/// last model built (consecutive runs often share their model parameters).
class RunWorkspace {
 public:
  explicit RunWorkspace(const SweepPlan& plan);
  /// The model for the workspace's current parameters: rebuilt only when a model parameter changed.
  const LongitudinalModel& Model(const SweepPlan& plan);
  RunParameters parameters;
  std::vector<double> design_row;

 private:
  std::vector<double> model_key_;
  std::optional<LongitudinalModel> model_;
};

/// Runs design run `design_index` (row `row` of `block`): fills its design values, id, status,
/// message and results. Never throws for a numerical problem or an exception of an analysis: the
/// run is marked failed with the message. `cancel` (may be null) reaches inside the analyses (time
/// responses check it between integration steps): a run it stops keeps status kPending.
void ExecuteRun(const SweepPlan& plan, std::int64_t design_index, RunWorkspace& workspace, ResultBlock& block,
                int row, const std::atomic<bool>* cancel = nullptr);

/// Counters the runner updates while it works (read them from any thread).
struct SweepProgress {
  std::atomic<std::int64_t> runs_done{0};     ///< computed in this process
  std::atomic<std::int64_t> runs_failed{0};   ///< of them, failed
  std::atomic<std::int64_t> runs_written{0};  ///< handed to the sink
  std::int64_t runs_to_do = 0;                ///< pending runs at the start
  std::int64_t runs_skipped = 0;              ///< already complete (resume)
};

/// Options of RunSweep.
struct RunnerOptions {
  int threads = 0;  ///< worker threads; 0: all cores
  /// Set (e.g. by a signal handler) to stop: no new batch is taken, the runs in flight stop between
  /// two integration steps, and a batch with a run left unfinished is not written (its runs stay
  /// pending for --resume). Batches finished before are written, so the archive stays resumable.
  const std::atomic<bool>* cancel = nullptr;
  int queue_batches = 4;  ///< capacity of the queue to the writer
};

/// What a sweep did.
struct SweepOutcome {
  std::int64_t runs_ok = 0;
  std::int64_t runs_failed = 0;
  std::int64_t runs_skipped = 0;
  bool cancelled = false;  ///< stopped by `cancel` before every batch was run and written
};

/// Runs the batches `pending_blocks` (ascending batch numbers of the plan's shard) and writes them
/// through `sink`. Rethrows the first exception of the sink after stopping cleanly.
SweepOutcome RunSweep(const SweepPlan& plan, const std::vector<std::int64_t>& pending_blocks,
                      ResultSink& sink, const RunnerOptions& options, SweepProgress* progress);

}  // namespace gesweep
