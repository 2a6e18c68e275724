#pragma once
/// The estimates of a subset-simulation archive as `gesweep risk` prints them (a table, or the
/// archive's result_json); `gesweep dispersion` prints the same for such an archive.
#include <filesystem>
#include <string>

#include "engine/cli/command.h"

namespace gesweep::cli {

/// Reads the archive (risk::ReadRiskArchive's checks) and prints its estimates in `format` to stdout;
/// returns the exit code (0).
int PrintRiskArchive(const std::filesystem::path& archive, TableOrJson format);

/// A result_json document as printed: "archive" (the file read or written) first, then the document.
std::string WithArchive(const std::string& result_json, const std::filesystem::path& archive);

/// The table of a result_json document.
void PrintRiskTable(const std::string& result_json);

}  // namespace gesweep::cli
