#pragma once
/// `gesweep query`: selected columns of the runs of an archive that satisfy a condition, optionally
/// sorted and limited (docs/report.md, "gesweep query"), and `--describe`: what an archive holds.
///
/// Memory is bounded by the block of runs read at a time (QueryRequest::chunk_rows), whatever the
/// run count, except when sorting: --sort with --limit n keeps the n best rows (a bounded heap);
/// --sort without --limit keeps every matching row (its output cells) until the end.
///
/// Only complete runs (status ok or failed) are rows of a result. An archive that a sweep is writing,
/// or whose writer was killed, is read as a snapshot (ArchiveReader): every block's statuses are read
/// before its values, and a nonzero status is written only after the run's values reached the disk
/// (docs/sweep.md, "Crash safety"), so a row is never half-written.

#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "engine/query/run_columns.h"

namespace gesweep {

class ArchiveReader;
class RowFilter;

/// What to select.
struct QueryRequest {
  std::string where;  ///< condition (expression.h); empty: every complete run
  std::vector<std::string>
      columns;       ///< column names or wildcards (ColumnCatalog::Expand); empty: DefaultColumns
  std::string sort;  ///< column to sort by; empty: run order
  bool descending = false;
  std::int64_t limit = -1;            ///< at most this many rows; < 0: all
  std::int64_t chunk_rows = 1 << 16;  ///< runs read at a time (memory bound)
};

/// One cell of a result row.
struct QueryCell {
  double number = std::numeric_limits<double>::quiet_NaN();  ///< kNumber and kUnsigned columns
  std::string text;  ///< kText: the text; kUnsigned: the exact decimal value
};

/// Counts of a finished query.
struct QuerySummary {
  std::int64_t runs = 0;      ///< rows of the archive
  std::int64_t complete = 0;  ///< of them with status ok or failed
  std::int64_t matched = 0;   ///< complete runs satisfying the condition
  std::int64_t shown = 0;     ///< rows handed to the sink (≤ limit)
  bool snapshot = false;      ///< read while a sweep writes it, or after its writer died
  std::int64_t groups = -1;   ///< aggregates (aggregate.h): the groups of matching runs; -1: rows
  int passes = 1;             ///< passes over the archive (aggregates' exact order statistics)
};

/// The runs of rows [first, first + count) a query keeps: keep[i] = 1 for a complete run
/// (MarkCompleteRuns) that satisfies `filter` when there is one (null: every complete run); they are
/// counted into summary.complete and summary.matched. The filter's columns are read into `values`
/// (ReadColumn) only when some run of the block is complete. Returns whether any run is kept.
bool SelectRuns(const ArchiveReader& archive, const ColumnCatalog& catalog, const RowFilter* filter,
                std::int64_t first, std::int64_t count, std::vector<ColumnValues>& values,
                std::vector<char>& keep, QuerySummary& summary);

/// Receives a query's result, row by row (formats: query_output.h).
class QueryRowSink {
 public:
  virtual ~QueryRowSink() = default;
  /// Called once, before any row, with the output columns.
  virtual void Begin(const std::vector<const RunColumn*>& columns) = 0;
  /// One row: a cell per column, in order.
  virtual void Row(const std::vector<QueryCell>& cells) = 0;
  /// Called once at the end.
  virtual void End(const QuerySummary& summary) = 0;
};

/// The columns shown when none are asked for: runs/index, the design parameters, runs/status.
std::vector<int> DefaultColumns(const ColumnCatalog& catalog);

/// Runs a query. Checks every name and the condition before reading any row: InputError (source
/// "command line", key the request field: columns, where, sort). ArchiveError on I/O failure.
QuerySummary RunQuery(const ArchiveReader& archive, const ColumnCatalog& catalog, const QueryRequest& request,
                      QueryRowSink& sink);

/// Runs by status.
struct StatusCounts {
  std::int64_t pending = 0, ok = 0, failed = 0;
};
/// Counts runs/status in blocks of `chunk_rows`.
StatusCounts CountStatuses(const ArchiveReader& archive, std::int64_t chunk_rows = 1 << 16);

/// One attribute rendered as text: a string as is; numbers with up to 10 digits; a list as
/// "[a, b, c]".
struct AttributeText {
  std::string name;
  std::string value;
};
/// Every attribute of the object at `path` ("/" for the root), in name order.
std::vector<AttributeText> ReadAttributes(const ArchiveReader& archive, const std::string& path);

}  // namespace gesweep
