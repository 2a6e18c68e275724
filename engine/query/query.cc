#include "engine/query/query.h"

#include <algorithm>
#include <cmath>
#include <queue>

#include "engine/archive/archive_reader.h"
#include "engine/archive/column_reader.h"
#include "engine/common/errors.h"
#include "engine/query/expression.h"

namespace gesweep {
namespace {

// A matching row kept for sorting: its key and its cells.
struct SortedRow {
  double key = 0;
  std::string text_key;
  std::int64_t order = 0;  // position in the archive: ties keep run order
  std::vector<QueryCell> cells;
};

// Strict "a comes before b": ascending or descending key, NaN (no value) last, then run order.
struct SortOrder {
  bool descending = false;
  bool text = false;
  bool operator()(const SortedRow& a, const SortedRow& b) const {
    if (text) {
      const int c = a.text_key.compare(b.text_key);
      if (c != 0) return descending ? c > 0 : c < 0;
      return a.order < b.order;
    }
    const bool a_nan = std::isnan(a.key), b_nan = std::isnan(b.key);
    if (a_nan != b_nan) return b_nan;
    if (!a_nan && a.key != b.key) return descending ? a.key > b.key : a.key < b.key;
    return a.order < b.order;
  }
};

QueryCell CellOf(const RunColumn& column, const ColumnValues& values, std::size_t row) {
  QueryCell cell;
  switch (column.kind) {
    case ColumnKind::kText:
      cell.text = values.texts[row];
      break;
    case ColumnKind::kUnsigned:
      cell.number = values.numbers[row];
      cell.text = std::to_string(values.unsigned_values[row]);
      break;
    case ColumnKind::kNumber:
      cell.number = values.numbers[row];
      break;
  }
  return cell;
}

std::string FormatAttributeNumber(double value, bool integer) {
  if (integer && std::abs(value) < 9e15) return std::to_string(static_cast<long long>(value));
  return FormatValue(value);
}

std::string AttributeTextOf(const AttributeValue& attribute) {
  std::vector<std::string> items;
  switch (attribute.kind) {
    case AttributeValue::Kind::kText:
      if (attribute.scalar && attribute.texts.size() == 1) return attribute.texts[0];
      items = attribute.texts;
      break;
    case AttributeValue::Kind::kInteger:
    case AttributeValue::Kind::kFloat:
      for (double v : attribute.numbers)
        items.push_back(FormatAttributeNumber(v, attribute.kind == AttributeValue::Kind::kInteger));
      if (attribute.scalar && items.size() == 1) return items[0];
      break;
    case AttributeValue::Kind::kOther:
      return "(unsupported attribute type)";
  }
  std::string text = "[";
  for (std::size_t i = 0; i < items.size(); ++i) text += (i ? ", " : "") + items[i];
  return text + "]";
}

}  // namespace

std::vector<int> DefaultColumns(const ColumnCatalog& catalog) {
  std::vector<int> columns{catalog.index_column()};
  for (int c : catalog.design_columns()) columns.push_back(c);
  columns.push_back(catalog.status_column());
  return columns;
}

bool SelectRuns(const ArchiveReader& archive, const ColumnCatalog& catalog, const RowFilter* filter,
                std::int64_t first, std::int64_t count, std::vector<ColumnValues>& values,
                std::vector<char>& keep, QuerySummary& summary) {
  const std::size_t complete = MarkCompleteRuns(archive, first, count, keep);
  summary.complete += static_cast<std::int64_t>(complete);
  if (complete == 0) return false;
  if (filter != nullptr) {
    for (int c : filter->columns())
      ReadColumn(archive, catalog.column(c), first, count, values[static_cast<std::size_t>(c)]);
    std::vector<char> condition;
    filter->Evaluate(values, count, condition);
    for (std::size_t i = 0; i < keep.size(); ++i) keep[i] = keep[i] && condition[i];
  }
  const auto matched = static_cast<std::int64_t>(std::count(keep.begin(), keep.end(), 1));
  summary.matched += matched;
  return matched > 0;
}

namespace {

// A request checked against the catalog: its output columns, filter and sort column.
struct CheckedRequest {
  std::vector<int> output;
  std::optional<RowFilter> filter;
  std::optional<int> sort_column;
};

// Checks everything a person typed, before the first row is read: the columns (the default ones,
// with the filter's and the sort column, when none is named), the filter and the sort column.
CheckedRequest CheckRequest(const ColumnCatalog& catalog, const QueryRequest& request) {
  CheckedRequest checked;
  std::vector<int>& output = checked.output;
  for (const std::string& name : request.columns) {
    for (int c : catalog.Expand(name, "command line", "columns")) {
      if (std::find(output.begin(), output.end(), c) == output.end()) output.push_back(c);
    }
  }
  if (!request.where.empty()) checked.filter.emplace(RowFilter::Parse(request.where, catalog, "where"));
  if (!request.sort.empty()) checked.sort_column = catalog.Require(request.sort, "command line", "sort");
  if (output.empty()) {
    output = DefaultColumns(catalog);
    auto add = [&](int c) {
      if (std::find(output.begin(), output.end(), c) == output.end()) output.push_back(c);
    };
    if (checked.filter) {
      for (int c : checked.filter->columns()) add(c);
    }
    if (checked.sort_column) add(*checked.sort_column);
  }
  return checked;
}

// The matching rows of a sorted query. Top-k: a heap whose top is the worst row kept. Without a
// limit: every matching row.
class SortedRows {
 public:
  SortedRows(const SortOrder& order, std::int64_t limit) : order_(order), limit_(limit), best_(order) {}

  // Keeps `row` if it is among the best `limit` so far (every row without a limit).
  void Add(SortedRow row) {
    if (limit_ < 0) {
      all_.push_back(std::move(row));
    } else if (limit_ > 0) {
      if (static_cast<std::int64_t>(best_.size()) < limit_) {
        best_.push(std::move(row));
      } else if (order_(row, best_.top())) {
        best_.pop();
        best_.push(std::move(row));
      }
    }
  }

  // Sends the rows kept to `sink` in order, counting them in summary.shown.
  void Emit(QueryRowSink& sink, QuerySummary& summary) {
    if (limit_ >= 0) {
      while (!best_.empty()) {
        all_.push_back(best_.top());
        best_.pop();
      }
    }
    std::sort(all_.begin(), all_.end(), order_);
    for (const auto& row : all_) {
      sink.Row(row.cells);
      ++summary.shown;
    }
  }

 private:
  SortOrder order_;
  std::int64_t limit_;
  std::priority_queue<SortedRow, std::vector<SortedRow>, SortOrder> best_;
  std::vector<SortedRow> all_;
};

}  // namespace

QuerySummary RunQuery(const ArchiveReader& archive, const ColumnCatalog& catalog, const QueryRequest& request,
                      QueryRowSink& sink) {
  // Everything a person typed is checked before the first row is read.
  CheckedRequest checked = CheckRequest(catalog, request);
  const std::vector<int>& output = checked.output;
  const std::optional<RowFilter>& filter = checked.filter;
  const std::optional<int>& sort_column = checked.sort_column;
  GESWEEP_DEMAND(request.chunk_rows > 0);

  std::vector<const RunColumn*> shown_columns;
  shown_columns.reserve(output.size());
  for (int c : output) shown_columns.push_back(&catalog.column(c));
  sink.Begin(shown_columns);

  QuerySummary summary;
  summary.runs = archive.run_count();
  summary.snapshot = archive.snapshot();
  const bool sorting = sort_column.has_value();
  const SortOrder order{request.descending,
                        sorting && catalog.column(*sort_column).kind == ColumnKind::kText};
  SortedRows sorted(order, request.limit);
  const bool bounded = request.limit >= 0;

  std::vector<ColumnValues> values(catalog.columns().size());
  std::vector<char> keep;
  std::vector<int> read_for_output = output;
  if (sort_column) read_for_output.push_back(*sort_column);
  std::sort(read_for_output.begin(), read_for_output.end());
  read_for_output.erase(std::unique(read_for_output.begin(), read_for_output.end()), read_for_output.end());

  for (std::int64_t first = 0; first < summary.runs; first += request.chunk_rows) {
    const std::int64_t count = std::min(request.chunk_rows, summary.runs - first);
    const auto n = static_cast<std::size_t>(count);
    if (!SelectRuns(archive, catalog, filter ? &*filter : nullptr, first, count, values, keep, summary))
      continue;
    // Output values are read only for blocks that contribute a row.
    const bool want_rows = sorting || !bounded || summary.shown < request.limit;
    if (!want_rows) continue;
    for (int c : read_for_output) {
      if (filter && std::binary_search(filter->columns().begin(), filter->columns().end(), c)) continue;
      ReadColumn(archive, catalog.column(c), first, count, values[static_cast<std::size_t>(c)]);
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (!keep[i]) continue;
      std::vector<QueryCell> cells;
      cells.reserve(output.size());
      for (int c : output) cells.push_back(CellOf(catalog.column(c), values[static_cast<std::size_t>(c)], i));
      if (!sorting) {
        if (bounded && summary.shown >= request.limit) break;
        sink.Row(cells);
        ++summary.shown;
        continue;
      }
      SortedRow row;
      const QueryCell key =
          CellOf(catalog.column(*sort_column), values[static_cast<std::size_t>(*sort_column)], i);
      row.key = key.number;
      row.text_key = key.text;
      row.order = first + static_cast<std::int64_t>(i);
      row.cells = std::move(cells);
      sorted.Add(std::move(row));
    }
  }
  if (sorting) sorted.Emit(sink, summary);
  sink.End(summary);
  return summary;
}

StatusCounts CountStatuses(const ArchiveReader& archive, std::int64_t chunk_rows) {
  StatusCounts counts;
  for (std::int64_t first = 0; first < archive.run_count(); first += chunk_rows) {
    const std::int64_t count = std::min(chunk_rows, archive.run_count() - first);
    for (std::int8_t s : archive.ReadStatus(first, count)) {
      counts.pending += s == 0;
      counts.ok += s == 1;
      counts.failed += s == 2;
    }
  }
  return counts;
}

std::vector<AttributeText> ReadAttributes(const ArchiveReader& archive, const std::string& path) {
  std::vector<AttributeText> attributes;
  for (const AttributeValue& attribute : ReadObjectAttributes(archive, path))
    attributes.push_back({attribute.name, AttributeTextOf(attribute)});
  return attributes;
}

}  // namespace gesweep
