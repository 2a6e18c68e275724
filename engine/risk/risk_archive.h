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

#include "engine/risk/landing_risk.h"

namespace gesweep::risk {

inline constexpr const char* kRiskArchiveKind = "subset_simulation";
inline constexpr int kRiskArchiveVersion = 1;

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

/// A journal read back.
struct JournalContents {
  std::map<EvaluationKey, Evaluation> evaluations;
  std::uint64_t valid_length = 0;  ///< bytes up to the end of the last whole record
  std::int64_t records = 0;
  bool torn_tail = false;          ///< a partial last record was dropped
};

/// Reads a journal; throws InputError (source the journal) when it is not one, is of another
/// fingerprint or value count, or has a damaged record before its last.
JournalContents ReadJournal(const std::filesystem::path& path, std::uint64_t fingerprint,
                            std::uint32_t value_count);

/// One design point's landing series: the time axis and the series columns by name.
struct PointSeries {
  std::string name;  ///< "steady" (u = 0: no turbulence), "mean_failure", "most_likely"
  std::vector<double> time_s;
  std::vector<std::string> columns;        ///< series names, e.g. "w_g_mps"
  std::vector<std::string> units;
  std::vector<std::vector<double>> values;  ///< one per column, time_s.size() each
};

/// What the archive keeps of one (cell, limit) estimate beyond result_json.
struct DesignPoint {
  std::int64_t cell = 0;
  int limit = 0;
  double sample_interval_s = 0;          ///< the held noise's interval Δt_n
  std::vector<double> mean_noise;        ///< the mean failing point (empty when none failed)
  std::vector<double> most_likely_noise;
  std::vector<PointSeries> series;
};

/// Everything an archive holds.
struct RiskArchive {
  std::string study_path;
  std::string study_text;
  std::uint64_t fingerprint = 0;
  std::string command_line;
  std::string result_json;
  std::vector<std::string> value_columns;  ///< the archive paths of Evaluation::values
  std::vector<Evaluation> evaluations;
  std::vector<DesignPoint> design_points;
};

/// Writes `archive` to `path` + ".partial" and renames it onto `path`. Throws ArchiveError.
void WriteRiskArchive(const std::filesystem::path& path, const RiskArchive& archive);

/// Whether `path` is a subset-simulation archive (an HDF5 file whose root says so). False for any
/// other file, readable or not; never throws.
bool IsRiskArchive(const std::filesystem::path& path);

/// Reads an archive back (guarded: the decode runs first in a child with a deadline, as every
/// archive a person names). Checks what it reads: the kind and version, equal lengths of the
/// evaluation columns, tags and statuses in range, unique tags, the value matrix's width; throws
/// InputError (source the archive) with one line otherwise. `with_design_points` false skips them.
RiskArchive ReadRiskArchive(const std::filesystem::path& path, bool with_design_points = true);

}  // namespace gesweep::risk
