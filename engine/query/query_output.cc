#include "engine/query/query_output.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

// Significant digits of numbers in the table; CSV and JSON give the exact value.
constexpr int kTableDigits = 10;
constexpr int kExactDigits = 17;
constexpr std::size_t kNumberWidth = 12;
constexpr std::size_t kTextWidth = 24;

std::string CellText(const RunColumn& column, const QueryCell& cell, int digits) {
  if (column.kind != ColumnKind::kNumber) return cell.text;
  if (!column.levels.empty() || column.integer || std::isnan(cell.number))
    return FormatCell(column, cell.number);
  return FormatValue(cell.number, digits);
}

std::string SummaryLine(const QuerySummary& s, const std::string& archive) {
  std::string line;
  if (s.groups >= 0) {
    line = "# " + std::to_string(s.shown) + " shown of " + std::to_string(s.groups) + " groups of " +
           std::to_string(s.matched) + " matching runs (" + std::to_string(s.complete) + " complete of " +
           std::to_string(s.runs) + ") in " + archive;
    if (s.passes > 1) line += "; medians and quantiles exact after " + std::to_string(s.passes) + " passes";
  } else {
    line = "# " + std::to_string(s.shown) + " shown of " + std::to_string(s.matched) + " matching runs (" +
           std::to_string(s.complete) + " complete of " + std::to_string(s.runs) + ") in " + archive;
  }
  if (s.snapshot) {
    line +=
        "\n# snapshot: a sweep is writing this archive (or its writer stopped without closing it); "
        "pending runs are left out";
  }
  return line;
}

class TableWriter final : public QueryRowSink {
 public:
  TableWriter(std::ostream& out, std::string archive) : out_(out), archive_(std::move(archive)) {}

  void Begin(const std::vector<const RunColumn*>& columns) override {
    columns_ = columns;
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const RunColumn& column = *columns[c];
      std::size_t width = column.name.size();
      if (column.kind == ColumnKind::kText) {
        width = std::max(width, kTextWidth);
      } else if (column.kind == ColumnKind::kUnsigned) {
        width = std::max<std::size_t>(width, 20);
      } else if (!column.levels.empty()) {
        for (const auto& level : column.levels) width = std::max(width, level.size());
      } else if (!column.integer) {
        width = std::max(width, kNumberWidth);
      } else {
        width = std::max<std::size_t>(width, 6);
      }
      widths_.push_back(width);
    }
    std::vector<std::string> names;
    names.reserve(columns.size());
    for (const RunColumn* column : columns) names.push_back(column->name);
    Write(names);
  }

  void Row(const std::vector<QueryCell>& cells) override {
    std::vector<std::string> texts;
    for (std::size_t c = 0; c < cells.size(); ++c)
      texts.push_back(CellText(*columns_[c], cells[c], kTableDigits));
    Write(texts);
  }

  void End(const QuerySummary& summary) override { out_ << SummaryLine(summary, archive_) << "\n"; }

 private:
  void Write(const std::vector<std::string>& texts) {
    for (std::size_t c = 0; c < texts.size(); ++c) {
      const bool left = columns_[c]->kind == ColumnKind::kText;
      const bool last = c + 1 == texts.size();
      if (c > 0) out_ << "  ";
      if (left) {
        out_ << (last ? texts[c]
                      : texts[c] + std::string(
                                       widths_[c] > texts[c].size() ? widths_[c] - texts[c].size() : 0, ' '));
      } else {
        out_ << std::setw(static_cast<int>(widths_[c])) << texts[c];
      }
    }
    out_ << "\n";
  }

  std::ostream& out_;
  std::string archive_;
  std::vector<const RunColumn*> columns_;
  std::vector<std::size_t> widths_;
};

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

class CsvWriter final : public QueryRowSink {
 public:
  explicit CsvWriter(std::ostream& out) : out_(out) {}
  void Begin(const std::vector<const RunColumn*>& columns) override {
    columns_ = columns;
    for (std::size_t c = 0; c < columns.size(); ++c) out_ << (c ? "," : "") << CsvField(columns[c]->name);
    out_ << "\n";
  }
  void Row(const std::vector<QueryCell>& cells) override {
    for (std::size_t c = 0; c < cells.size(); ++c) {
      out_ << (c ? "," : "") << CsvField(CellText(*columns_[c], cells[c], kExactDigits));
    }
    out_ << "\n";
  }
  void End(const QuerySummary&) override { out_.flush(); }

 private:
  std::ostream& out_;
  std::vector<const RunColumn*> columns_;
};

class JsonWriter final : public QueryRowSink {
 public:
  JsonWriter(std::ostream& out, std::string archive) : out_(out), archive_(std::move(archive)) {}
  void Begin(const std::vector<const RunColumn*>& columns) override {
    columns_ = columns;
    nlohmann::json list = nlohmann::json::array();
    for (const RunColumn* column : columns) {
      nlohmann::json entry = {{"name", column->name}, {"path", column->path}, {"units", column->units}};
      if (!column->levels.empty()) entry["levels"] = column->levels;
      if (!column->statistic.empty()) entry["statistic"] = column->statistic;
      list.push_back(entry);
    }
    out_ << "{\"archive\": " << nlohmann::json(archive_).dump() << ",\n \"columns\": " << list.dump()
         << ",\n \"rows\": [";
  }
  void Row(const std::vector<QueryCell>& cells) override {
    nlohmann::json row = nlohmann::json::object();
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const RunColumn& column = *columns_[c];
      const QueryCell& cell = cells[c];
      if (column.kind == ColumnKind::kText) {
        row[column.name] = cell.text;
      } else if (column.kind == ColumnKind::kUnsigned) {
        row[column.name] = static_cast<std::uint64_t>(std::stoull(cell.text));
      } else if (std::isnan(cell.number) || std::isinf(cell.number)) {
        row[column.name] = nullptr;
      } else if (!column.levels.empty()) {
        row[column.name] = FormatCell(column, cell.number);
      } else if (column.integer) {
        row[column.name] = static_cast<std::int64_t>(cell.number);
      } else {
        row[column.name] = cell.number;
      }
    }
    out_ << (first_ ? "\n  " : ",\n  ") << row.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    first_ = false;
  }
  void End(const QuerySummary& s) override {
    out_ << (first_ ? "]" : "\n ]") << ",\n \"runs\": " << s.runs << ", \"complete\": " << s.complete
         << ", \"matched\": " << s.matched << ", \"shown\": " << s.shown;
    if (s.groups >= 0) out_ << ", \"groups\": " << s.groups << ", \"passes\": " << s.passes;
    out_ << ", \"snapshot\": " << (s.snapshot ? "true" : "false") << "}\n";
  }

 private:
  std::ostream& out_;
  std::string archive_;
  std::vector<const RunColumn*> columns_;
  bool first_ = true;
};

}  // namespace

std::unique_ptr<QueryRowSink> MakeQueryWriter(QueryFormat format, std::ostream& out,
                                              const std::string& archive) {
  switch (format) {
    case QueryFormat::kAligned:
      return std::make_unique<TableWriter>(out, archive);
    case QueryFormat::kCsv:
      return std::make_unique<CsvWriter>(out);
    case QueryFormat::kJson:
      return std::make_unique<JsonWriter>(out, archive);
  }
  return nullptr;
}

}  // namespace gesweep
