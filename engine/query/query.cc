#include "engine/query/query.h"

#include <algorithm>
#include <cmath>
#include <queue>

#include "engine/archive/archive_reader.h"
#include "engine/archive/hdf5_util.h"
#include "engine/common/errors.h"
#include "engine/query/expression.h"

namespace gesweep {
namespace {

using hdf5::Check;
using hdf5::Handle;

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

std::string ReadAttributeText(hid_t object, const std::string& name) {
  if (H5Aexists(object, name.c_str()) <= 0) return "";
  Handle attribute(H5Aopen(object, name.c_str(), H5P_DEFAULT), "open attribute " + name);
  Handle type(H5Aget_type(attribute.get()), "type of attribute " + name);
  Handle space(H5Aget_space(attribute.get()), "space of attribute " + name);
  const bool scalar = H5Sget_simple_extent_type(space.get()) == H5S_SCALAR;
  const auto count = static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.get()));
  const H5T_class_t type_class = H5Tget_class(type.get());
  std::vector<std::string> items;
  if (type_class == H5T_STRING) {
    if (scalar) return hdf5::ReadStringAttribute(object, name).value_or("");
    items = hdf5::ReadStringListAttribute(object, name);
  } else if (type_class == H5T_INTEGER || type_class == H5T_FLOAT) {
    std::vector<double> numbers(count);
    if (count > 0)
      Check(H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, numbers.data()), "read attribute " + name);
    for (double v : numbers) items.push_back(FormatAttributeNumber(v, type_class == H5T_INTEGER));
    if (scalar && items.size() == 1) return items[0];
  } else {
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

QuerySummary RunQuery(const ArchiveReader& archive, const ColumnCatalog& catalog, const QueryRequest& request,
                      QueryRowSink& sink) {
  // Everything a person typed is checked before the first row is read.
  std::vector<int> output;
  for (const std::string& name : request.columns) {
    output.push_back(catalog.Require(name, "command line", "--columns"));
  }
  std::optional<RowFilter> filter;
  if (!request.where.empty()) filter.emplace(RowFilter::Parse(request.where, catalog, "--where"));
  std::optional<int> sort_column;
  if (!request.sort.empty()) sort_column = catalog.Require(request.sort, "command line", "--sort");
  if (output.empty()) {
    output = DefaultColumns(catalog);
    auto add = [&](int c) {
      if (std::find(output.begin(), output.end(), c) == output.end()) output.push_back(c);
    };
    if (filter) {
      for (int c : filter->columns()) add(c);
    }
    if (sort_column) add(*sort_column);
  }
  GESWEEP_DEMAND(request.chunk_rows > 0);

  std::vector<const RunColumn*> shown_columns;
  for (int c : output) shown_columns.push_back(&catalog.column(c));
  sink.Begin(shown_columns);

  QuerySummary summary;
  summary.runs = archive.run_count();
  summary.snapshot = archive.snapshot();
  const bool sorting = sort_column.has_value();
  const SortOrder order{request.descending,
                        sorting && catalog.column(*sort_column).kind == ColumnKind::kText};
  // Top-k: a heap whose top is the worst row kept. Without a limit: every matching row.
  std::priority_queue<SortedRow, std::vector<SortedRow>, SortOrder> best(order);
  std::vector<SortedRow> all;
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
    // Statuses first: a nonzero status vouches for values written before it (snapshot safety).
    const std::vector<std::int8_t> status = archive.ReadStatus(first, count);
    keep.assign(n, 0);
    std::size_t complete = 0;
    for (std::size_t i = 0; i < n; ++i) {
      keep[i] = status[i] != 0;
      complete += keep[i] != 0;
    }
    summary.complete += static_cast<std::int64_t>(complete);
    if (complete == 0) continue;
    if (filter) {
      for (int c : filter->columns())
        ReadColumn(archive, catalog.column(c), first, count, values[static_cast<std::size_t>(c)]);
      std::vector<char> condition;
      filter->Evaluate(values, count, condition);
      for (std::size_t i = 0; i < n; ++i) keep[i] = keep[i] && condition[i];
    }
    const auto matched = static_cast<std::int64_t>(std::count(keep.begin(), keep.end(), 1));
    summary.matched += matched;
    if (matched == 0) continue;
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
      if (!bounded) {
        all.push_back(std::move(row));
      } else if (request.limit > 0) {
        if (static_cast<std::int64_t>(best.size()) < request.limit) {
          best.push(std::move(row));
        } else if (order(row, best.top())) {
          best.pop();
          best.push(std::move(row));
        }
      }
    }
  }
  if (sorting) {
    if (bounded) {
      while (!best.empty()) {
        all.push_back(best.top());
        best.pop();
      }
    }
    std::sort(all.begin(), all.end(), order);
    for (const auto& row : all) {
      sink.Row(row.cells);
      ++summary.shown;
    }
  }
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
  Handle object(H5Oopen(archive.file(), path.c_str(), H5P_DEFAULT), "open " + path);
  H5O_info_t info;
  Check(H5Oget_info2(object.get(), &info, H5O_INFO_NUM_ATTRS), "info of " + path);
  std::vector<std::string> names;
  for (hsize_t i = 0; i < info.num_attrs; ++i) {
    const ssize_t length =
        H5Aget_name_by_idx(object.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    Check(length, "attribute name of " + path);
    std::string name(static_cast<std::size_t>(length), '\0');
    Check(H5Aget_name_by_idx(object.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size() + 1,
                             H5P_DEFAULT),
          "attribute name of " + path);
    names.push_back(name);
  }
  std::vector<AttributeText> attributes;
  for (const auto& name : names) attributes.push_back({name, ReadAttributeText(object.get(), name)});
  return attributes;
}

}  // namespace gesweep
