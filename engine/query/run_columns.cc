#include "engine/query/run_columns.h"

#include <fnmatch.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "engine/archive/archive_format.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/column_reader.h"
#include "engine/common/errors.h"
#include "engine/common/request_error.h"
#include "engine/common/toml_reader.h"

namespace gesweep {
namespace {

bool StartsWith(const std::string& text, const std::string& prefix) {
  return text.size() >= prefix.size() && text.compare(0, prefix.size(), prefix) == 0;
}

bool EndsWithTail(const std::string& path, const std::string& tail) {
  if (tail.empty()) return false;
  if (path == tail) return true;
  return path.size() > tail.size() && path.compare(path.size() - tail.size(), tail.size(), tail) == 0 &&
         path[path.size() - tail.size() - 1] == '/';
}

// The tails of a path after each "/", shortest first: "a/b/c" gives "c", "b/c", "a/b/c".
std::vector<std::string> Tails(const std::string& path) {
  std::vector<std::string> tails;
  for (std::size_t i = path.size(); i-- > 0;) {
    if (path[i] == '/') tails.push_back(path.substr(i + 1));
  }
  tails.push_back(path);
  return tails;
}

std::string Join(const std::vector<std::string>& items, const std::string& separator) {
  std::string text;
  for (const auto& item : items) text += (text.empty() ? "" : separator) + item;
  return text;
}

}  // namespace

ColumnCatalog ColumnCatalog::Of(const ArchiveReader& archive) {
  const std::int64_t runs = archive.run_count();
  const std::vector<std::string> design_order =
      ReadStringListAttribute(archive, archive::kDesignGroup, "parameters");
  std::vector<RunColumn> columns;
  std::vector<OtherDataset> others;
  for (const DatasetInfo& dataset : DescribeDatasets(archive)) {
    const std::string& path = dataset.path;
    const bool per_run_group = StartsWith(path, std::string(archive::kRunsGroup) + "/") ||
                               StartsWith(path, std::string(archive::kDesignGroup) + "/") ||
                               StartsWith(path, std::string(archive::kResultsGroup) + "/");
    const std::vector<std::int64_t>& shape = dataset.shape;
    std::string why;
    if (!per_run_group) {
      why = "not a per-run dataset (outside runs/, design/, results/)";
    } else if (shape.empty() || shape[0] != runs) {
      why = "not one value per run";
    } else if (shape.size() > 1) {
      why = dataset.time_axis.empty()
                ? std::to_string(shape[1]) + (dataset.type == StoredType::kCompound ? " complex" : "") +
                      " values per run"
                : "a time series of " + std::to_string(shape[1]) + " samples per run";
    } else if (dataset.type == StoredType::kCompound) {
      why = "a compound value per run";
    } else if (dataset.type == StoredType::kOther) {
      why = "of an unsupported type";
    }
    if (!why.empty()) {
      others.push_back(OtherDataset{path, shape, dataset.units, dataset.description, why});
      continue;
    }
    RunColumn column;
    column.path = path;
    column.units = dataset.units;
    column.description = dataset.description;
    column.primary = !StartsWith(path, std::string(archive::kResultsGroup) + "/");
    if (dataset.type == StoredType::kText) {
      column.kind = ColumnKind::kText;
    } else if (dataset.type == StoredType::kSignedInteger || dataset.type == StoredType::kUnsignedInteger) {
      column.integer = true;
      if (dataset.type == StoredType::kUnsignedInteger && dataset.element_bytes == 8)
        column.kind = ColumnKind::kUnsigned;
      column.fill = dataset.fill;
    }
    column.levels = dataset.levels;
    columns.push_back(std::move(column));
  }
  ColumnCatalog catalog = FromColumns(std::move(columns), design_order, std::move(others));
  if (catalog.status_ < 0 || catalog.index_ < 0) {
    throw ArchiveError(archive.path().string() +
                       ": no runs/status or runs/index dataset (not a complete archive)");
  }
  return catalog;
}

ColumnCatalog ColumnCatalog::FromColumns(std::vector<RunColumn> columns,
                                         const std::vector<std::string>& design_order,
                                         std::vector<OtherDataset> others) {
  ColumnCatalog catalog;
  catalog.columns_ = std::move(columns);
  catalog.others_ = std::move(others);
  // Display names: the shortest tail that resolves back to the column.
  for (auto& column : catalog.columns_) column.name = column.path;
  for (std::size_t i = 0; i < catalog.columns_.size(); ++i) {
    for (const std::string& tail : Tails(catalog.columns_[i].path)) {
      const auto found = catalog.Find(tail);
      if (found && static_cast<std::size_t>(*found) == i) {
        catalog.columns_[i].name = tail;
        break;
      }
    }
  }
  for (std::size_t i = 0; i < catalog.columns_.size(); ++i) {
    const std::string& path = catalog.columns_[i].path;
    if (path == archive::kRunStatus) catalog.status_ = static_cast<int>(i);
    if (path == archive::kRunIndex) catalog.index_ = static_cast<int>(i);
  }
  for (const std::string& name : design_order) {
    if (const auto index = catalog.FindPath(archive::DesignPath(name)))
      catalog.design_columns_.push_back(*index);
  }
  return catalog;
}

std::vector<std::string> ColumnCatalog::Candidates(const std::string& raw) const {
  const std::string name = !raw.empty() && raw[0] == '/' ? raw.substr(1) : raw;
  std::vector<std::string> matches;
  for (const auto& column : columns_) {
    if (EndsWithTail(column.path, name)) matches.push_back(column.path);
  }
  return matches;
}

std::optional<int> ColumnCatalog::FindPath(const std::string& path) const {
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (columns_[i].path == path) return static_cast<int>(i);
  }
  return std::nullopt;
}

std::optional<int> ColumnCatalog::Find(const std::string& raw) const {
  const std::string name = !raw.empty() && raw[0] == '/' ? raw.substr(1) : raw;
  if (name.empty()) return std::nullopt;
  std::vector<int> matches, primary_bare;
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    const RunColumn& column = columns_[i];
    if (column.path == name) return static_cast<int>(i);  // a full path is never ambiguous
    if (!EndsWithTail(column.path, name)) continue;
    matches.push_back(static_cast<int>(i));
    // A bare name (no "/") of a design/runs column: the name after its group.
    if (column.primary && name.find('/') == std::string::npos) primary_bare.push_back(static_cast<int>(i));
  }
  if (matches.size() == 1) return matches[0];
  if (primary_bare.size() == 1) return primary_bare[0];
  return std::nullopt;
}

std::optional<int> ColumnCatalog::Resolve(const std::string& name, std::string* problem,
                                          std::string* remedy) const {
  if (const auto index = Find(name)) return index;
  const std::vector<std::string> candidates = Candidates(name);
  if (candidates.size() > 1) {
    std::vector<std::string> shown;
    shown.reserve(candidates.size());
    for (const auto& path : candidates)
      shown.push_back(columns_[static_cast<std::size_t>(*FindPath(path))].name);
    *problem = "ambiguous column '" + name + "': it matches " + Join(shown, ", ") + "; write one of them";
    return std::nullopt;
  }
  const std::string stripped = !name.empty() && name[0] == '/' ? name.substr(1) : name;
  for (const auto& other : others_) {
    if (EndsWithTail(other.path, stripped)) {
      *problem = "'" + name + "' (" + other.path + ") is not a per-run scalar column: " + other.why;
      return std::nullopt;
    }
  }
  std::vector<std::string> names;
  for (const auto& column : columns_) names.push_back(column.name);
  const std::string nearest = NearestName(name, names);
  *problem = "unknown column '" + name + "'" + (nearest.empty() ? "" : " (did you mean " + nearest + "?)");
  if (remedy != nullptr) *remedy = "describe_columns";
  return std::nullopt;
}

int ColumnCatalog::Require(const std::string& name, const std::string& source, const std::string& key) const {
  std::string problem, remedy;
  const auto index = Resolve(name, &problem, &remedy);
  if (!index) throw RequestError(source, key, name, problem, remedy);
  return *index;
}

std::vector<int> ColumnCatalog::NaturalOrder() const {
  std::vector<int> order;
  std::vector<char> placed(columns_.size(), 0);
  auto place = [&](int c) {
    if (c < 0 || placed[static_cast<std::size_t>(c)]) return;
    placed[static_cast<std::size_t>(c)] = 1;
    order.push_back(c);
  };
  place(index_);
  for (int c : design_columns_) place(c);
  place(status_);
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (!StartsWith(columns_[i].path, std::string(archive::kRunsGroup) + "/")) place(static_cast<int>(i));
  }
  for (std::size_t i = 0; i < columns_.size(); ++i) place(static_cast<int>(i));
  return order;
}

std::vector<int> ColumnCatalog::Expand(const std::string& name, const std::string& source,
                                       const std::string& key) const {
  if (name.find_first_of("*?[") == std::string::npos) return {Require(name, source, key)};
  const bool full_path_only = !name.empty() && name[0] == '/';
  std::vector<int> matches;
  for (int c : NaturalOrder()) {
    const std::string& path = columns_[static_cast<std::size_t>(c)].path;
    bool hit = false;
    if (full_path_only) {
      hit = fnmatch(name.c_str(), ("/" + path).c_str(), 0) == 0;
    } else {
      for (const std::string& tail : Tails(path)) {
        if (fnmatch(name.c_str(), tail.c_str(), 0) == 0) {
          hit = true;
          break;
        }
      }
    }
    if (hit) matches.push_back(c);
  }
  if (matches.empty()) {
    throw RequestError(source, key, name, "the pattern matches no column", "describe_columns");
  }
  return matches;
}

std::size_t MarkCompleteRuns(const ArchiveReader& archive, std::int64_t first, std::int64_t count,
                             std::vector<char>& keep) {
  const auto n = static_cast<std::size_t>(count);
  const std::vector<std::int8_t> status = archive.ReadStatus(first, count);
  keep.assign(n, 0);
  std::size_t complete = 0;
  for (std::size_t i = 0; i < n; ++i) {
    keep[i] = status[i] != 0;
    complete += keep[i] != 0;
  }
  return complete;
}

void ReadColumn(const ArchiveReader& archive, const RunColumn& column, std::int64_t first, std::int64_t count,
                ColumnValues& out) {
  const auto n = static_cast<std::size_t>(count);
  switch (column.kind) {
    case ColumnKind::kText:
      out.texts = ReadTextRows(archive, column.path, first, count);
      return;
    case ColumnKind::kUnsigned:
      ReadUnsignedRows(archive, column.path, first, count, out.unsigned_values);
      out.numbers.resize(n);
      for (std::size_t i = 0; i < n; ++i) out.numbers[i] = static_cast<double>(out.unsigned_values[i]);
      return;
    case ColumnKind::kNumber:
      ReadDoubleRows(archive, column.path, first, count, out.numbers);
      if (column.fill) {
        const auto fill = static_cast<double>(*column.fill);
        for (double& v : out.numbers) {
          if (v == fill) v = std::nan("");
        }
      }
      return;
  }
}

std::string FormatValue(double value, int significant) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  // The shortest text that reads back to the same double (fixed or scientific, whichever is shorter),
  // when it needs at most `significant` digits; else rounded to `significant` digits.
  char buffer[64];
  const auto shortest = std::to_chars(buffer, buffer + sizeof(buffer), value);
  std::string text(buffer, shortest.ptr);
  int digits = 0;
  bool leading = true;
  for (char c : text) {
    if (c == 'e') break;
    if (c < '0' || c > '9') continue;
    if (leading && c == '0') continue;
    leading = false;
    ++digits;
  }
  // Trailing zeros of an integer written in fixed form are not significant digits.
  if (text.find_first_of(".e") == std::string::npos) {
    for (std::size_t i = text.size(); i-- > 0 && text[i] == '0';) --digits;
  }
  if (digits <= significant) return text;
  const auto rounded =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::general, significant);
  return std::string(buffer, rounded.ptr);
}

std::string FormatCell(const RunColumn& column, double number) {
  if (std::isnan(number)) return "nan";
  if (!column.levels.empty() && number >= 0 && number < static_cast<double>(column.levels.size()) &&
      number == std::floor(number)) {
    return column.levels[static_cast<std::size_t>(number)];
  }
  if (column.integer && std::abs(number) < 9.0e15) {
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%.0f", number);
    return buffer;
  }
  return FormatValue(number);
}

}  // namespace gesweep
