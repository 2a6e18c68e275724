// schemas/study.schema.json and schemas/archive.md document the same parameters, analyses and columns
// the engine knows: a parameter, analysis or column added to one and not the other fails here.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/analyses/analysis.h"
#include "engine/analyses/parameter_catalog.h"
#include "engine/common/input_limits.h"
#include "engine/common/toml_reader.h"

namespace gesweep {
namespace {

nlohmann::json Schema() {
  std::ifstream in(std::string(GESWEEP_SOURCE_DIR) + "/schemas/study.schema.json");
  return nlohmann::json::parse(in);
}

TEST(StudySchema, ListsEveryCatalogueParameterAndNoOther) {
  const nlohmann::json schema = Schema();
  const auto& fixed = schema["properties"]["parameters"]["properties"];
  std::set<std::string> catalogue, documented;
  for (const auto& info : ParameterCatalog()) {
    catalogue.insert(info.name);
    EXPECT_TRUE(fixed.contains(info.name)) << info.name << " is not in schemas/study.schema.json";
    const auto dot = info.name.find('.');
    if (dot != std::string::npos) {
      // Written in TOML as a dotted key, it arrives as a nested table.
      EXPECT_TRUE(fixed[info.name.substr(0, dot)]["properties"].contains(info.name.substr(dot + 1)))
          << info.name;
    }
    const auto& entry = fixed[info.name];
    if (info.kind == ParameterKind::kReal) {
      EXPECT_EQ(entry["type"], "number") << info.name;
    } else if (info.kind == ParameterKind::kBoolean) {
      EXPECT_EQ(entry["type"], "boolean") << info.name;
    } else {
      EXPECT_EQ(entry["enum"], nlohmann::json(info.levels)) << info.name;
    }
  }
  for (const auto& [name, entry] : fixed.items()) {
    if (entry.value("type", "") == "object") continue;  // the nested forms
    documented.insert(name);
  }
  EXPECT_EQ(documented, catalogue);
}

TEST(StudySchema, MonteCarloDesignNamesEveryCatalogueParameter) {
  // A monte_carlo design samples any parameter (a choice or boolean by values = [...]).
  const nlohmann::json schema = Schema();
  std::set<std::string> catalogue, documented;
  for (const auto& info : ParameterCatalog()) catalogue.insert(info.name);
  bool found = false;
  for (const auto& branch : schema["properties"]["design"]["allOf"]) {
    if (branch["if"]["properties"]["kind"]["const"] != "monte_carlo") continue;
    found = true;
    for (const auto& name : branch["then"]["properties"]["parameter"]["items"]["properties"]["name"]["enum"])
      documented.insert(name.get<std::string>());
  }
  EXPECT_TRUE(found) << "no monte_carlo branch in the design's allOf";
  EXPECT_EQ(documented, catalogue);
}

TEST(StudySchema, ListsEveryAnalysis) {
  const nlohmann::json schema = Schema();
  std::set<std::string> registry, documented;
  for (const auto& entry : AnalysisRegistry()) registry.emplace(entry.name);
  for (const auto& [name, entry] : schema["properties"]["analyses"]["properties"].items())
    documented.insert(name);
  EXPECT_EQ(documented, registry);
}

// The bounds a schema entry states, as the limits table would write them.
struct SchemaBounds {
  std::optional<double> minimum, maximum;
  bool minimum_exclusive = false, maximum_exclusive = false;
};

SchemaBounds BoundsOf(const nlohmann::json& entry) {
  SchemaBounds b;
  if (entry.contains("minimum")) b.minimum = entry["minimum"].get<double>();
  if (entry.contains("exclusiveMinimum")) {
    b.minimum = entry["exclusiveMinimum"].get<double>();
    b.minimum_exclusive = true;
  }
  if (entry.contains("maximum")) b.maximum = entry["maximum"].get<double>();
  if (entry.contains("exclusiveMaximum")) {
    b.maximum = entry["exclusiveMaximum"].get<double>();
    b.maximum_exclusive = true;
  }
  return b;
}

void ExpectSameBounds(const nlohmann::json& entry, const InputLimit& limit, const std::string& where) {
  const SchemaBounds b = BoundsOf(entry);
  if (limit.allows_infinity) {  // JSON has no inf: the schema states the lower bound only
    ASSERT_TRUE(b.minimum && !b.maximum) << where;
    EXPECT_EQ(*b.minimum, limit.minimum) << where;
    EXPECT_EQ(b.minimum_exclusive, limit.minimum_exclusive) << where;
    return;
  }
  ASSERT_TRUE(b.minimum && b.maximum)
      << where << ": the schema states no range; the table says " << DescribeLimit(limit);
  EXPECT_EQ(*b.minimum, limit.minimum) << where;
  EXPECT_EQ(*b.maximum, limit.maximum) << where;
  EXPECT_EQ(b.minimum_exclusive, limit.minimum_exclusive) << where;
  EXPECT_EQ(b.maximum_exclusive, limit.maximum_exclusive) << where;
}

// One table of limits (engine/common/input_limits.h): the schema states the same range for every
// catalogue parameter and every analysis setting the table covers.
TEST(StudySchema, StatesTheLimitsTableRanges) {
  const nlohmann::json schema = Schema();
  const auto& fixed = schema["properties"]["parameters"]["properties"];
  int checked = 0;
  for (const auto& info : ParameterCatalog()) {
    if (info.kind != ParameterKind::kReal) continue;
    ExpectSameBounds(fixed[info.name], RequireInputLimit(info.limit), "parameters." + info.name);
    ++checked;
  }
  const auto& analyses = schema["properties"]["analyses"]["properties"];
  // Settings named "<analysis>.<key>", the shared ones by their key, and two that reuse a parameter's.
  const std::vector<std::pair<std::string, std::string>> shared = {{"open_loop", "relative_tolerance"},
                                                                   {"open_loop", "absolute_tolerance"},
                                                                   {"landing", "relative_tolerance"},
                                                                   {"landing", "absolute_tolerance"}};
  for (const InputLimit& limit : InputLimits()) {
    const std::string name(limit.name);
    const auto dot = name.find('.');
    if (dot == std::string::npos || !analyses.contains(name.substr(0, dot))) continue;
    const auto& settings = analyses[name.substr(0, dot)]["properties"];
    const std::string key = name.substr(dot + 1);
    if (!settings.contains(key)) continue;  // a flag of simulate or land only
    ExpectSameBounds(settings[key], limit, "analyses." + name);
    ++checked;
  }
  for (const auto& [analysis, key] : shared) {
    ExpectSameBounds(analyses[analysis]["properties"][key], RequireInputLimit(key),
                     "analyses." + analysis + "." + key);
    ++checked;
  }
  ExpectSameBounds(analyses["landing"]["properties"]["design_speed_mps"], RequireInputLimit("speed_mps"),
                   "analyses.landing.design_speed_mps");
  ExpectSameBounds(analyses["boundary"]["properties"]["lower_height_m"], RequireInputLimit("height_m"),
                   "analyses.boundary.lower_height_m");
  ExpectSameBounds(analyses["boundary"]["properties"]["upper_height_m"], RequireInputLimit("height_m"),
                   "analyses.boundary.upper_height_m");
  ExpectSameBounds(schema["properties"]["output"]["properties"]["output_dt_s"],
                   RequireInputLimit("output_dt_s"), "output.output_dt_s");
  EXPECT_GT(checked, 40);
}

// The analyses whose settings are described once (engine/common/describe.h; modes and flying_qualities
// have none): their part of the schema is checked against the description (and generated from it,
// scripts/schemas/sync.py).
const std::vector<std::string> kDescribedAnalyses = {"modes", "flying_qualities", "open_loop"};

// The analysis `name` with its default settings (and the ANCE, for one that needs a model).
std::unique_ptr<Analysis> MakeAnalysis(const std::string& name) {
  static const Aircraft aircraft =
      LoadAircraftFile(std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml");
  const toml::table empty;
  return gesweep::MakeAnalysis(name, TomlSection(empty, "test", "analyses." + name), &aircraft);
}

// Each described setting is a schema property of the same kind, range and default, and the schema
// has no other property.
TEST(StudySchema, DescribedSettingsAreTheSchemaProperties) {
  const nlohmann::json schema = Schema();
  for (const std::string& name : kDescribedAnalyses) {
    const auto analysis = MakeAnalysis(name);
    ASSERT_TRUE(analysis);
    const auto& properties = schema["properties"]["analyses"]["properties"][name]["properties"];
    std::set<std::string> described, documented;
    for (const FieldRecord& field : analysis->SettingsFields()) {
      if (!InScope(field.attributes, true) || field.kind == FieldKind::kArray) continue;
      const std::string key(field.attributes.key);
      const std::string where = "analyses." + name + "." + key;
      described.insert(key);
      ASSERT_TRUE(properties.contains(key)) << where << " is not in schemas/study.schema.json";
      const auto& entry = properties[key];
      EXPECT_FALSE(entry.value("description", "").empty()) << where;
      switch (field.kind) {
        case FieldKind::kNumber:
          EXPECT_EQ(entry["type"], "number") << where;
          EXPECT_EQ(entry["default"].get<double>(), *field.number) << where;
          if (!field.attributes.limit.empty())
            ExpectSameBounds(entry, RequireInputLimit(field.attributes.limit), where);
          break;
        case FieldKind::kInteger:
          EXPECT_EQ(entry["type"], "integer") << where;
          EXPECT_EQ(entry["default"].get<double>(), *field.number) << where;
          break;
        case FieldKind::kBoolean:
          EXPECT_EQ(entry["type"], "boolean") << where;
          EXPECT_EQ(entry["default"].get<bool>(), field.default_text == "true") << where;
          break;
        case FieldKind::kChoice:
          EXPECT_EQ(entry["enum"], nlohmann::json(field.choices)) << where;
          EXPECT_EQ(entry["default"], field.default_text) << where;
          break;
        case FieldKind::kText:
          EXPECT_EQ(entry["type"], "string") << where;
          break;
        case FieldKind::kArray:
          break;
      }
    }
    for (const auto& [key, entry] : properties.items()) documented.insert(key);
    EXPECT_EQ(documented, described) << "analyses." << name;
  }
}

std::string ArchiveDocument() {
  std::ifstream in(std::string(GESWEEP_SOURCE_DIR) + "/schemas/archive.md");
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The marker lines around the generated part of schemas/archive.md (scripts/schemas/sync.py,
// BEGIN_MARK and END_MARK).
constexpr std::string_view kGeneratedBegin = "\n<!-- BEGIN generated by scripts/schemas/sync.py ";
constexpr std::string_view kGeneratedEnd = "\n<!-- END generated by scripts/schemas/sync.py -->\n";

// The cells of a Markdown table row "| a | b |" (an escaped "\|" inside a cell is not a separator).
std::vector<std::string> Cells(const std::string& row) {
  std::vector<std::string> cells;
  std::size_t start = 2;  // after "| "
  for (auto at = row.find(" | ", start); at != std::string::npos; at = row.find(" | ", start)) {
    cells.push_back(row.substr(start, at - start));
    start = at + 3;
  }
  const auto last = row.rfind(" |");
  if (last != std::string::npos && last >= start) cells.push_back(row.substr(start, last - start));
  return cells;
}

// The settings an analysis needs to be built (its columns do not depend on them); others: none.
toml::table RequiredSettings(std::string_view name) {
  return name == "linear" ? ParseToml("coefficients = [1.0]", "test") : toml::table{};
}

// schemas/archive.md's columns of each analysis are generated from `gesweep columns --json` by
// scripts/schemas/sync.py (ctest schemas.archive_columns compares them with its output). Checked here
// against the registry itself, without that script: the generated part has a heading per registered
// analysis in the registry's order, and under it a row per column the analysis declares (time series
// on), in the declared order, with its units and its levels as "0 `name`, 1 `name`".
TEST(ArchiveDocument, GeneratedPartListsEveryDeclaredColumn) {
  const std::string text = ArchiveDocument();
  const auto begin = text.find(kGeneratedBegin);
  const auto end = text.find(kGeneratedEnd);
  ASSERT_NE(begin, std::string::npos) << "schemas/archive.md has no generated part";
  ASSERT_NE(end, std::string::npos) << "schemas/archive.md's generated part has no end";
  const std::string part = text.substr(begin, end - begin);
  static const Aircraft aircraft =
      LoadAircraftFile(std::string(GESWEEP_SOURCE_DIR) + "/studies/aircraft/ance.toml");
  StorageOptions storage;
  storage.time_series = true;
  std::size_t at = 0;
  int rows = 0;
  for (const AnalysisEntry& entry : AnalysisRegistry()) {
    const std::string name(entry.name);
    at = part.find("\n#### `" + name + "`\n", at);
    ASSERT_NE(at, std::string::npos) << "no heading of " << name << " (or not in the registry's order)";
    const toml::table settings = RequiredSettings(entry.name);
    const auto analysis = entry.factory(TomlSection(settings, "test", "analyses." + name),
                                        entry.needs_model ? &aircraft : nullptr);
    OutputSchema schema;
    analysis->DeclareOutputs(schema, storage);
    for (const OutputColumn& column : schema.columns) {
      at = part.find("\n| `" + column.path + "` | ", at);
      ASSERT_NE(at, std::string::npos) << "no row of " << column.path << " (or not in the declared order)";
      const std::vector<std::string> cells = Cells(part.substr(at + 1, part.find('\n', at + 1) - at - 1));
      ASSERT_EQ(cells.size(), 6u) << column.path;  // dataset, shape, type, units, levels, meaning
      EXPECT_EQ(cells[3], column.units) << column.path;
      std::string levels;
      for (std::size_t code = 0; code < column.levels.size(); ++code)
        levels += (code ? ", " : "") + std::to_string(code) + " `" + column.levels[code] + "`";
      EXPECT_EQ(cells[4], levels) << column.path;
      EXPECT_FALSE(cells[5].empty()) << column.path;
      ++rows;
    }
  }
  EXPECT_GT(rows, 100);
}

// The hand-written notes after the generated part ("- `<name>`: ...") each open with a registered
// analysis: none is left behind by a removed or renamed one.
TEST(ArchiveDocument, NotesNameRegisteredAnalyses) {
  const std::string text = ArchiveDocument();
  const auto end = text.find(kGeneratedEnd);
  ASSERT_NE(end, std::string::npos);
  const auto next = text.find("\n### ", end);
  const std::string notes = text.substr(end, next - end);
  std::set<std::string> registered;
  for (const auto& entry : AnalysisRegistry()) registered.insert(std::string(entry.name));
  int count = 0;
  for (auto at = notes.find("\n- `"); at != std::string::npos; at = notes.find("\n- `", at + 1)) {
    const auto close = notes.find('`', at + 4);
    const std::string name = notes.substr(at + 4, close - at - 4);
    EXPECT_TRUE(registered.count(name))
        << "schemas/archive.md has a note on '" << name << "', which is not a registered analysis";
    ++count;
  }
  EXPECT_GT(count, 0);
}

}  // namespace
}  // namespace gesweep
