#pragma once
/// The parallel runner (docs/sweep.md, "Runner"). oneTBB schedules the runs of a plan in batches
/// (one batch = one HDF5 chunk of every column), each worker thread with its own workspace. The
/// worker that computed a batch also encodes it (ResultSink::Encode: the archive filters its chunks,
/// shuffle + deflate + Fletcher-32, in the worker); finished batches go through a bounded queue to
/// ONE writer thread, which hands them to ResultSink::Write (the HDF5 archive stores the ready
/// chunks; the runner knows nothing of HDF5). Where batch numbers come from is a BatchSource: a list
/// in one process, the MPI transport's dispatcher across ranks (engine/mpi) -- the same pipeline
/// either way. A fixed pool of batch buffers bounds memory whatever the run count. Every run's
/// result depends only on its design row, so the archive is the same bit for bit whatever the
/// thread count, sharding or rank count.

#include <atomic>
#include <cstdint>
#include <exception>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "engine/common/enum_names.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep {

/// Status of a run, as stored in /runs/status.
enum class RunStatus : std::int8_t {
  kPending = 0,  ///< not (completely) written yet: a resumed sweep runs it
  kOk = 1,
  kFailed = 2,  ///< a numerical failure or an exception; the message says why
};
/// The status names, in code order: the levels of /runs/status and the manifest's `run_status`
/// (the one place the Python readers take the codes from).
GESWEEP_ENUM_NAMES(RunStatus, {kPending, "pending"}, {kOk, "ok"}, {kFailed, "failed"});
static_assert(
    [] {
      std::int8_t code = 0;
      for (const auto& entry : EnumNames<RunStatus>::kTable) {
        if (static_cast<std::int8_t>(entry.value) != code++) return false;
      }
      return true;
    }(),
    "RunStatus's names are in code order: level i of /runs/status is code i");

/// The names of RunStatus in code order (level i is code i): the `levels` of /runs/status.
inline std::vector<std::string> RunStatusLevels() {
  std::vector<std::string> levels;
  for (const auto& entry : EnumNames<RunStatus>::kTable) levels.emplace_back(entry.name);
  return levels;
}

/// One stored chunk of a batch, filtered by the worker that computed it (opaque to the runner: the
/// sink's Encode makes them, its Write stores them).
struct StoredChunk {
  int dataset = 0;                ///< index of the dataset in the sink's layout
  std::int64_t row = 0;           ///< first row of the chunk, counted from the batch's first row
  std::uint32_t filter_mask = 0;  ///< HDF5's filter mask (bit i set: filter i skipped)
  std::vector<unsigned char> bytes;
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
  /// The batch as stored, once encoded: chunks[0 .. chunk_count) (the buffers are kept between
  /// batches, so a reused block allocates nothing).
  std::vector<StoredChunk> chunks;
  int chunk_count = 0;
  int runs_failed = 0;  ///< failed runs of the batch (counted when it is computed)

  /// Sizes the buffers for `plan` (capacity chunk_runs rows).
  void Allocate(const SweepPlan& plan);
  /// Prepares it for batch `block_index` of `plan`: row count, design indices, NaN-filled results.
  void Reset(const SweepPlan& plan, std::int64_t block_index);
};

/// Receives finished batches. Encode is called by the worker thread that computed a batch, right
/// after computing it, concurrently for different batches (it must be thread-safe); Write from the
/// one writer thread only, in no particular batch order. Either may throw (e.g. disk full), which
/// stops the sweep.
class ResultSink {
 public:
  virtual ~ResultSink() = default;
  /// Prepares a computed batch for Write (e.g. filters its chunks). Default: nothing.
  virtual void Encode(ResultBlock& block) { (void)block; }
  virtual void Write(const ResultBlock& block) = 0;
};

/// Where a sweep's batch numbers come from (the pipeline's input stage; called by one thread at a
/// time). A list in one process; under MPI, the batches the dispatcher hands this rank.
class BatchSource {
 public:
  virtual ~BatchSource() = default;
  /// The next batch of the plan to compute, or -1 when there is none left (it may block until one
  /// is known).
  virtual std::int64_t Next() = 0;
};

/// A BatchSource over a fixed list (ascending batch numbers of the plan's shard).
class ListBatchSource final : public BatchSource {
 public:
  explicit ListBatchSource(const std::vector<std::int64_t>& blocks) : blocks_(blocks) {}
  std::int64_t Next() override { return next_ < blocks_.size() ? blocks_[next_++] : -1; }
  std::size_t remaining() const { return blocks_.size() - next_; }

 private:
  const std::vector<std::int64_t>& blocks_;
  std::size_t next_ = 0;
};

/// The per-thread state of the workers: the parameter vector, the design row, the per-run slots of a
/// group of runs (ExecuteRuns), and the models built, kept while consecutive runs share them.
class RunWorkspace {
 public:
  explicit RunWorkspace(const SweepPlan& plan);
  /// The model for the workspace's current parameters: rebuilt only when a model parameter changed.
  const LongitudinalModel& Model(const SweepPlan& plan);
  RunParameters parameters;
  std::vector<double> design_row;

  /// Starts a group of runs: the models the previous group used are kept, older ones dropped.
  void StartGroup();
  /// The model for `run_parameters` (built once for each distinct set of model parameters among the
  /// runs of this group and the last): valid until the next group starts but one.
  const LongitudinalModel& GroupModel(const SweepPlan& plan, const RunParameters& run_parameters);
  /// The parameters and design row of each run of a group (at least as many as its runs).
  std::vector<RunParameters> group_parameters;
  std::vector<std::vector<double>> group_rows;

 private:
  struct CachedModel {
    std::vector<double> key;  // the values of the plan's model parameters
    std::unique_ptr<const LongitudinalModel> model;
    std::int64_t group = 0;  // the last group that used it
  };
  std::vector<CachedModel> models_;
  std::int64_t group_ = 0;
};

/// Cuts a run's message to the stored length (kMessageLength bytes) without splitting a UTF-8
/// sequence, ending it in "..." when it was cut.
void TruncateMessage(std::string& message);

/// Runs design run `design_index` (row `row` of `block`): fills its design values, id, status,
/// message and results. Never throws for a numerical problem or an exception of an analysis: the
/// run is marked failed with the message. `cancel` (may be null) reaches inside the analyses (time
/// responses check it between integration steps): a run it stops keeps status kPending.
/// `noise_point` (empty in a sweep): the run's noise as a point of the standard-normal space
/// (RunContext::noise_point), as a subset simulation flies it (engine/risk).
/// `design_values` (empty in a sweep): the values of the design's columns, taken instead of row
/// `design_index` (a subset simulation's random parameters, drawn from its point; engine/risk).
void ExecuteRun(const SweepPlan& plan, std::int64_t design_index, RunWorkspace& workspace, ResultBlock& block,
                int row, const std::atomic<bool>* cancel = nullptr, std::span<const double> noise_point = {},
                std::span<const double> design_values = {});

/// Runs rows [first_row, first_row + count) of `block` (design runs block.design_index[...]) as a
/// group, each run exactly as ExecuteRun runs it alone: every analysis gets the group's runs at once
/// (Analysis::RunLanes), `lanes` at a time where it takes lanes; the runs' design values, ids,
/// statuses, messages and results are bit for bit ExecuteRun's, whatever `lanes` (one of
/// kLaneWidths) and whichever runs share the group. A run a cancellation stops keeps status
/// kPending ("cancelled"); a run whose model cannot be built fails, the others go on.
/// `noise_points` and `design_values` (empty in a sweep; else one per run of the group): ExecuteRun's
/// of each run (a subset simulation's landings, engine/risk).
void ExecuteRuns(const SweepPlan& plan, RunWorkspace& workspace, ResultBlock& block, int first_row, int count,
                 int lanes, const std::atomic<bool>* cancel = nullptr,
                 std::span<const std::span<const double>> noise_points = {},
                 std::span<const std::span<const double>> design_values = {});

/// Whether a sweep of `plan` with `lanes` runs its runs in groups (ExecuteRuns): lanes > 1 and an
/// analysis of the study takes lanes (Analysis::takes_lanes). Otherwise one at a time (ExecuteRun).
bool RunsInLanes(const SweepPlan& plan, int lanes);

/// The lane width of a sweep when none is asked for: the width of the widest vector of doubles this
/// CPU has with AVX2 or AVX-512 (4 or 8: the lanes then compute in whole vectors, lanes_isa.h), else
/// one at a time (SSE2's pairs were measured slower than one at a time). The archive is the same bit
/// for bit whatever the width, so this is a matter of speed only (docs/performance.md, "The open loop
/// in lanes": 0.75x of the CPU per run at 8 and AVX-512, at load 1).
int DefaultLanes();

/// Counters the runner updates while it works (read them from any thread).
struct SweepProgress {
  std::atomic<std::int64_t> runs_done{0};     ///< computed in this process
  std::atomic<std::int64_t> runs_failed{0};   ///< of them, failed
  std::atomic<std::int64_t> runs_written{0};  ///< handed to the sink
  std::atomic<std::int64_t> runs_to_do{0};    ///< pending runs at the start (all ranks under MPI)
  std::atomic<std::int64_t> runs_skipped{0};  ///< already complete (resume)
};

/// Options of RunSweep.
struct RunnerOptions {
  int threads = 0;  ///< worker threads; 0: all cores
  /// Set (e.g. by a signal handler) to stop: no new batch is taken, the runs in flight stop between
  /// two integration steps, and a batch with a run left unfinished is not written (its runs stay
  /// pending for --resume). Batches finished before are written, so the archive stays resumable.
  const std::atomic<bool>* cancel = nullptr;
  int queue_batches = 4;  ///< capacity of the queue to the writer
  /// Runs computed at once in the lanes of SIMD vectors by the analyses that take them (open_loop, landing),
  /// one of kLaneWidths; 1: one at a time. The archive is the same bit for bit whatever it is.
  int lanes = DefaultLanes();
};

/// What a sweep did.
struct SweepOutcome {
  std::int64_t runs_ok = 0;
  std::int64_t runs_failed = 0;
  std::int64_t runs_skipped = 0;
  bool cancelled = false;  ///< stopped by `cancel` before every batch was run and written
};

/// Runs the batches `source` gives and writes them through `sink` (the one pipeline: threads,
/// MPI ranks and the benchmarks all come through here). Rethrows the first exception of the sink
/// or of a worker after stopping cleanly. `cancelled` in the outcome: `options.cancel` stopped it
/// before `source` ran dry.
SweepOutcome RunSweep(const SweepPlan& plan, BatchSource& source, ResultSink& sink,
                      const RunnerOptions& options, SweepProgress* progress);
/// The same over a list of batches (ascending batch numbers of the plan's shard).
SweepOutcome RunSweep(const SweepPlan& plan, const std::vector<std::int64_t>& pending_blocks,
                      ResultSink& sink, const RunnerOptions& options, SweepProgress* progress);

}  // namespace gesweep
