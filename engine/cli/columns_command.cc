// gesweep columns: the column manifest, every dataset an archive can hold, with its units, description,
// type, width, levels, component names and time axis (schemas/archive.md, "The column manifest"; its
// --json output is what scripts/lib/columns.py reads and scripts/schemas/sync.py writes the
// per-analysis parts of schemas/study.schema.json and schemas/archive.md from; checked against real
// archives by tests/report/columns_manifest_test.py). Each analysis of the registry is
// built with its default settings and asked for its columns with time series on, so the manifest is
// what the analyses declare, not a second list.
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "engine/aircraft/aircraft.h"
#include "engine/analyses/analysis.h"
#include "engine/analyses/parameter_catalog.h"
#include "engine/archive/archive_format.h"
#include "engine/cli/command.h"
#include "engine/common/enum_names.h"
#include "engine/common/errors.h"
#include "engine/common/input_limits.h"
#include "engine/common/toml_reader.h"
#include "engine/products/product_layouts.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep::cli {
namespace {

using Json = nlohmann::ordered_json;

// Version of the manifest's own layout (not of the archive's, which it names beside it).
constexpr int kManifestVersion = 1;
// A column is a rating when it is an int8 code whose first level is named this (any case):
// "level 1", "level 2", ..., a larger code worse. The one named kOverallRatingName is its analysis's
// overall rating (the worst of the others, the parts).
constexpr std::string_view kRatingFirstLevel = "level 1";
constexpr std::string_view kOverallRatingName = "level";
// Settings for the analyses that have a required setting (their columns do not depend on it); every
// other analysis is built from an empty [analyses.<name>] table, i.e. its defaults.
constexpr std::pair<std::string_view, std::string_view> kRequiredSettings[] = {
    {"linear", "coefficients = [1.0]"},
};

// The analyses whose [analyses.<name>] settings are still read by hand, not from a description
// (describe.h): the manifest gives null for their settings, and their part of
// schemas/study.schema.json is written by hand. Every other analysis's settings are its
// SettingsFields() (none for an analysis that has no settings).
constexpr std::string_view kSettingsByHand[] = {"boundary", "landing", "ishigami", "linear"};

// The settings table `name` is built with: its required settings, or none.
toml::table SettingsOf(std::string_view name) {
  for (const auto& [analysis, text] : kRequiredSettings) {
    if (analysis == name)
      return ParseToml(text, "gesweep columns (its settings of " + std::string(name) + ")");
  }
  return toml::table{};
}

// The manifest's names of the column types and of the parameters' kinds and groups.
constexpr EnumName<ColumnType> kTypeNames[] = {{ColumnType::kFloat64, "float64"},
                                               {ColumnType::kInt32, "int32"},
                                               {ColumnType::kInt8, "int8"},
                                               {ColumnType::kComplex, "complex128"}};
constexpr EnumName<ParameterKind> kKindNames[] = {
    {ParameterKind::kReal, "real"}, {ParameterKind::kBoolean, "boolean"}, {ParameterKind::kChoice, "choice"}};
constexpr EnumName<ParameterGroup> kGroupNames[] = {{ParameterGroup::kFlight, "flight"},
                                                    {ParameterGroup::kModel, "model"},
                                                    {ParameterGroup::kOpenLoop, "open_loop"},
                                                    {ParameterGroup::kLanding, "landing"},
                                                    {ParameterGroup::kVerification, "verification"}};

// The name of `value` in `table`, which lists every value.
template <class E, std::size_t N>
std::string_view NameIn(const EnumName<E> (&table)[N], E value) {
  for (const auto& entry : table) {
    if (entry.value == value) return entry.name;
  }
  GESWEEP_UNREACHABLE();
}

std::string Lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// The last part of a path: the name a script asks for ("results/modes/phugoid/damping_ratio" under
// "results/modes/" is "phugoid/damping_ratio").
std::string NameUnder(const std::string& path, const std::string& prefix) {
  GESWEEP_DEMAND(path.compare(0, prefix.size(), prefix) == 0);
  return path.substr(prefix.size());
}

// "rating", "overall_rating" or "" (see kRatingFirstLevel).
std::string Role(const OutputColumn& column, const std::string& name) {
  if (column.type != ColumnType::kInt8 || column.levels.empty() ||
      Lower(column.levels[0]) != kRatingFirstLevel) {
    return "";
  }
  return name == kOverallRatingName ? "overall_rating" : "rating";
}

Json ColumnJson(const OutputColumn& column, const std::string& analysis) {
  const bool series = !column.time_axis.empty();
  const std::string group = series ? archive::kSeriesGroup : archive::kResultsGroup;
  const std::string name = NameUnder(column.path, group + "/" + analysis + "/");
  Json out = {{"path", column.path},
              {"group", group},
              {"name", name},
              {"units", column.units},
              {"description", column.description},
              {"type", NameIn(kTypeNames, column.type)},
              {"width", column.width}};
  out["levels"] = column.levels;
  out["component_names"] = column.component_names;
  out["time_axis"] = column.time_axis;
  if (column.type == ColumnType::kInt8 || column.type == ColumnType::kInt32) {
    out["fill"] = column.integer_fill;
  } else {
    out["fill"] = nullptr;  // NaN
  }
  out["role"] = Role(column, name);
  return out;
}

Json AxisJson(const TimeAxis& axis) {
  GESWEEP_DEMAND(!axis.times_s.empty());
  const double step = axis.times_s.size() > 1 ? axis.times_s[1] - axis.times_s[0] : 0.0;
  return {{"path", axis.path},
          {"description", axis.description},
          {"units", "s"},
          {"samples", axis.times_s.size()},
          {"first_s", axis.times_s.front()},
          {"step_s", step},
          {"last_s", axis.times_s.back()}};
}

// One described setting as the JSON Schema of its key in [analyses.<name>]: what
// schemas/study.schema.json states for it (scripts/schemas/sync.py copies it there).
Json SettingSchema(const FieldRecord& field) {
  Json out;
  switch (field.kind) {
    case FieldKind::kNumber:
      out = {{"default", *field.number}, {"type", "number"}};
      break;
    case FieldKind::kInteger:
      out = {{"default", static_cast<long long>(*field.number)}, {"type", "integer"}};
      break;
    case FieldKind::kBoolean:
      out = {{"default", field.default_text == "true"}, {"type", "boolean"}};
      break;
    case FieldKind::kChoice:
      out = {{"default", field.default_text}, {"enum", field.choices}};
      break;
    case FieldKind::kText:
      out = {{"type", "string"}};
      break;
    case FieldKind::kArray:
      GESWEEP_UNREACHABLE();  // not a study key (SettingsJson leaves arrays out)
  }
  out["description"] = std::string(field.attributes.doc);
  if (field.attributes.limit.empty()) return out;
  const InputLimit& limit = RequireInputLimit(field.attributes.limit);
  out[limit.minimum_exclusive ? "exclusiveMinimum" : "minimum"] = limit.minimum;
  if (!limit.allows_infinity) out[limit.maximum_exclusive ? "exclusiveMaximum" : "maximum"] = limit.maximum;
  return out;
}

// The JSON Schema properties of [analyses.<name>], from the analysis's described settings; null for
// an analysis of kSettingsByHand.
Json SettingsJson(std::string_view name, const Analysis& analysis) {
  for (std::string_view by_hand : kSettingsByHand) {
    if (by_hand == name) return nullptr;
  }
  Json properties = Json::object();
  for (const FieldRecord& field : analysis.SettingsFields()) {
    if (!InScope(field.attributes, true) || field.kind == FieldKind::kArray) continue;
    properties[std::string(field.attributes.key)] = SettingSchema(field);
  }
  return properties;
}

// Every parameter a design can sweep: design/<name> when swept (float64; a boolean 0/1, a choice the
// index of its level).
Json DesignJson() {
  Json design = Json::array();
  for (const ParameterInfo& info : ParameterCatalog()) {
    design.push_back({{"path", archive::DesignPath(info.name)},
                      {"name", info.name},
                      {"units", info.units},
                      {"description", info.description},
                      {"type", "float64"},
                      {"kind", NameIn(kKindNames, info.kind)},
                      {"group", NameIn(kGroupNames, info.group)},
                      {"levels", info.levels}});
  }
  return design;
}

Json Manifest(const Aircraft& aircraft) {
  const Json layout = ArchiveLayoutJson();
  StorageOptions storage;
  storage.time_series = true;
  Json analyses = Json::array();
  for (const AnalysisEntry& entry : AnalysisRegistry()) {
    GESWEEP_DEMAND(entry.factory != nullptr);
    const toml::table table = SettingsOf(entry.name);
    const TomlSection settings(table, "gesweep columns (engine/cli/columns_command.cc, kRequiredSettings)",
                               "analyses." + std::string(entry.name));
    std::unique_ptr<Analysis> analysis = entry.factory(settings, entry.needs_model ? &aircraft : nullptr);
    OutputSchema schema;
    analysis->DeclareOutputs(schema, storage);
    Json columns = Json::array();
    for (const OutputColumn& column : schema.columns)
      columns.push_back(ColumnJson(column, std::string(entry.name)));
    Json axes = Json::array();
    for (const TimeAxis& axis : schema.axes) axes.push_back(AxisJson(axis));
    Json parameters = Json::array();
    for (ParameterId id : analysis->parameters_used()) {
      parameters.push_back(ParameterCatalog()[static_cast<std::size_t>(id)].name);
    }
    analyses.push_back({{"name", entry.name},
                        {"description", entry.description},
                        {"needs_model", entry.needs_model},
                        {"parameters_used", parameters},
                        {"settings", SettingsJson(entry.name, *analysis)},
                        {"columns", columns},
                        {"time_axes", axes}});
  }
  return {{"format", "gesweep-columns"},
          {"format_version", kManifestVersion},
          {"archive_format_version", archive::kFormatVersion},
          {"generated_by", "gesweep columns --json"},
          {"note",
           "Every dataset an archive can hold (schemas/archive.md). Each analysis is built with its default "
           "settings; series widths are for output.time_series = true at the default output_dt_s and "
           "durations (a study's own settings change them, not the names). role: 'rating' for an int8 "
           "column whose levels begin 'level 1', 'overall_rating' for the one named 'level'. groups, runs, "
           "run_status, products (the /analysis groups) and subset_archive (gesweep risk's archive): the "
           "layout the readers of archives find their paths in, from what the writers store; a name or "
           "path in <angle brackets> stands for a family."},
          {"storage", {{"time_series", storage.time_series}, {"output_dt_s", storage.output_dt_s}}},
          {"runs", layout["runs"]},
          {"run_status", layout["run_status"]},
          {"design", DesignJson()},
          {"analyses", analyses},
          {"groups", layout["groups"]},
          {"products", layout["products"]},
          {"subset_archive", layout["subset_archive"]}};
}

std::string Text(const Json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_array()) {
    std::string out;
    for (const auto& item : value) out += (out.empty() ? "" : ", ") + Text(item);
    return out;
  }
  return value.dump();
}

// The datasets of a product (or of one of its subgroups) under `path`, then its subgroups'.
template <class Row>
void PrintLayout(const Json& layout, const std::string& path, const Row& row) {
  for (const auto& d : layout["datasets"]) {
    row(path + "/" + Text(d["name"]), Text(d["type"]), Text(d["units"]), Text(d["shape"]),
        Text(d["description"]));
  }
  for (const auto& group : layout["groups"]) PrintLayout(group, path + "/" + Text(group["path"]), row);
}

// The /analysis products and the subset-simulation archive.
template <class Row>
void PrintLayouts(const Json& manifest, const Row& row) {
  for (const auto& product : manifest["products"]) {
    std::cout << "\n## /" << Text(product["path"]) << " (" << Text(product["written_by"])
              << "): " << Text(product["description"]) << "\n";
    PrintLayout(product, Text(product["path"]), row);
  }
  const Json& subset = manifest["subset_archive"];
  std::cout << "\n## " << Text(subset["written_by"]) << ": " << Text(subset["description"]) << "\n";
  for (const auto& group : subset["groups"]) PrintLayout(group, Text(group["path"]), row);
}

void PrintText(const Json& manifest) {
  auto row = [](const std::string& path, const std::string& type, const std::string& units,
                const std::string& extra, const std::string& description) {
    std::cout << std::left << std::setw(58) << path << " " << std::setw(11) << type << " " << std::setw(7)
              << units << " " << description << (extra.empty() ? "" : "  [" + extra + "]") << "\n";
  };
  std::cout << "# The columns of a gesweep archive (format " << Text(manifest["archive_format_version"])
            << "); `gesweep columns --json` gives the same as JSON.\n";
  std::cout << "\n## runs (every archive)\n";
  for (const auto& c : manifest["runs"]) {
    row(Text(c["path"]), Text(c["type"]), Text(c["units"]),
        c["levels"].empty() ? "" : "levels: " + Text(c["levels"]), Text(c["description"]));
  }
  std::cout << "\n## design (one dataset per swept parameter)\n";
  for (const auto& c : manifest["design"]) {
    std::string extra = Text(c["kind"]);
    if (!c["levels"].empty()) extra += "; levels: " + Text(c["levels"]);
    row(Text(c["path"]), Text(c["type"]), Text(c["units"]), extra, Text(c["description"]));
  }
  PrintLayouts(manifest, row);
  for (const auto& analysis : manifest["analyses"]) {
    std::cout << "\n## " << Text(analysis["name"]) << ": " << Text(analysis["description"]) << "\n";
    for (const auto& c : analysis["columns"]) {
      std::string type = Text(c["type"]);
      if (c["width"].get<int>() != 1) type += "[" + Text(c["width"]) + "]";
      std::vector<std::string> extra;
      if (!c["levels"].empty()) extra.push_back("levels: " + Text(c["levels"]));
      if (!c["component_names"].empty()) extra.push_back("components: " + Text(c["component_names"]));
      if (!Text(c["time_axis"]).empty()) extra.push_back("time axis: " + Text(c["time_axis"]));
      if (!Text(c["role"]).empty()) extra.push_back("role: " + Text(c["role"]));
      std::string joined;
      for (const auto& e : extra) joined += (joined.empty() ? "" : "; ") + e;
      row(Text(c["path"]), type, Text(c["units"]), joined, Text(c["description"]));
    }
    for (const auto& axis : analysis["time_axes"]) {
      row(Text(axis["path"]), "float64[" + Text(axis["samples"]) + "]", "s",
          "time axis: " + Text(axis["first_s"]) + " to " + Text(axis["last_s"]) + " s by " +
              Text(axis["step_s"]),
          Text(axis["description"]));
    }
  }
}

struct ColumnsFlags {
  bool json = false;
  std::string aircraft = GESWEEP_COLUMNS_AIRCRAFT_DEFAULT;
};

void AddColumnsFlags(CLI::App& app, ColumnsFlags& flags) {
  app.add_flag("--json", flags.json, "JSON (what scripts read, schemas/archive.md) instead of a text table");
  app.add_option("--aircraft", flags.aircraft,
                 "Aircraft file the analyses that need one are built with (the columns do not depend on "
                 "it); default: the repository's studies/aircraft/ance.toml");
}

int RunColumns(const ColumnsFlags& flags) {
  const Json manifest = Manifest(LoadAircraftFile(flags.aircraft));
  if (flags.json) {
    std::cout << manifest.dump(2) << "\n";
  } else {
    PrintText(manifest);
  }
  return 0;
}

const CommandRegistrar kRegistrar{CommandWith<ColumnsFlags>(
    "columns", "The column manifest: every dataset an archive can hold (schemas/archive.md)", AddColumnsFlags,
    RunColumns)};

}  // namespace
}  // namespace gesweep::cli
