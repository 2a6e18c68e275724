#pragma once
/// Reading an archive (schemas/archive.md): attributes, the dataset list, rows of any dataset in
/// pieces (memory bounded by the piece, not the run count). Opens a file that a sweep is writing,
/// or whose writer died, in HDF5's SWMR-read mode: a consistent snapshot of the complete batches.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/archive/archive_identity.h"
#include "engine/archive/hdf5_util.h"

namespace gesweep {

class SweepPlan;
class ArchiveWriter;

/// A read-only view of one archive.
class ArchiveReader {
 public:
  /// Opens an archive. Throws InputError (source = the path) when it is missing, not a regular file
  /// (a FIFO or a device is refused before anything reads it), not HDF5, not a gesweep archive, of
  /// a newer format version, cannot be opened at all (e.g. a writer is setting it up right now:
  /// "archive in use"), or breaks the layout its readers rely on: a root attribute they use missing
  /// (run_count, design_runs, first_run, chunk_runs), runs/ or design/ missing, a per-run dataset
  /// (runs/, design/, results/, the series) without one row per run or of a type its readers cannot
  /// convert; and when it is a virtual archive whose sources fail archive::CheckVirtualSources
  /// (missing, replaced, moved, foreign, incomplete, itself, a cycle), before any value is read. Every
  /// reader (query, boundary, report, sensitivity, dispersion, merge, resume, Python's open_archive)
  /// goes through it. What it could not check (an archive merged before identities) is in notes(),
  /// each also sent to the note handler (archive::SetArchiveNoteHandler). A file shorter than HDF5 recorded
  /// (a write that failed half-way: disk full, a file-size limit) is refused saying so, unless
  /// `repair_truncated` (the writer resuming it): then a copy of it ("<path>.repair", deleted when the
  /// reader closes) is extended with zeros to the recorded size and opened (repaired() is true), whose
  /// complete batches the resume copies into a fresh archive; the file itself is never written.
  /// Before libhdf5 decodes the file, the whole check runs in a child process with a deadline
  /// (archive::GuardArchiveDecode): a file on which libhdf5 crashes or hangs is one InputError.
  static ArchiveReader Open(const std::filesystem::path& path, bool repair_truncated = false);

  ArchiveReader(ArchiveReader&&) = default;
  ArchiveReader& operator=(ArchiveReader&&) = default;

  /// True when opened as a snapshot (SWMR read): a sweep is writing it, or its writer stopped
  /// without closing it (killed). Runs with status 0 may then still be coming.
  bool snapshot() const { return snapshot_; }
  /// Whether it is a virtual archive (its per-run datasets map other files).
  bool is_virtual() const { return is_virtual_; }
  /// True when what is open is a repaired copy of a truncated file (Open with `repair_truncated`).
  bool repaired() const { return repair_copy_ != nullptr; }
  /// A virtual archive's sources, found where HDF5 reads them and checked (empty otherwise).
  const std::vector<archive::FoundSource>& sources() const { return sources_; }
  /// Every other file a read of this archive opens: a virtual archive's sources, and theirs.
  const std::vector<std::filesystem::path>& files_read() const { return files_read_; }
  /// What opening it could not check, one line each (e.g. an archive merged before identities).
  const std::vector<std::string>& notes() const { return notes_; }
  const std::filesystem::path& path() const { return path_; }
  hid_t file() const { return file_.get(); }

  /// Root attributes. StringAttribute gives "" and StringListAttribute {} when absent;
  /// IntegerAttribute throws ArchiveError when absent.
  std::string StringAttribute(const std::string& name) const;
  std::int64_t IntegerAttribute(const std::string& name) const;
  std::vector<std::string> StringListAttribute(const std::string& name) const;

  /// Attributes of any group or dataset (`object`, e.g. "design" or "design/height_m"); nullopt
  /// (or empty) when the object or the attribute is absent, ArchiveError when it is of another kind.
  std::optional<std::string> StringAttributeOf(const std::string& object, const std::string& name) const;
  std::optional<std::int64_t> IntegerAttributeOf(const std::string& object, const std::string& name) const;
  std::optional<double> DoubleAttributeOf(const std::string& object, const std::string& name) const;
  std::vector<std::string> StringListAttributeOf(const std::string& object, const std::string& name) const;
  /// A numeric (float or integer) attribute as doubles; empty when absent.
  std::vector<double> DoubleListAttributeOf(const std::string& object, const std::string& name) const;

  /// Whether a group or dataset exists (every intermediate group included).
  bool Exists(const std::string& path) const;

  /// What a dataset holds: its dimensions and the class of its elements.
  struct DatasetInfo {
    enum class Kind { kFloat, kInteger, kCompound, kString, kOther } kind = Kind::kOther;
    std::vector<std::int64_t> dims;
  };
  DatasetInfo Describe(const std::string& path) const;

  /// Rows [first, first + count) of an integer per-run dataset (e.g. runs/index) as int64.
  std::vector<std::int64_t> ReadIntegers(const std::string& path, std::int64_t first,
                                         std::int64_t count) const;

  /// Runs in this archive (the length of every per-run dataset).
  std::int64_t run_count() const { return run_count_; }

  /// Every dataset's path, depth-first in name order ("design/height_m", "results/modes/...").
  std::vector<std::string> Datasets() const;

  /// Reads rows [first, first + count) of a per-run dataset (all columns of a 2-D one) converted
  /// to `memory_type` into `out`.
  void ReadRows(const std::string& path, std::int64_t first, std::int64_t count, hid_t memory_type,
                void* out) const;
  /// Rows of a numeric per-run dataset as doubles (integers converted).
  std::vector<double> ReadDoubles(const std::string& path, std::int64_t first, std::int64_t count) const;
  /// Statuses of runs [first, first + count) (0 pending, 1 ok, 2 failed).
  std::vector<std::int8_t> ReadStatus(std::int64_t first, std::int64_t count) const;

  /// Messages of runs [first, first + count) (empty for most ok runs).
  std::vector<std::string> ReadMessages(std::int64_t first, std::int64_t count) const;

  /// Batches (of `chunk_runs` runs) whose every run has a nonzero status, ascending.
  std::vector<std::int64_t> CompleteBlocks(int chunk_runs) const;

  /// Throws InputError unless this archive was made by the same study (fingerprint), engine
  /// version and commit, for the same shard of the same design as `plan`.
  void CheckSameSweep(const SweepPlan& plan, const std::string& shown) const;
  /// Throws InputError unless the first run of each of `blocks` has the index and id `plan` gives.
  void VerifyRunIds(const SweepPlan& plan, const std::vector<std::int64_t>& blocks,
                    const std::string& shown) const;

  /// Copies batches `blocks` (ascending; of `chunk_runs` runs) of every dataset of `writer`'s plan
  /// into it, each target chunk written once.
  void CopyBlocks(ArchiveWriter& writer, const std::vector<std::int64_t>& blocks, int chunk_runs) const;

  void Close();

 private:
  ArchiveReader(std::filesystem::path path, hdf5::Handle file, bool snapshot);
  void CheckVirtualSources();
  std::filesystem::path path_;
  hdf5::Handle file_;
  bool snapshot_ = false;
  bool is_virtual_ = false;
  std::int64_t run_count_ = 0;
  std::vector<archive::FoundSource> sources_;
  std::vector<std::filesystem::path> files_read_;
  std::vector<std::string> notes_;
  std::shared_ptr<const std::filesystem::path> repair_copy_;  // deleted when the last owner goes
};

}  // namespace gesweep
