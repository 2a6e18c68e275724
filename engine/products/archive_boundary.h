#pragma once
/// The stability boundary H* of a sweep's results (docs/report.md, "gesweep boundary --archive"):
/// for each combination of the design's other axes (speed, model switches, scale factors, ...), the
/// sign change of results/modes/stability_margin_per_s along design/height_m, unstable below and
/// stable above (the highest such change, as FindBoundary defines H*, docs/model.md §6), refined on
/// the continuous model of that run (ArchiveRunModels) by FindBoundary's TOMS 748 inside the grid
/// bracket, to BoundaryExtractionOptions::tolerance_m. Written to /analysis/boundary.
///
/// Memory: 24 bytes per complete run (height, σ and a group index are kept until every run is read).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "engine/analyses/analysis.h"
#include "engine/archive/product_fields.h"
#include "engine/modal/boundary.h"

namespace gesweep {

class ArchiveReader;
class ArchiveRunModels;
class ColumnCatalog;

/// How to extract.
struct BoundaryExtractionOptions {
  /// Design parameters to order the curve by, first to last (e.g. {"speed_mps"}). The other swept
  /// parameters (besides height_m) follow in design order: every combination is its own curve point.
  std::vector<std::string> by;
  /// Width of the final bracket of the refinement, m. The issue asks for ≤ 1 mm.
  double tolerance_m = 1e-4;
};

/// The boundary at one combination of the other axes.
struct ArchiveBoundaryPoint {
  std::vector<double> key_values;          ///< one per ArchiveBoundary::key_names
  std::optional<double> height_m;          ///< H*, refined; nullopt when none
  std::optional<double> height_over_span;  ///< H*/b
  double grid_lower_height_m = 0;          ///< the grid heights bracketing the sign change (NaN when none)
  double grid_upper_height_m = 0;
  double bracket_width_m = 0;  ///< width of the refinement's final bracket (NaN when none)
  int grid_crossings = 0;      ///< sign changes of σ between neighbouring grid heights
  std::int64_t heights = 0;    ///< runs (distinct heights) with a finite σ in this group
  std::string reason;          ///< why there is none (empty when there is one)
  RunParameters parameters;    ///< the run parameters the refinement used
  BoundaryResult refined;      ///< FindBoundary's result inside the bracket
};

/// The boundary curve of an archive.
struct ArchiveBoundary {
  std::string archive;
  std::string study_name;
  std::string aircraft_name;
  double wingspan_m = 0;
  std::vector<std::string> key_names;  ///< the axes other than height_m, --by first
  std::vector<std::string> key_units;
  std::vector<std::vector<std::string>> key_levels;  ///< level names of a choice/boolean axis
  std::vector<ArchiveBoundaryPoint> points;          ///< ordered by key_names
  double tolerance_m = 0;
  std::int64_t runs_used = 0;     ///< complete ok runs with a finite σ
  std::int64_t runs_skipped = 0;  ///< pending, failed, or without a finite σ
  bool snapshot = false;
};

/// Extracts and refines the boundary. Throws InputError (source the archive) when the design does
/// not sweep height_m, the archive has no results/modes/stability_margin_per_s, or an --by name is
/// not one of the other swept parameters; ArchiveError on I/O failure. A combination without a
/// boundary is a point with a reason, not an error.
ArchiveBoundary ExtractBoundary(const ArchiveReader& archive, const ColumnCatalog& catalog,
                                ArchiveRunModels& models, const BoundaryExtractionOptions& options);

/// Writes `boundary` into the archive's group analysis/boundary (docs/report.md lists its datasets),
/// replacing a previous one: written under a temporary name and moved into place when complete.
/// Preconditions: the caller holds ArchiveLock on the archive and has no handle open on it. Throws
/// InputError when the archive cannot be opened for writing, ArchiveError on an I/O failure.
void WriteBoundaryGroup(const std::filesystem::path& archive, const ArchiveBoundary& boundary,
                        const std::string& command_line);

/// The path of the group: "analysis/boundary". What it holds is product::boundary of
/// engine/archive/product_fields.h, generated from schemas/products.json.
inline constexpr const char* kBoundaryGroup = product::boundary::kPath;

/// A boundary curve H*(u0) traced by continuation on the continuous model (engine/estimators/
/// boundary_curve.h), as plain arrays in ascending speed, to store beside /analysis/boundary.
struct BoundaryCurveRecord {
  std::vector<double> speed_mps, height_m, height_over_span, height_speed_derivative;
  std::vector<std::int32_t> branch;  ///< a new branch after each event
  std::vector<double> event_speed_mps;
  std::vector<std::string> event_what;  ///< "appears", "ends", "jumps"
  double wingspan_m = 0;
};

/// Writes `curve` to the group analysis/boundary_curve (replacing a previous one, as WriteBoundaryGroup).
/// Same preconditions and errors as WriteBoundaryGroup.
void WriteBoundaryCurveGroup(const std::filesystem::path& archive, const BoundaryCurveRecord& curve,
                             const std::string& command_line);

/// The path of the group: "analysis/boundary_curve" (product::boundary_curve).
inline constexpr const char* kBoundaryCurveGroup = product::boundary_curve::kPath;

}  // namespace gesweep
