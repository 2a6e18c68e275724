#pragma once
/// MPI as a transport of the one sweep pipeline (docs/cluster.md, "MPI"):
/// `mpirun -n R gesweep run STUDY -o ARCHIVE --mpi`.
///
/// Every rank builds the same SweepPlan from the same study file and runs the same RunSweep
/// (engine/sweep/runner.h) as a single process does; only where batch numbers come from and where
/// finished batches go differ:
///  - batches out: world rank 0 hands out batch numbers on request (guided: at most a fair share of
///    what is left per request); a rank gets its own node's batches first and steals another
///    node's only when its node has none left;
///  - compressed result blocks back: the worker that computed a batch filters its chunks (shuffle,
///    deflate, Fletcher-32, as HDF5 would), and the batch goes, as those chunks, to the writer of
///    the node whose part of the design holds it;
///  - one writer per node: the ranks of a node (MPI_Comm_split_type SHARED, or `ranks_per_node`
///    consecutive ranks) elect their lowest rank, which writes the node's shard archive
///    (ARCHIVE-stem.node<k>-of-<K>.h5: an ordinary shard archive of a contiguous run of batches,
///    with the crash safety and --resume of docs/sweep.md);
///  - at the end rank 0 merges the node shards into ARCHIVE, virtually by default (nothing copied,
///    the node shards must stay beside it) or by raw chunk copy.
/// Every run's result depends only on its design row, so ARCHIVE equals a single-process run's
/// dataset by dataset (only provenance attributes differ), whatever the rank, node and thread counts.
/// Nothing here prints: progress and the outcome come back as data for the CLI.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "engine/archive/archive_merge.h"
#include "engine/archive/archive_writer.h"
#include "engine/common/errors.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep {

/// Options of an MPI sweep; every rank passes the same (the command line is the same on every rank).
struct MpiRunOptions {
  std::filesystem::path output;                     ///< the merged archive; the node shards go beside it
  ArchiveOpenMode mode = ArchiveOpenMode::kCreate;  ///< --force / --resume, as `gesweep run`
  int threads = 0;                                  ///< compute threads per rank; 0: the rank's cores
  int lanes = DefaultLanes();                       ///< RunnerOptions::lanes of every rank
  std::string command_line;                         ///< provenance (the archives' command_line attribute)
  /// Set (by a SIGINT/SIGTERM handler; mpirun forwards both to every rank) to stop: no more batches
  /// are handed out, every batch handed out is finished and written, the node shards stay resumable.
  const std::atomic<bool>* cancel = nullptr;
  /// Batches a rank holds (computing or queued) beyond two per thread; 0: one per thread more.
  int prefetch_batches = 0;
  /// Ranks per "node" (one writer each): 0 takes GESWEEP_RANKS_PER_NODE when set, else the ranks
  /// that share memory (MPI_Comm_split_type SHARED). Lets 4 ranks on one machine act as 2 nodes.
  int ranks_per_node = 0;
  MergeKind merge = MergeKind::kVirtual;  ///< how the node shards become ARCHIVE
  /// The line of a person's bad input that the ranks agree on and report (MpiSweepReport::error):
  /// the front end's wording of the error (its flags for the request's fields, its hints for a
  /// RequestError's remedy); empty: what().
  std::function<std::string(const InputError&)> describe_input_error;
};

struct MpiSweepReport;
/// Called on every rank once the nodes are set up and their shards opened, before the first batch
/// (the CLI prints its header and starts its progress display on rank 0).
using MpiStartCallback = std::function<void(const MpiSweepReport&)>;

/// What an MPI sweep did. Every field marked "all ranks" is the same on every rank.
struct MpiSweepReport {
  int rank = 0, ranks = 1;
  int nodes = 1;                            ///< all ranks: node shards written (one writer each)
  int node = 0;                             ///< this rank's node
  bool writer = false;                      ///< this rank wrote its node's shard
  std::vector<std::string> node_archives;   ///< all ranks: the node shards, by node
  std::int64_t runs_computed = 0;           ///< by this rank
  std::vector<std::int64_t> runs_per_rank;  ///< rank 0: runs computed by each rank
  std::int64_t runs_complete_at_start = 0;  ///< all ranks: already complete (resume)
  std::int64_t runs_to_do = 0;              ///< all ranks: pending at the start
  /// All ranks: runs by status over the node shards after the sweep.
  std::int64_t runs_ok = 0, runs_failed = 0, runs_pending = 0;
  bool cancelled = false;  ///< all ranks: stopped by `cancel` with runs still pending
  bool merged = false;     ///< all ranks: ARCHIVE was made (every run complete)
  MergeReport merge;       ///< rank 0: the merge
  double seconds = 0;      ///< rank 0: from the first batch handed out to the merged archive
  /// All ranks: 0, or 1 for an I/O error, 2 for a person's mistake (a study that differs between
  /// ranks, an existing archive without --force/--resume...), with `error` the one line to print
  /// (rank 0 holds the text).
  int error_code = 0;
  std::string error;
};

/// Runs `plan` across every rank of MPI_COMM_WORLD. Collective: every rank calls it with an equal
/// plan and options. Initialises MPI (MPI_THREAD_FUNNELED: only each rank's calling thread calls
/// MPI) unless it already is; the caller prints the outcome, then calls FinalizeMpi (an
/// MpiFinalizer does). `progress`
/// (rank 0) is kept up to date while it runs: runs to do, and runs done over all ranks (as the
/// ranks last reported them). Throws only for what no rank can recover from (an MPI error, a bug);
/// the caller then prints and calls AbortMpi.
MpiSweepReport RunStudyMpi(const SweepPlan& plan, const MpiRunOptions& options,
                           SweepProgress* progress = nullptr, const MpiStartCallback& on_started = nullptr);

/// Ends every rank of the job (MPI_Abort) after the caller printed why: for an exception out of
/// RunStudyMpi, which may leave other ranks waiting.
[[noreturn]] void AbortMpi(int code);

/// Finalises MPI if it is initialised and not finalised yet.
void FinalizeMpi();

/// Calls FinalizeMpi when it goes out of scope (hold it around RunStudyMpi and the printing of
/// its outcome).
struct MpiFinalizer {
  MpiFinalizer() = default;
  MpiFinalizer(const MpiFinalizer&) = delete;
  MpiFinalizer& operator=(const MpiFinalizer&) = delete;
  ~MpiFinalizer() { FinalizeMpi(); }
};

/// The shard of node `node` of `nodes` for the merged archive `output`: out.h5 -> out.node0-of-2.h5.
std::filesystem::path NodeArchivePath(const std::filesystem::path& output, int node, int nodes);

/// Bytes of one write batch of `rows` runs of `plan` before compression (what a rank would send
/// unfiltered; docs/scaling.md compares it with the filtered chunks it sends).
std::int64_t BatchMessageBytes(const SweepPlan& plan, int rows);

}  // namespace gesweep
