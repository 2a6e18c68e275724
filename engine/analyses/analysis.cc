#include "engine/analyses/analysis.h"

#include <algorithm>

#include "engine/analyses/described_columns.h"
#include "engine/common/errors.h"

namespace gesweep {

int OutputColumn::stored_bytes_per_run() const {
  switch (type) {
    case ColumnType::kFloat64:
      return 8 * width;
    case ColumnType::kInt32:
      return 4 * width;
    case ColumnType::kInt8:
      return width;
    case ColumnType::kComplex:
      return 16 * width;
  }
  GESWEEP_UNREACHABLE();
}

ColumnType ColumnTypeOf(StoredAs stored) {
  switch (stored) {
    case StoredAs::kFloat64:
      return ColumnType::kFloat64;
    case StoredAs::kInt32:
      return ColumnType::kInt32;
    case StoredAs::kInt8:
      return ColumnType::kInt8;
    case StoredAs::kNotStored:
      break;
  }
  GESWEEP_UNREACHABLE();
}

int OutputSchema::Add(OutputColumn column) {
  GESWEEP_DEMAND(column.width >= 1);
  GESWEEP_DEMAND(
      std::none_of(columns.begin(), columns.end(), [&](const auto& c) { return c.path == column.path; }));
  columns.push_back(std::move(column));
  return static_cast<int>(columns.size()) - 1;
}

void OutputSchema::AddAxis(TimeAxis axis) {
  GESWEEP_DEMAND(std::none_of(axes.begin(), axes.end(), [&](const auto& a) { return a.path == axis.path; }));
  axes.push_back(std::move(axis));
}

std::int64_t OutputSchema::StoredBytesPerRun() const {
  std::int64_t bytes = 0;
  for (const auto& column : columns) bytes += column.stored_bytes_per_run();
  return bytes;
}

}  // namespace gesweep
