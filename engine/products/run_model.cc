#include "engine/products/run_model.h"

#include "engine/analyses/analysis.h"
#include "engine/archive/archive_format.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/column_reader.h"
#include "engine/common/errors.h"
#include "engine/common/toml_reader.h"
#include "engine/sweep/runner.h"
#include "engine/sweep/study.h"
#include "engine/sweep/sweep_plan.h"

namespace gesweep {
namespace {

// An archive's parameter name: today's, or an older name of it, as an older archive has it
// (RenamedParameters).
ParameterId ParameterOf(const std::string& name, const std::string& source, const std::string& where) {
  const auto id = FindParameterOrOlder(name, nullptr);
  if (!id)
    throw InputError(source, where, name,
                     "a parameter this engine does not know (an archive of another version?)");
  return *id;
}

}  // namespace

ArchiveRunModels::ArchiveRunModels() = default;
ArchiveRunModels::ArchiveRunModels(ArchiveRunModels&&) noexcept = default;
ArchiveRunModels& ArchiveRunModels::operator=(ArchiveRunModels&&) noexcept = default;
ArchiveRunModels::~ArchiveRunModels() = default;

ArchiveRunModels ArchiveRunModels::Of(const ArchiveReader& archive) {
  const std::string source = archive.path().string();
  const std::string text = archive.StringAttribute("aircraft_text");
  if (text.empty()) {
    throw InputError(source, "aircraft_text", "",
                     "the archive records no aircraft (its study names none), so no model");
  }
  const std::string aircraft_path = archive.StringAttribute("aircraft_path");
  // A synthetic one-run study of this aircraft: its plan gives the runner's defaults for the
  // aircraft (mass and inertia included) and its workspace builds models exactly as the sweep did.
  Study study;
  study.path = source;
  study.name = archive.StringAttribute("study_name");
  study.aircraft = ParseAircraft(
      text, (aircraft_path.empty() ? source : aircraft_path) + " (as stored in " + source + ")");
  const toml::table empty;
  study.analyses.push_back(
      MakeAnalysis("modes", TomlSection(empty, source, "analyses.modes"), &*study.aircraft));
  study.design.kind = DesignKind::kSingle;

  ArchiveRunModels models;
  models.plan_ = std::make_unique<SweepPlan>(std::move(study), ShardSpec{});
  models.workspace_ = std::make_unique<RunWorkspace>(*models.plan_);
  models.base_ = models.plan_->base_parameters();

  const std::vector<std::string> names =
      ReadStringListAttribute(archive, archive::kDesignGroup, "unswept_parameter_names");
  const std::vector<double> values =
      ReadDoubleListAttribute(archive, archive::kDesignGroup, "unswept_parameter_values");
  if (names.size() != values.size()) {
    throw InputError(
        source, "design/unswept_parameter_values", "",
        "expected one value per name of unswept_parameter_names (" + std::to_string(names.size()) + ")");
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    models.base_[static_cast<std::size_t>(ParameterOf(names[i], source, "design/unswept_parameter_names"))] =
        values[i];
  }
  for (const std::string& name : ReadStringListAttribute(archive, archive::kDesignGroup, "parameters")) {
    models.design_ids_.push_back(ParameterOf(name, source, "design/parameters"));
  }
  return models;
}

const Aircraft& ArchiveRunModels::aircraft() const { return *plan_->study().aircraft; }

RunParameters ArchiveRunModels::Parameters(const std::vector<double>& design_values) const {
  GESWEEP_DEMAND(design_values.size() == design_ids_.size());
  RunParameters parameters = base_;
  for (std::size_t i = 0; i < design_ids_.size(); ++i) {
    parameters[static_cast<std::size_t>(design_ids_[i])] = design_values[i];
  }
  return parameters;
}

const LongitudinalModel& ArchiveRunModels::Model(const RunParameters& parameters) {
  workspace_->parameters = parameters;
  return workspace_->Model(*plan_);
}

}  // namespace gesweep
