#pragma once
/// Writing a global sensitivity result into its archive, under /analysis/sensitivity/<output>/
/// (schemas/archive.md, "analysis/sensitivity"; docs/sensitivity.md). The caller holds the archive's
/// ArchiveLock (engine/archive/archive_lock.h) so that no sweep writes it meanwhile.

#include <filesystem>
#include <string>

#include "engine/archive/analysis_product.h"
#include "engine/products/archive_sensitivity.h"

namespace gesweep {

/// The group of an output's result: "analysis/sensitivity/" + output.name, e.g.
/// "analysis/sensitivity/boundary/height_m" for results/boundary/height_m.
std::string SensitivityGroupPath(const ArchiveOutput& output);

/// Writes `result` (status kOk) into the archive at SensitivityGroupPath(result.output), replacing a
/// previous result for the same output: the new group is written under a temporary name and moved
/// into place only when complete, so a failure leaves the previous result untouched. Records the
/// indices and their intervals, the estimators, N, D, the bootstrap resamples, level and seed, the
/// blocks used and dropped, the parameter names, the method and `command_line`. Preconditions: the
/// caller holds ArchiveLock on the archive and has no handle open on it. Throws InputError when
/// the archive cannot be opened for writing (open elsewhere), ArchiveError on an I/O failure.
/// The group's fields are product::sensitivity of engine/archive/product_fields.h (generated from
/// schemas/products.json), which lists the Sobol' and the Morris ones: a group holds its method's.
void WriteSensitivityGroup(const std::filesystem::path& archive, const ArchiveSensitivity& result,
                           const std::string& command_line);

}  // namespace gesweep
