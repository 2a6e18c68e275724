#pragma once
/// The archive's share of a sweep's time, for the dry run's estimate (docs/sweep.md, "Dry run"): for a
/// cheap analysis (modes: microseconds per run) encoding the batches (shuffle, deflate and checksums
/// of every column, done by the workers) costs as much as the runs, and the one writer thread stores
/// the encoded chunks (two flushes per batch). It also times what the archive costs a sweep whatever
/// its size: creating it (file, skeleton of every dataset at the shard's length, provenance, reopened
/// in SWMR mode and renamed into place) and closing it (statuses counted, end attributes, flush).

#include <filesystem>

#include "engine/sweep/sweep_plan.h"

namespace gesweep {

/// What MeasureWriteCost measured.
struct WriteCostEstimate {
  double seconds_per_run = 0;      ///< the writer thread's time per run, storing (0 when not measured)
  double seconds_per_run_low = 0;  ///< 95 % interval of it (equal to it with fewer than 3 batches)
  double seconds_per_run_high = 0;
  double encode_seconds_per_run = 0;  ///< a worker's time per run encoding its batch (0 when not measured)
  std::int64_t runs_written = 0;
  bool measured = false;  ///< false: skipped (`compute_budget_s` too small for one real batch)
  /// Once per sweep: ArchiveWriter::Open of a new archive for the plan (create, skeleton, reopen in
  /// SWMR mode, rename), s; and ArchiveWriter::Finish (statuses counted, end attributes, flush,
  /// close), s. Measured whenever the scratch archive could be written, batch or not.
  double open_seconds = 0;
  double close_seconds = 0;
  bool archive_measured = false;
};

/// Creates a scratch archive for `plan` in a fresh temporary directory
/// (std::filesystem::temp_directory_path) with the real writer (timed: open_seconds). When one real
/// batch of `plan` (its first batch's runs, so the data compress as the sweep's will) takes less than
/// `compute_budget_s` on one thread at `seconds_per_run_compute`, computes it, encodes it (timed: the
/// workers' share) and writes it as several batches of the scratch archive, timing the writes until
/// `write_budget_s` is spent (at least one). Then finishes the archive (timed: close_seconds) and
/// deletes the directory. Nothing is written near the sweep's own archive. Throws ArchiveError when
/// the scratch archive cannot be written.
WriteCostEstimate MeasureWriteCost(SweepPlan& plan, double seconds_per_run_compute, double compute_budget_s,
                                   double write_budget_s);

}  // namespace gesweep
