#pragma once
/// The HDF5 archive of a sweep (layout: schemas/archive.md; crash safety: docs/sweep.md).
///
/// Crash safety by construction:
///  - every dataset is created up front with the shard's full length, chunked with one chunk per
///    write batch, so every chunk is written exactly once (no compressed chunk is ever rewritten,
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

  /// Writes one batch: design values, results, ids, messages; flush; statuses; flush.
  void Write(const ResultBlock& block) override;

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
  void CountStatuses();

  std::filesystem::path path_;
  const SweepPlan& plan_;
  hdf5::Handle file_;
  hdf5::Handle index_, id_, status_, message_;
  std::vector<hdf5::Handle> design_;
  std::vector<hdf5::Handle> results_;
  hdf5::Handle complex_memory_type_, message_type_;
  std::vector<std::int32_t> int_buffer_;
  std::vector<std::int8_t> byte_buffer_;
  std::vector<char> message_buffer_;
  std::int64_t runs_ok_ = 0, runs_failed_ = 0, runs_pending_ = 0;
  bool finished_ = false;
  int lock_fd_ = -1;  ///< flock on ARCHIVE.lock: one writer per archive at a time
  bool lock_held_ = false;

  friend class ArchiveReader;  // copies the complete batches of a crashed archive (resume)
};

/// Series chunk rows for a series of `samples` values when batches have `chunk_runs` runs: the
/// largest divisor of chunk_runs whose chunk stays within 1 MiB (at least 1).
int SeriesChunkRows(int chunk_runs, int samples);

}  // namespace gesweep
