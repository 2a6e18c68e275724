// The registry of the analyses a study can name (analysis.h): each adapter file adds its own entry
// with an AnalysisRegistrar; the list is kept sorted by the entries' order keys, which is the order
// of the analyses' columns in an archive.
#include <algorithm>

#include "engine/analyses/analysis.h"
#include "engine/common/errors.h"

namespace gesweep {
namespace {

// Built on first use, so that registrars in other files may run before or after this file's
// static initialisation.
std::vector<AnalysisEntry>& MutableRegistry() {
  static std::vector<AnalysisEntry> registry;
  return registry;
}

}  // namespace

const std::vector<AnalysisEntry>& AnalysisRegistry() { return MutableRegistry(); }

AnalysisRegistrar::AnalysisRegistrar(const AnalysisEntry& entry) {
  std::vector<AnalysisEntry>& registry = MutableRegistry();
  GESWEEP_DEMAND(std::none_of(registry.begin(), registry.end(), [&](const AnalysisEntry& e) {
    return e.name == entry.name || e.order == entry.order;
  }));
  const auto at = std::upper_bound(registry.begin(), registry.end(), entry.order,
                                   [](int order, const AnalysisEntry& e) { return order < e.order; });
  registry.insert(at, entry);
}

std::unique_ptr<Analysis> MakeAnalysis(std::string_view name, const TomlSection& settings,
                                       const Aircraft* aircraft) {
  const auto& registry = AnalysisRegistry();
  const auto entry =
      std::find_if(registry.begin(), registry.end(), [&](const AnalysisEntry& e) { return e.name == name; });
  GESWEEP_DEMAND(entry != registry.end() && entry->factory != nullptr);
  return entry->factory(settings, aircraft);
}

}  // namespace gesweep
