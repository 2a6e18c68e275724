#pragma once
/// The records and the HDF5 file of a subset simulation (`gesweep risk`; docs/dispersion.md, "Landing
/// risk by subset simulation"; layout in schemas/archive.md, "Subset-simulation archives"). The
/// driver and its journal are in engine/risk; the file is here because the archive owns HDF5.
///
/// The archive holds the study (its text), the spec's fingerprint, every evaluation (its tag: the
/// recipe that flies it again; its status, limit-state value and result columns), the estimates as
/// JSON (result_json: what `gesweep risk` and `gesweep dispersion --format json` print) and the
/// design points' noise and time series.

#include <cstdint>
#include <filesystem>
#include <string>
#include <tuple>
#include <vector>

namespace gesweep::risk {

inline constexpr const char* kRiskArchiveKind = "subset_simulation";
/// 2 adds the evaluations' `repetition` tag (independent repetitions of a study's simulations); a
/// version-1 archive is read with every repetition 0.
inline constexpr int kRiskArchiveVersion = 2;

/// The tag of one evaluation.
struct EvaluationKey {
  std::int32_t cell = 0, limit = 0, repetition = 0, level = 0, chain = 0, step = 0;
  auto tie() const { return std::tie(cell, limit, repetition, level, chain, step); }
  bool operator<(const EvaluationKey& other) const { return tie() < other.tie(); }
  bool operator==(const EvaluationKey& other) const { return tie() == other.tie(); }
};

/// One landing of a subset simulation.
struct Evaluation {
  EvaluationKey key;
  std::int8_t status = 0;      ///< RunStatus (engine/sweep/runner.h): kOk or kFailed
  double g = 0;                ///< the limit state (failure g <= 0); NaN: a failed run or no value
  std::string message;         ///< the run's message (why it failed; a note)
  std::vector<double> values;  ///< the RiskColumns of the run
};

/// One design point's landing series: the time axis and the series columns by name.
struct PointSeries {
  std::string name;  ///< "steady" (u = 0: no turbulence), "mean_failure", "most_likely"
  std::vector<double> time_s;
  std::vector<std::string> columns;  ///< series names, e.g. "w_g_mps"
  std::vector<std::string> units;
  std::vector<std::vector<double>> values;  ///< one per column, time_s.size() each
};

/// What the archive keeps of one (cell, limit) estimate beyond result_json.
struct DesignPoint {
  std::int64_t cell = 0;
  int limit = 0;
  double sample_interval_s = 0;    ///< the held noise's interval Δt_n
  std::vector<double> mean_noise;  ///< the mean failing point (empty when none failed)
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

/// Writes `archive` to `path` + ".partial" and renames it onto `path`. Throws ArchiveError. The
/// file's layout is product::subset_archive of engine/archive/product_fields.h (generated from
/// schemas/products.json), which this writer and the reader below name every field through.
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
