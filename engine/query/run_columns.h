#pragma once
/// The per-run columns of an archive as `gesweep query` and `gesweep boundary --archive` see them
/// (docs/report.md, "Column names"): every one-value-per-run dataset under runs/, design/ and
/// results/ (schemas/archive.md), with its short name, units, levels and missing-value fill, and
/// chunked reading of their values.
///
/// Column names. A column is named by its full dataset path ("results/modes/stability_margin_per_s",
/// a leading "/" allowed) or by any tail of that path after a "/" ("modes/stability_margin_per_s",
/// "stability_margin_per_s") that names no other column. Where a tail is shared, the bare name of a
/// design parameter or a runs/ column wins: "height_m" is design/height_m even when
/// results/boundary/height_m exists (write "boundary/height_m" for that one). Every column's display
/// name is its shortest tail that resolves back to it.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace gesweep {

class ArchiveReader;

/// What a column holds.
enum class ColumnKind {
  kNumber,    ///< float or integer data, read as doubles (an integer column's fill value reads as NaN)
  kText,      ///< fixed-length strings (runs/message)
  kUnsigned,  ///< 64-bit unsigned integers (runs/id), kept exact for display; compared as doubles
};

/// One per-run scalar column.
struct RunColumn {
  std::string path;         ///< dataset path without a leading "/", e.g. "design/height_m"
  std::string name;         ///< display name: the shortest tail of `path` that resolves to it
  std::string units;        ///< the `units` attribute ("" when absent)
  std::string description;  ///< the `description` attribute
  ColumnKind kind = ColumnKind::kNumber;
  bool integer = false;              ///< stored as an integer type
  std::vector<std::string> levels;   ///< names of the codes 0, 1, ... (a choice, a flag, a status)
  std::optional<std::int64_t> fill;  ///< integer value that means "no value" (attribute `fill`)
  /// True for design/ and runs/ columns, whose bare names win over results' (see the file comment).
  bool primary = false;
  /// For an output column of `gesweep query --aggregate`: the statistic ("count", "mean", "quantile",
  /// ...), and `path` is the path of the column it summarises ("" for count). "" for a run column.
  std::string statistic;
  /// Whether `levels` are exactly {"false", "true"}: the column can stand alone as a condition.
  bool boolean() const { return levels.size() == 2 && levels[0] == "false" && levels[1] == "true"; }
};

/// A dataset of the archive that is not a per-run scalar column, with why (for --describe and errors).
struct OtherDataset {
  std::string path;
  std::vector<std::int64_t> shape;
  std::string units;
  std::string description;
  std::string why;  ///< e.g. "5 complex values per run", "a time series of 2001 samples per run"
};

/// Values of one column for a block of consecutive runs.
struct ColumnValues {
  std::vector<double> numbers;                 ///< kNumber, kUnsigned (as doubles)
  std::vector<std::string> texts;              ///< kText
  std::vector<std::uint64_t> unsigned_values;  ///< kUnsigned, exact
};

/// The per-run columns of one archive.
class ColumnCatalog {
 public:
  /// Lists the columns of `archive` (every dataset under runs/, design/, results/ whose first
  /// dimension is the run count). Throws ArchiveError when the archive cannot be read.
  static ColumnCatalog Of(const ArchiveReader& archive);
  /// A catalogue of the given columns (display names, status/index and design columns derived as
  /// Of does); `design_order` lists the design parameters' names. For tests and the fuzz target,
  /// which need a catalogue without an archive. status_column()/index_column() are -1 when
  /// runs/status or runs/index is not among `columns`.
  static ColumnCatalog FromColumns(std::vector<RunColumn> columns,
                                   const std::vector<std::string>& design_order,
                                   std::vector<OtherDataset> others = {});

  const std::vector<RunColumn>& columns() const { return columns_; }
  const std::vector<OtherDataset>& others() const { return others_; }
  const RunColumn& column(int index) const { return columns_[static_cast<std::size_t>(index)]; }

  /// The column `name` names (rules in the file comment), or nullopt.
  std::optional<int> Find(const std::string& name) const;
  /// Resolves `name` or explains why it does not resolve: "unknown column 'x' (did you mean y?)",
  /// "ambiguous: ... matches a, b; write one of them", "is not a per-run scalar column (...)".
  /// Returns the index, or nullopt with `*problem` set (and `*remedy` to "describe_columns" for an
  /// unknown name: the front end says how to list the columns; errors.h, InputError::remedy).
  std::optional<int> Resolve(const std::string& name, std::string* problem,
                             std::string* remedy = nullptr) const;
  /// Like Resolve, throwing InputError(source, key, name, problem) when it does not resolve.
  int Require(const std::string& name, const std::string& source, const std::string& key) const;

  /// The columns `name` stands for. A name without wildcard characters gives the one column Resolve
  /// gives. A pattern with '*', '?' or '[...]' (shell wildcards; '*' also matches '/') gives every
  /// column of which some tail, the full path included, matches it (a pattern that starts with "/"
  /// matches full paths only): "phugoid/*" gives every phugoid column, "*" every column, "*_m"
  /// every column in metres. The columns come in natural order (NaturalOrder). Throws
  /// InputError(source, key, name, ...) when `name` resolves to nothing (remedy "describe_columns").
  std::vector<int> Expand(const std::string& name, const std::string& source, const std::string& key) const;
  /// Every column: runs/index, the design columns in design order, runs/status, the results in
  /// archive order, then the other runs/ columns (id, message).
  std::vector<int> NaturalOrder() const;

  /// Index of the column at `path` (full dataset path), or nullopt.
  std::optional<int> FindPath(const std::string& path) const;

  /// Indices of the design/ columns, in the design's parameter order.
  const std::vector<int>& design_columns() const { return design_columns_; }
  /// Index of runs/status, runs/index (always present in an archive).
  int status_column() const { return status_; }
  int index_column() const { return index_; }

 private:
  std::vector<std::string> Candidates(const std::string& name) const;
  std::vector<RunColumn> columns_;
  std::vector<OtherDataset> others_;
  std::vector<int> design_columns_;
  int status_ = -1;
  int index_ = -1;
};

/// Reads rows [first, first + count) of column `column` into `out` (numbers for kNumber and
/// kUnsigned, texts for kText, unsigned_values for kUnsigned); an integer column's fill value
/// becomes NaN. Memory: the block only. Throws ArchiveError on an I/O failure.
void ReadColumn(const ArchiveReader& archive, const RunColumn& column, std::int64_t first, std::int64_t count,
                ColumnValues& out);

/// Reads the statuses of rows [first, first + count) and sets keep[i] to 1 for a complete run
/// (nonzero status), 0 otherwise; returns how many are complete. Read the statuses before the
/// values: a nonzero status vouches for values written before it (snapshot safety).
std::size_t MarkCompleteRuns(const ArchiveReader& archive, std::int64_t first, std::int64_t count,
                             std::vector<char>& keep);

/// Renders a number for people and CSV: shortest round-trip form up to `significant` digits;
/// "nan", "inf", "-inf".
std::string FormatValue(double value, int significant = 10);

/// The text a cell of `column` shows for a number: the level name of a level column, the exact
/// integer of an integer column, else FormatValue. NaN shows as "nan".
std::string FormatCell(const RunColumn& column, double number);

}  // namespace gesweep
