#pragma once
/// The output formats of `gesweep query` (docs/report.md): an aligned table for people, CSV and JSON
/// for programs. Each writes rows as they come (no buffering beyond one row). A level column
/// (status, a choice, a flag) shows its level name; CSV and JSON give every number exactly (shortest
/// round-trip form), the table with up to 10 significant digits.

#include <memory>
#include <ostream>
#include <string>

#include "engine/common/enum_names.h"
#include "engine/query/query.h"

namespace gesweep {

/// Output formats (the names of `gesweep query --format`).
enum class QueryFormat { kAligned, kCsv, kJson };
GESWEEP_ENUM_NAMES(QueryFormat, {kAligned, "table"}, {kCsv, "csv"}, {kJson, "json"});

/// A sink that writes a query's rows in `format` to `out`. `archive` names the archive in the JSON
/// output and the table's closing comment.
std::unique_ptr<QueryRowSink> MakeQueryWriter(QueryFormat format, std::ostream& out,
                                              const std::string& archive);

}  // namespace gesweep
