#pragma once
/// The archive of a subset simulation (docs/dispersion.md, "Landing risk by subset simulation"; layout
/// in schemas/archive.md, "Subset-simulation archives") and its journal.
///
/// The journal (ARCHIVE.journal) is written while the levels run: after each batch of landings its
/// evaluations are appended as checksummed records and flushed to the disk, so a killed run loses at
/// most the batch in flight. `gesweep risk --resume` reads it back (a torn last record is dropped; a
/// damaged one before the end, or a journal of another study or spec, is refused) and RunRisk takes
/// those landings instead of flying them: the estimate is the one an uninterrupted run gives, bit for
/// bit. At the end the archive is written whole to ARCHIVE.partial and renamed into place, and only
/// then is the journal deleted.
///
/// The archive holds the study (its text), the spec's fingerprint, every evaluation (its tag: the
/// recipe that flies it again; its status, limit-state value and result columns), the estimates as
/// JSON (result_json: what `gesweep risk` and `gesweep dispersion --format json` print) and the
/// design points' noise and time series.

#include <cstdint>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "engine/archive/subset_archive.h"
#include "engine/risk/landing_risk.h"

namespace gesweep::risk {

/// The journal beside an archive: ARCHIVE.journal.
std::filesystem::path JournalPath(const std::filesystem::path& archive);

/// Appends evaluations to a journal (creating it with its header, or continuing a resumed one).
class JournalWriter {
 public:
  /// Creates `path` (which must not exist) or, with `resume_length` > 0, opens it, cuts it at that
  /// length (the end of its last whole record) and appends there. Throws ArchiveError on I/O failure.
  JournalWriter(const std::filesystem::path& path, std::uint64_t fingerprint, std::uint32_t value_count,
                std::uint64_t resume_length);
  ~JournalWriter();
  JournalWriter(const JournalWriter&) = delete;
  JournalWriter& operator=(const JournalWriter&) = delete;
  /// Writes the records and flushes them to the disk (fdatasync).
  void Append(std::span<const Evaluation> evaluations);

 private:
  int fd_ = -1;
  std::filesystem::path path_;
};

/// Evaluations as the journal's records (each with its checksum), for a process that sends them.
std::vector<unsigned char> EncodeEvaluations(std::span<const Evaluation> evaluations);

/// The evaluations of EncodeEvaluations's bytes, each with `value_count` values; false (and `out`
/// partly filled) when the bytes are not whole records of that width.
bool DecodeEvaluations(std::span<const unsigned char> bytes, std::uint32_t value_count,
                       std::vector<Evaluation>& out);

/// A journal read back.
struct JournalContents {
  std::map<EvaluationKey, Evaluation> evaluations;
  std::uint64_t valid_length = 0;  ///< bytes up to the end of the last whole record
  std::int64_t records = 0;
  bool torn_tail = false;  ///< a partial last record was dropped
};

/// Reads a journal; throws InputError (source the journal) when it is not one, is of another
/// fingerprint or value count, or has a damaged record before its last.
JournalContents ReadJournal(const std::filesystem::path& path, std::uint64_t fingerprint,
                            std::uint32_t value_count);

}  // namespace gesweep::risk
