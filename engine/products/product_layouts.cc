#include "engine/products/product_layouts.h"

#include <string>

#include "engine/archive/archive_format.h"
#include "engine/archive/product_fields.h"
#include "engine/common/enum_names.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep {
namespace {

using Json = nlohmann::ordered_json;

// A field's dimensions ("group, column") as a list of names.
Json ShapeJson(std::string_view shape) {
  Json out = Json::array();
  while (!shape.empty()) {
    const std::size_t comma = shape.find(", ");
    out.push_back(std::string(shape.substr(0, comma)));
    shape = comma == std::string_view::npos ? std::string_view() : shape.substr(comma + 2);
  }
  return out;
}

Json FieldJson(const ProductField& field, bool dataset) {
  Json out = {{"name", field.name}, {"type", field.type}};
  if (dataset) out["units"] = field.units;
  out["shape"] = ShapeJson(field.shape);
  out["description"] = field.description;
  return out;
}

Json LayoutJson(const ProductLayout& layout) {
  Json attributes = Json::array(), datasets = Json::array(), groups = Json::array();
  for (const ProductField& field : layout.attributes) attributes.push_back(FieldJson(field, false));
  for (const ProductField& field : layout.datasets) datasets.push_back(FieldJson(field, true));
  for (const ProductLayout& group : layout.groups) groups.push_back(LayoutJson(group));
  return {{"name", layout.name},
          {"path", layout.path},
          {"written_by", layout.written_by},
          {"description", layout.description},
          {"attributes", attributes},
          {"datasets", datasets},
          {"groups", groups}};
}

// The bookkeeping datasets every archive has (engine/archive/archive_writer.cc writes the same
// units, descriptions and levels; the manifest test compares them with a real archive).
Json RunsJson() {
  Json runs = Json::array();
  runs.push_back({{"path", archive::kRunIndex},
                  {"units", "1"},
                  {"description", "Index of the run in the design (0-based); -1 where not written yet"},
                  {"type", "int64"},
                  {"levels", Json::array()}});
  runs.push_back({{"path", archive::kRunId},
                  {"units", "1"},
                  {"description",
                   "Stable id of the run: FNV-1a hash of its design parameters' names and values (with "
                   "runs/index, identifies the run across shards and resumes)"},
                  {"type", "uint64"},
                  {"levels", Json::array()}});
  runs.push_back(
      {{"path", archive::kRunStatus},
       {"units", "1"},
       {"description",
        "Run status: 0 pending (not complete), 1 ok, 2 failed; written after the run's results, so "
        "a nonzero status marks a complete run"},
       {"type", "int8"},
       {"levels", RunStatusLevels()}});
  runs.push_back(
      {{"path", archive::kRunMessage},
       {"units", "1"},
       {"description",
        "Why a run failed, or a note on an ok run (e.g. no boundary); UTF-8, NUL-padded, at most " +
            std::to_string(kMessageLength) +
            " bytes (a longer message ends in '...'); empty for most runs, whose chunks are never "
            "written"},
       {"type", "string" + std::to_string(kMessageLength)},
       {"levels", Json::array()}});
  return runs;
}

// The run-status levels with their codes, from RunStatus's names table (engine/sweep/runner.h):
// the codes the Python readers compare /runs/status with.
Json RunStatusJson() {
  Json levels = Json::array();
  for (const auto& entry : EnumNames<RunStatus>::kTable) {
    levels.push_back({{"name", entry.name}, {"code", static_cast<int>(entry.value)}});
  }
  return levels;
}

}  // namespace

nlohmann::ordered_json ArchiveLayoutJson() {
  Json products = Json::array();
  for (const ProductLayout* layout : product::AnalysisProducts()) products.push_back(LayoutJson(*layout));
  const Json groups = {{"runs", archive::kRunsGroup},
                       {"design", archive::kDesignGroup},
                       {"results", archive::kResultsGroup},
                       {"series", archive::kSeriesGroup},
                       {"analysis", archive::kAnalysisGroup}};
  return {{"groups", groups},
          {"runs", RunsJson()},
          {"run_status", RunStatusJson()},
          {"products", products},
          {"subset_archive", LayoutJson(product::subset_archive::Layout())}};
}

}  // namespace gesweep
