#pragma once
/// `gesweep query --group-by COLUMNS --aggregate LIST` (docs/query.md, "Aggregates"): statistics of
/// the complete runs that satisfy --where, per group of runs with equal values of the --group-by
/// columns (one group of all of them without --group-by).
///
/// Statistics, each of a numeric column (levels count as their codes 0, 1, ...; a false/true column's
/// mean is the fraction true); missing values (NaN: a failed run's results, no boundary) are skipped
/// as pandas and NumPy's nan-functions skip them:
///   count               runs in the group
///   count(c)            of them with a value of c
///   sum(c) min(c) max(c) mean(c)
///   std(c[, ddof])      standard deviation with ddof = 1 (sample, as pandas) by default, or 0
///   median(c)           exact: the middle value, or the mean of the two middle values
///   quantile(c, p)      exact, 0 <= p <= 1: NumPy's default ("linear", Hyndman & Fan's 7th)
/// A column may be a wildcard (run_columns.h, ColumnCatalog::Expand): mean(phugoid/*) is one mean
/// per matching numeric column.
///
/// Memory and passes. Counts, sums, extremes, means and standard deviations are streaming (one
/// accumulator per group and column; Welford's update for the variance, a compensated sum for sum
/// and mean). Medians and quantiles are exact order statistics, found within a memory budget
/// (AggregateRequest::memory_bytes): the first pass keeps the values it needs (16 bytes each) while
/// they fit; when they do not, further passes over the archive each either collect the values of
/// some groups, or narrow the rank's value range by a 1024-bucket histogram (8 KB per sought rank),
/// until every sought rank is found. Memory is then the budget, the group table (about 100 bytes
/// plus 56 bytes per statistics column per group; at most max_groups groups) and one block of rows,
/// whatever the run count; one bit per run records the runs the first pass selected, so every pass
/// sees the same runs even while a sweep writes the archive.

#include <cstdint>
#include <string>
#include <vector>

#include "engine/common/enum_names.h"
#include "engine/query/query.h"
#include "engine/query/run_columns.h"

namespace gesweep {

class ArchiveReader;

/// What one --aggregate item computes.
enum class AggregateKind { kCount, kSum, kMin, kMax, kMean, kStd, kMedian, kQuantile };
/// The statistics' names in --aggregate items and output columns (ToString, ParseEnum: enum_names.h).
GESWEEP_ENUM_NAMES(AggregateKind, {kCount, "count"}, {kSum, "sum"}, {kMin, "min"}, {kMax, "max"},
                   {kMean, "mean"}, {kStd, "std"}, {kMedian, "median"}, {kQuantile, "quantile"});

/// One statistic of the output.
struct AggregateSpec {
  AggregateKind kind = AggregateKind::kCount;
  int column = -1;    ///< catalogue column; -1 for `count` (runs in the group)
  double p = 0.5;     ///< kQuantile: the probability, 0 <= p <= 1
  int ddof = 1;       ///< kStd: delta degrees of freedom, 0 or 1
  std::string label;  ///< output column name, e.g. "quantile(sink_rate_mps, 0.95)"
  bool operator==(const AggregateSpec& other) const {
    return kind == other.kind && column == other.column && p == other.p && ddof == other.ddof;
  }
};

/// Parses --aggregate items: each text is a comma-separated list (commas inside parentheses belong
/// to the item). Wildcards expand to one item per matching non-text column; a repeated item counts
/// once. Throws InputError(source "command line", key `flag`) naming the item at fault.
std::vector<AggregateSpec> ParseAggregates(const std::vector<std::string>& texts,
                                           const ColumnCatalog& catalog,
                                           const std::string& flag = "aggregates");

/// What to compute.
struct AggregateRequest {
  std::string where;                    ///< condition (expression.h); empty: every complete run
  std::vector<std::string> group_by;    ///< column names or wildcards; empty: one group of all runs
  std::vector<std::string> aggregates;  ///< --aggregate texts; empty: "count"
  std::string sort;                     ///< an output column (group column or aggregate); empty: key order
  bool descending = false;
  std::int64_t limit = -1;                              ///< at most this many groups; < 0: all
  std::int64_t chunk_rows = 1 << 16;                    ///< runs read at a time
  std::int64_t memory_bytes = std::int64_t{256} << 20;  ///< budget for exact medians and quantiles
  std::int64_t max_groups = 1'000'000;                  ///< more groups than this are refused
};

/// Computes the aggregates and hands one row per group to `sink` (group columns, then one column per
/// statistic), in ascending order of the group columns (missing values last) unless sorted. Checks
/// every name and the condition before reading a row, and reads every pass before the first row
/// goes out, so a refusal leaves no output. Throws InputError (names, a bad item, too many groups)
/// and ArchiveError (I/O). The summary's `groups` is the number of groups, `passes` the passes over
/// the archive.
QuerySummary RunAggregateQuery(const ArchiveReader& archive, const ColumnCatalog& catalog,
                               const AggregateRequest& request, QueryRowSink& sink);

}  // namespace gesweep
