#pragma once
// The contract of the --where parser (engine/query/expression.h), checked by the libFuzzer target
// fuzz_where (tests/fuzz/where_fuzz.cc) on arbitrary bytes and by query_test's regression case on
// every kept input (tests/query/where_regressions/) in every build:
//  - any text either parses, or throws InputError whose message is one line; nothing else escapes;
//  - a parsed condition evaluates on a block of awkward values (NaN, ±inf, ±0, huge numbers, codes
//    out of the levels, empty and long texts, bytes that are not UTF-8) to one 0/1 per row;
//  - not (E) parses too (unless E is at the nesting or height limit, refused with the limit's
//    message) and evaluates to the exact complement of E on every row.
// A breach is reported through `defect(what, detail)`, which must not return normally (the fuzz
// target aborts; the test records a failure and throws).
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "engine/common/errors.h"
#include "engine/query/expression.h"
#include "engine/query/run_columns.h"

namespace gesweep::testing {

// A catalogue shaped like a real archive's: an index and an id, design parameters (two with
// levels, one of them false/true), a status with levels, a message, results with shared tails.
inline ColumnCatalog WhereFuzzCatalog() {
  auto column = [](std::string path, ColumnKind kind, bool integer, std::vector<std::string> levels,
                   bool primary) {
    RunColumn c;
    c.path = std::move(path);
    c.kind = kind;
    c.integer = integer;
    c.levels = std::move(levels);
    c.primary = primary;
    if (integer && !c.levels.empty()) c.fill = -1;
    return c;
  };
  std::vector<RunColumn> columns = {
      column("design/cdh", ColumnKind::kNumber, true, {"polar", "zero"}, true),
      column("design/h_derivatives", ColumnKind::kNumber, true, {"false", "true"}, true),
      column("design/height_m", ColumnKind::kNumber, false, {}, true),
      column("design/speed_mps", ColumnKind::kNumber, false, {}, true),
      column("results/boundary/height_m", ColumnKind::kNumber, false, {}, false),
      column("results/boundary/height_over_span", ColumnKind::kNumber, false, {}, false),
      column("results/modes/height_over_span", ColumnKind::kNumber, false, {}, false),
      column("results/modes/phugoid/damping_ratio", ColumnKind::kNumber, false, {}, false),
      column("results/modes/short_period/damping_ratio", ColumnKind::kNumber, false, {}, false),
      column("results/modes/stability_margin_per_s", ColumnKind::kNumber, false, {}, false),
      column("results/modes/stable", ColumnKind::kNumber, true, {"false", "true"}, false),
      column("results/open_loop/end_event", ColumnKind::kNumber, true,
             {"time_limit", "touchdown", "diverged"}, false),
      column("runs/id", ColumnKind::kUnsigned, true, {}, true),
      column("runs/index", ColumnKind::kNumber, true, {}, true),
      column("runs/message", ColumnKind::kText, false, {}, true),
      column("runs/status", ColumnKind::kNumber, true, {"pending", "ok", "failed"}, true),
  };
  return ColumnCatalog::FromColumns(std::move(columns), {"cdh", "h_derivatives", "height_m", "speed_mps"});
}

// A block of rows with awkward values for every column of `catalog`.
inline std::vector<ColumnValues> WhereFuzzValues(const ColumnCatalog& catalog, std::int64_t* rows) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> numbers = {0.0, -0.0, 1.0, -1.0, 2.0, 3.5, nan, inf, -inf, 1e308, -1e-308, 7.0};
  const std::vector<std::string> texts = {"",
                                          "boundary: none (stable at every height)",
                                          "LQR: the Riccati equation has no stabilising solution",
                                          "\xff\xfe not UTF-8",
                                          std::string(5000, 'a') + "b",
                                          "touchdown",
                                          "a\nb",
                                          "(?i)",
                                          "ok",
                                          "failed",
                                          "\xe2\x82\xac",
                                          "x"};
  *rows = static_cast<std::int64_t>(numbers.size());
  std::vector<ColumnValues> values(catalog.columns().size());
  for (std::size_t c = 0; c < catalog.columns().size(); ++c) {
    const RunColumn& column = catalog.columns()[c];
    ColumnValues& v = values[c];
    for (std::size_t r = 0; r < numbers.size(); ++r) {
      if (column.kind == ColumnKind::kText) {
        v.texts.push_back(texts[r]);
      } else if (column.kind == ColumnKind::kUnsigned) {
        const std::uint64_t id = r * 0x9e3779b97f4a7c15ULL;
        v.unsigned_values.push_back(id);
        v.numbers.push_back(static_cast<double>(id));
      } else if (!column.levels.empty()) {
        // Codes in and out of the levels, and missing.
        v.numbers.push_back(r % 5 == 4 ? nan : static_cast<double>(r % 4));
      } else {
        v.numbers.push_back(numbers[(r + c) % numbers.size()]);
      }
    }
  }
  return values;
}

inline bool OneLine(const std::string& message) { return message.find_first_of("\n\r") == std::string::npos; }

inline bool IsLimitMessage(const std::string& message) {
  return message.find("nested deeper than") != std::string::npos ||
         message.find("levels of operators") != std::string::npos;
}

// Checks the contract on `text`; returns whether it parsed.
template <typename Defect>
bool CheckWhereContract(const std::string& text, const ColumnCatalog& catalog,
                        const std::vector<ColumnValues>& values, std::int64_t rows, const Defect& defect) {
  std::vector<char> keep;
  try {
    const RowFilter filter = RowFilter::Parse(text, catalog);
    filter.Evaluate(values, rows, keep);
  } catch (const InputError& e) {
    if (!OneLine(e.what())) defect("InputError message is not one line", e.what());
    return false;
  }
  if (static_cast<std::int64_t>(keep.size()) != rows) defect("wrong number of results", text);
  for (char k : keep) {
    if (k != 0 && k != 1) defect("a result is not 0 or 1", text);
  }
  std::vector<char> complement;
  try {
    const RowFilter negated = RowFilter::Parse("not (" + text + ")", catalog);
    negated.Evaluate(values, rows, complement);
  } catch (const InputError& e) {
    if (!IsLimitMessage(e.what())) defect("not (E) refused where E parsed", e.what());
    return true;
  }
  for (std::size_t r = 0; r < keep.size(); ++r) {
    if (complement[r] == keep[r]) defect("not (E) is not the complement of E", text);
  }
  return true;
}

}  // namespace gesweep::testing
