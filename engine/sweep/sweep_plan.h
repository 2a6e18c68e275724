#pragma once
/// A sweep ready to run: a validated study, its design, the columns its analyses fill, the shard of
/// the design this process runs, the write batch size, and the storage estimate (docs/sweep.md).

#include <cstdint>
#include <memory>
#include <string>

#include "engine/analyses/analysis.h"
#include "engine/sweep/design.h"
#include "engine/sweep/study.h"

namespace gesweep {

/// A contiguous block of the design: shard `index` of `count` (0 ≤ index < count). Shards are cut
/// at batch boundaries (ShardRange), so that the chunks of every shard coincide with the chunks of
/// the merged archive and `gesweep merge --copy` copies them as they are.
struct ShardSpec {
  int index = 0;
  int count = 1;
};

/// Parses "i/N" (0 ≤ i < N, 1 ≤ N ≤ 100000); throws InputError naming `flag`.
ShardSpec ParseShard(const std::string& text, const std::string& flag);

/// Runs per batch of a design of `design_runs` runs split in `shards` shards, when the study asks
/// for batches of `batch_runs`: at most design_runs / shards (so every shard has a batch), at least 1.
int ShardBatchRuns(std::int64_t design_runs, int batch_runs, int shards);

/// First run and run count of a shard, in whole batches of ShardBatchRuns(design_runs, batch_runs,
/// N): with B = ceil(M / b) batches of b runs, shard i of N takes batches [floor(i·B/N),
/// floor((i+1)·B/N)) -- every shard starts at a multiple of b, shards differ by at most one batch,
/// and only the last batch of the design can be partial.
void ShardRange(std::int64_t design_runs, int batch_runs, const ShardSpec& shard, std::int64_t* first,
                std::int64_t* count);

/// Storage of one run of a plan, in bytes before compression.
struct StorageEstimate {
  std::int64_t bytes_per_run = 0;         ///< every column, the bookkeeping columns included
  std::int64_t series_bytes_per_run = 0;  ///< the time series among them
  std::int64_t design_bytes = 0;          ///< bytes_per_run × the design's run count
};

/// A sweep plan. Built once per process; shared read-only by every worker thread.
class SweepPlan {
 public:
  /// Builds the design and the output schema of a validated study and checks the storage estimate
  /// against the study's max_archive_gb (InputError quoting the estimate when it is exceeded).
  SweepPlan(Study study, ShardSpec shard);
  SweepPlan(const SweepPlan&) = delete;
  SweepPlan& operator=(const SweepPlan&) = delete;

  const Study& study() const { return study_; }
  const Design& design() const { return *design_; }
  const OutputSchema& schema() const { return schema_; }
  const ShardSpec& shard() const { return shard_; }

  /// Runs in the whole design.
  std::int64_t design_runs() const { return design_runs_; }
  /// This shard's runs: design indices [first_run(), first_run() + run_count()).
  std::int64_t first_run() const { return first_run_; }
  std::int64_t run_count() const { return run_count_; }

  /// Runs per write batch and per HDF5 chunk (each chunk is written exactly once; docs/sweep.md).
  int chunk_runs() const { return chunk_runs_; }
  /// Overrides the batch size (a resumed archive keeps the one it was created with).
  void set_chunk_runs(int chunk_runs);
  /// Narrows the plan to batches [first_batch, first_batch + batch_count) of its shard (one node's
  /// part of an MPI sweep, engine/mpi): first_run and run_count change, the batch size does not.
  void RestrictToBatches(std::int64_t first_batch, std::int64_t batch_count);
  /// Number of batches of this shard.
  std::int64_t block_count() const { return (run_count_ + chunk_runs_ - 1) / chunk_runs_; }

  const StorageEstimate& storage() const { return storage_; }

  /// Parameters every run starts from: catalogue defaults, the aircraft's mass properties, the
  /// study's fixed values. NaN for a parameter no analysis reads and nobody set.
  const RunParameters& base_parameters() const { return base_; }
  /// Ids of the parameters some analysis of the study reads (the model parameters included when
  /// an analysis builds a model), catalogue order.
  const std::vector<ParameterId>& parameters_read() const { return parameters_read_; }
  /// Ids of the parameters that make the model (the model-cache key of each worker).
  const std::vector<ParameterId>& model_parameters() const { return model_parameters_; }

  /// The stable id of a run: a hash of its design parameters' names and values (the design index
  /// is stored beside it).
  std::uint64_t RunId(const double* design_row) const;

  /// Sum of the analyses' nominal costs, µs per run.
  double nominal_run_cost_us() const;

 private:
  /// Computes the storage estimate; throws InputError when it exceeds the study's max_archive_gb.
  void CheckStorage();
  /// Throws InputError when an analysis refuses the design's extreme runs (Analysis::CheckRun).
  void CheckRuns() const;
  Study study_;
  ShardSpec shard_;
  std::unique_ptr<Design> design_;
  OutputSchema schema_;
  std::int64_t design_runs_ = 0, first_run_ = 0, run_count_ = 0;
  int chunk_runs_ = 1;
  StorageEstimate storage_;
  RunParameters base_;
  std::vector<ParameterId> model_parameters_;
  std::vector<ParameterId> parameters_read_;
};

/// Formats a byte count for people: "812 B", "3.4 MB", "1.2 TB" (powers of 1000).
std::string FormatBytes(double bytes);

/// Bytes per run of the bookkeeping columns (index, id, status; runs/message is sparse -- only the
/// chunks holding a message are stored -- and is not counted).
std::int64_t BookkeepingBytesPerRun();

/// Most bytes of a run's stored message (runs/message, fixed-length UTF-8); a longer message is cut
/// at a character boundary and ends in "..." (docs/sweep.md, "Messages").
inline constexpr int kMessageLength = 1024;

}  // namespace gesweep
