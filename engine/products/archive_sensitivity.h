#pragma once
/// Global sensitivity of one archived output of a sweep (docs/sensitivity.md, "gesweep sensitivity"):
/// finds the output column, reads the design's layout from the archive's `design` group attributes
/// (schemas/archive.md), the output and the run statuses, and runs the Sobol' (Saltelli design) or
/// Morris (trajectory design) estimators of engine/estimators on them.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/common/enum_names.h"
#include "engine/estimators/morris_effects.h"
#include "engine/estimators/sensitivity_common.h"
#include "engine/estimators/sobol_indices.h"

namespace gesweep {

class ArchiveReader;

/// Which estimator family.
enum class SensitivityMethod {
  kSobol,   ///< Sobol' indices from a `sobol` (Saltelli) design
  kMorris,  ///< Morris elementary effects from a `morris` design
};
/// "sobol" / "morris" (ToString, ParseEnum: enum_names.h).
GESWEEP_ENUM_NAMES(SensitivityMethod, {kSobol, "sobol"}, {kMorris, "morris"});
/// Parses "sobol" / "morris"; nullopt otherwise.
std::optional<SensitivityMethod> ParseSensitivityMethod(std::string_view text);

/// One scalar result column of an archive.
struct ArchiveOutput {
  std::string path;         ///< dataset path, e.g. "results/boundary/height_m"
  std::string name;         ///< the path below results/, e.g. "boundary/height_m" (the analysis group's name)
  std::string units;        ///< the dataset's `units` attribute ("m", "1", ...)
  std::string description;  ///< the dataset's `description` attribute
};

/// The scalar result columns of an archive: 1-D numeric datasets under results/, one value per run,
/// in path order. Complex and multi-column datasets (eigenvalues, gains, series) are not scalars.
std::vector<ArchiveOutput> ScalarOutputs(const ArchiveReader& archive);

/// Finds the output `name`: a full dataset path ("results/boundary/height_m"), a path below results/
/// ("boundary/height_m") or a dataset's last name ("height_m", "ishigami"). Throws InputError
/// (source the archive, key --output) when nothing matches (listing the scalar outputs, with the
/// nearest name) or when a last name is ambiguous (listing the candidates' full paths).
ArchiveOutput ResolveOutput(const ArchiveReader& archive, const std::string& name);

/// What to analyse and how.
struct ArchiveSensitivityOptions {
  /// The estimator family; nullopt: the one the design was made for (sobol → kSobol, morris → kMorris).
  std::optional<SensitivityMethod> method;
  FailedRunPolicy failed_runs = FailedRunPolicy::kDropBlocks;
  BootstrapOptions bootstrap;
};

/// The result of a global sensitivity analysis of one archived output.
struct ArchiveSensitivity {
  SensitivityMethod method = SensitivityMethod::kSobol;  ///< the estimator family used
  std::string archive_path;                              ///< the archive, as given
  std::string study_name;                                ///< its root attribute study_name
  ArchiveOutput output;                                  ///< the analysed column
  std::string design_kind;                               ///< the archive's design kind ("sobol", "morris")
  std::vector<std::string> parameters;  ///< swept parameters, in the study's (design column) order
  std::vector<std::string> parameter_units;
  std::vector<ParameterRange> ranges;  ///< their sampled ranges (design dataset `bounds`, `distribution`)
  std::int64_t run_count = 0;          ///< rows of the design

  /// Rows that cannot enter the estimators: status failed, or status ok with a non-finite output
  /// (e.g. a boundary run that found no boundary stores NaN). Counted here from the archive.
  std::int64_t runs_failed = 0;         ///< status 2
  std::int64_t runs_without_value = 0;  ///< status 1 with a non-finite output (or an integer fill)
  std::int64_t first_missing_row = -1;  ///< first row of either kind; −1 when none
  std::string first_missing_message;    ///< its runs/message
  /// Saltelli blocks (Morris trajectories) that hold at least one such row.
  std::int64_t blocks_with_missing = 0;

  FailedRunPolicy failed_runs = FailedRunPolicy::kDropBlocks;
  SensitivityStatus status = SensitivityStatus::kOk;
  std::string message;  ///< why status is not kOk
  /// With kStoppedOnFailedRuns: what FailedRunPolicy::kDropBlocks would do instead ("leave out the 3
  /// of 40 blocks that hold them"); a front end offers it in its own terms.
  std::string failed_runs_remedy;

  SobolIndices sobol;       ///< when method is kSobol
  MorrisIndices morris;     ///< when method is kMorris
  int morris_levels = 0;    ///< p of the Morris design
  double morris_delta = 0;  ///< its unit step Δ

  /// N: base samples (Sobol') or trajectories (Morris).
  std::int64_t n() const;
  /// Blocks (Saltelli base samples, or Morris trajectories) left out because they held a missing row.
  std::int64_t blocks_dropped() const;
  /// Blocks that entered the estimates.
  std::int64_t blocks_used() const;
};

/// Analyses output `output_name` of an archive (ResolveOutput's rules). Throws InputError (source
/// the archive path) when: the output does not exist or is ambiguous; the archive holds only a shard
/// of its design (merge the shards first) or runs are still pending (finish the sweep); the design is
/// not of a kind the method needs (sobol for kSobol, morris for kMorris) or its recorded layout does
/// not match its rows; an option is invalid. Failed runs are not exceptions: with
/// FailedRunPolicy::kError they give status kStoppedOnFailedRuns and a message naming the count and
/// the first one; with kDropBlocks the blocks that hold them are dropped and counted.
ArchiveSensitivity AnalyzeArchiveOutput(const ArchiveReader& archive, const std::string& output_name,
                                        const ArchiveSensitivityOptions& options);

}  // namespace gesweep
