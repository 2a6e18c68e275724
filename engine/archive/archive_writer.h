#pragma once
/// The HDF5 archive of a sweep (layout: schemas/archive.md; crash safety: docs/sweep.md).
///
/// The workers filter their own chunks (Encode: shuffle, deflate, Fletcher-32 in the worker thread
/// that computed the batch, byte for byte what HDF5 would write; archive_layout.h) and the one
/// writer thread only stores them (H5Dwrite_chunk) and flushes.
///
/// Crash safety by construction:
///  - every dataset is created up front with the shard's full length, chunked with one chunk per
///    write batch (runs/message: a few small chunks per batch, written only where a run has a
///    message), so every chunk is written exactly once (no compressed chunk is ever rewritten,
///    so no file space is freed and reused);
///  - the file is written in HDF5's SWMR mode, whose ordered metadata flushes keep the file on disk
///    consistent at every instant; a batch is written results first, flushed, then its statuses
///    (the per-run "complete" flags), flushed again;
///  - after a crash the file opens in SWMR-read mode (h5py: swmr=True) and shows exactly the
///    batches whose statuses reached the disk; --resume copies those into a fresh file (written
///    under a temporary name, then renamed over the old one) and runs the rest.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "engine/archive/archive_layout.h"
#include "engine/archive/hdf5_util.h"
#include "engine/sweep/runner.h"

namespace gesweep {

/// How `gesweep run` may treat an existing archive.
enum class ArchiveOpenMode {
  kCreate,  ///< refuse when the archive exists
  kForce,   ///< replace an existing archive (atomically, once the new one is set up)
  kResume,  ///< continue an existing archive of the same study and shard (create it when absent)
};

/// Who made the archive (root attributes besides the study and engine).
struct RunProvenance {
  std::string command_line;
  int threads = 0;
  /// Under MPI: this archive is the shard of node `node_index` of `node_count` (its writer's node);
  /// -1 otherwise.
  int node_index = -1;
  int node_count = 0;
  int ranks = 1;  ///< MPI ranks of the job (1 without MPI)
};

/// What opening for a sweep found.
struct ArchiveOpenReport {
  enum class Kind { kCreated, kResumedClean, kResumedAfterCrash } kind = Kind::kCreated;
  std::int64_t runs_complete = 0;            ///< runs already complete in the archive
  std::vector<std::int64_t> pending_blocks;  ///< batches to run, ascending
  std::string note;                          ///< why a resume copied the complete batches into a fresh file
};

/// Writes one sweep's archive. Not thread-safe: one writer thread calls Write.
class ArchiveWriter final : public ResultSink {
 public:
  /// Opens `path` for `plan` in `mode`. Checks everything that can be checked before creating a
  /// file: the directory exists, an existing archive is not replaced without --force or --resume,
  /// a resumed archive comes from the same study (fingerprint), engine, shard and design. May
  /// change plan.chunk_runs() to the resumed archive's. Throws InputError for a person's mistake,
  /// ArchiveError for an I/O failure.
  static std::unique_ptr<ArchiveWriter> Open(const std::filesystem::path& path, SweepPlan& plan,
                                             const RunProvenance& provenance, ArchiveOpenMode mode,
                                             ArchiveOpenReport* report);

  ~ArchiveWriter() override;
  ArchiveWriter(const ArchiveWriter&) = delete;
  ArchiveWriter& operator=(const ArchiveWriter&) = delete;

  /// Filters a computed batch's chunks (any thread, concurrently).
  void Encode(ResultBlock& block) override { layout_.Encode(block); }
  /// Stores one batch's chunks: design values, results, ids, messages; flush; statuses; flush.
  /// A batch not encoded yet is encoded here first.
  void Write(const ResultBlock& block) override;

  /// The batches given to Write are numbered in a plan whose shard starts `runs` runs before this
  /// archive's (a node's shard of an MPI sweep): their rows are shifted by that much.
  void set_block_row_offset(std::int64_t runs) { block_row_offset_ = runs; }
  const archive::ArchiveLayout& layout() const { return layout_; }

  /// Ends the sweep: leaves SWMR mode and records the end time and the run counts by status.
  void Finish();

  /// Runs by status after Finish: ok, failed, pending.
  std::int64_t runs_ok() const { return runs_ok_; }
  std::int64_t runs_failed() const { return runs_failed_; }
  std::int64_t runs_pending() const { return runs_pending_; }

 private:
  ArchiveWriter(std::filesystem::path path, const SweepPlan& plan);
  void CreateSkeleton(hid_t file, const RunProvenance& provenance);
  void OpenDatasets();
  void CloseDatasets();
  void CountStatuses();
  void WriteChunks(const ResultBlock& block);

  std::filesystem::path path_;
  const SweepPlan& plan_;
  archive::ArchiveLayout layout_;
  hdf5::Handle file_;
  std::vector<hdf5::Handle> datasets_;  ///< layout_.datasets() order
  std::int64_t block_row_offset_ = 0;
  ResultBlock unencoded_;  ///< scratch for a batch given to Write without Encode
  std::int64_t runs_ok_ = 0, runs_failed_ = 0, runs_pending_ = 0;
  bool finished_ = false;
  int lock_fd_ = -1;  ///< flock on ARCHIVE.lock: one writer per archive at a time
  bool lock_held_ = false;

  friend class ArchiveReader;  // copies the complete batches of a crashed archive (resume)
};

using archive::SeriesChunkRows;

}  // namespace gesweep
