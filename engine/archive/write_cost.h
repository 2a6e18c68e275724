#pragma once
/// The writer's share of a sweep's time, for the dry run's estimate (docs/sweep.md, "Dry run"): a
/// cheap analysis (modes: microseconds per run) is bound by the one writer thread (shuffle, deflate
/// and checksums of every column, two flushes per batch), not by the workers.

#include <filesystem>

#include "engine/sweep/sweep_plan.h"

namespace gesweep {

/// What MeasureWriteCost measured.
struct WriteCostEstimate {
  double seconds_per_run = 0;  ///< the writer thread's time per run (0 when not measured)
  double seconds_per_run_low = 0;   ///< 95 % interval of it (equal to it with fewer than 3 batches)
  double seconds_per_run_high = 0;
  std::int64_t runs_written = 0;
  bool measured = false;       ///< false: skipped (`compute_budget_s` too small for one real batch)
};

/// Computes one real batch of `plan` (its first batch's runs, so the data compress as the sweep's
/// will), when that takes less than `compute_budget_s` on one thread at `seconds_per_run_compute`,
/// then writes it as several batches of a scratch archive in a fresh temporary directory
/// (std::filesystem::temp_directory_path) with the real writer, timing the writes until
/// `write_budget_s` is spent (at least one), and deletes the directory. Nothing is written near the
/// sweep's own archive. Throws ArchiveError when the scratch archive cannot be written.
WriteCostEstimate MeasureWriteCost(SweepPlan& plan, double seconds_per_run_compute, double compute_budget_s,
                                   double write_budget_s);

}  // namespace gesweep
