#pragma once
/// The MPI runner (docs/cluster.md, "MPI"): `mpirun -n R gesweep run STUDY -o ARCHIVE --mpi`.
///
/// Every rank builds the same SweepPlan from the same study file. Rank 0 opens the archive (the one
/// writer: the same ArchiveWriter as a single-process run, so the same chunking, compression and
/// crash safety) and hands out the plan's pending write batches on request: dynamic scheduling,
/// a few batches per request while many remain, one at a time near the end (guided). Every rank,
/// rank 0 included, computes its batches with its own oneTBB threads (ExecuteRun, as RunSweep
/// does) and sends each finished batch to rank 0, which writes it at its design position. Every
/// run's result depends only on its design row, so the archive equals a single-process run's bit
/// for bit apart from the provenance attributes, whatever the rank and thread counts.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <string>

#include "engine/archive/archive_writer.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep {

/// Options of an MPI sweep; every rank passes the same (the command line is the same on every rank).
struct MpiRunOptions {
  std::filesystem::path output;                     ///< the archive, written by rank 0 only
  ArchiveOpenMode mode = ArchiveOpenMode::kCreate;  ///< --force / --resume, as `gesweep run`
  int threads = 0;                                  ///< compute threads per rank; 0: the rank's cores
  std::string command_line;                         ///< provenance (the archive's command_line attribute)
  /// Set (by a SIGINT/SIGTERM handler; mpirun forwards both to every rank) to stop: rank 0 hands
  /// out no more batches, every batch handed out is finished and written, the archive stays
  /// resumable (`--resume`).
  const std::atomic<bool>* cancel = nullptr;
  const std::atomic<int>* signal = nullptr;  ///< the signal that set `cancel` (exit code 128 + signal)
  bool quiet = false;                        ///< no progress lines (the summary of failures stays)
  /// Batches a rank holds (computing or queued) beyond one per thread; 0: one per thread more.
  /// More hides the request latency to rank 0, fewer balances the tail better.
  int prefetch_batches = 0;
};

/// What an MPI sweep did, as seen by the calling rank.
struct MpiSweepReport {
  int ranks = 1;
  std::int64_t runs_computed = 0;  ///< by this rank
  /// Rank 0 only (the archive's counts after Finish): runs by status.
  std::int64_t runs_ok = 0, runs_failed = 0, runs_pending = 0;
  bool cancelled = false;  ///< stopped by `cancel` before every batch was handed out
};

/// Runs `plan` across every rank of MPI_COMM_WORLD and returns `gesweep run`'s exit code: 0 every
/// run ok, 3 some runs failed (data: status and message in the archive), 1 an I/O error (message on
/// stderr), 2 a rank's plan differs from rank 0's (study file not the same on every node; message
/// on stderr), 128+signal when cancelled (archive closed, resumable). Initialises MPI
/// (MPI_THREAD_FUNNELED) unless it already is, and then finalises it before returning, also when it
/// throws. Collective: every rank of MPI_COMM_WORLD must call it with an equal plan and options.
/// Only rank 0 prints (progress on stderr unless quiet, the summary line) and touches the archive.
/// Throws InputError on rank 0 for a person's mistake found when opening the archive (it exists
/// without --force/--resume, a resumed archive of another study...); the other ranks then return 2
/// silently. `plan` may get the resumed archive's chunk_runs (ArchiveWriter::Open).
int RunStudyMpi(SweepPlan& plan, const MpiRunOptions& options, MpiSweepReport* report = nullptr);

/// Bytes of one write batch of `rows` runs of `plan` as sent from a rank to rank 0 (before the
/// messages, which add 2 bytes + their length per run): docs/scaling.md's rank-0 bandwidth.
std::int64_t BatchMessageBytes(const SweepPlan& plan, int rows);

}  // namespace gesweep
