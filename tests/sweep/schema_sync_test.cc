// schemas/study.schema.json documents the same parameters and analyses the engine knows: a
// parameter or analysis added to one and not the other fails here.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "engine/sweep/analysis.h"
#include "engine/sweep/parameter_catalog.h"

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

TEST(StudySchema, ListsEveryAnalysis) {
  const nlohmann::json schema = Schema();
  std::set<std::string> registry, documented;
  for (const auto& entry : AnalysisRegistry()) registry.emplace(entry.name);
  for (const auto& [name, entry] : schema["properties"]["analyses"]["properties"].items())
    documented.insert(name);
  EXPECT_EQ(documented, registry);
}

}  // namespace
}  // namespace gesweep
