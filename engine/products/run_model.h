#pragma once
/// The model of any run of an archive, rebuilt the way the sweep built it (docs/report.md,
/// "gesweep boundary --archive"):
///  - the aircraft from the archive's own copy of the aircraft file (root attribute aircraft_text),
///    not from the file on disk, which may have changed since;
///  - the run's parameters: the catalogue defaults for that aircraft, then the values every run had
///    of the parameters the design does not sweep (design attributes unswept_parameter_names/values),
///    then the run's design values;
///  - the model by the runner's own RunWorkspace::Model (engine/sweep/runner.h), so the mapping from
///    run parameters to ModelOptions exists once, in the runner.

#include <memory>
#include <string>
#include <vector>

#include "engine/aircraft/aircraft.h"
#include "engine/analyses/analysis.h"
#include "engine/analyses/parameter_catalog.h"
#include "engine/dynamics/longitudinal_model.h"

namespace gesweep {

class ArchiveReader;
class SweepPlan;
class RunWorkspace;

/// Rebuilds run models of one archive.
class ArchiveRunModels {
 public:
  /// Reads the aircraft text and the unswept parameter values of `archive`. Throws InputError
  /// (source the archive) when the archive has no aircraft (a study without one) or its aircraft
  /// text does not load, or a recorded parameter is unknown to this engine.
  static ArchiveRunModels Of(const ArchiveReader& archive);

  ArchiveRunModels(ArchiveRunModels&&) noexcept;
  ArchiveRunModels& operator=(ArchiveRunModels&&) noexcept;
  ~ArchiveRunModels();

  const Aircraft& aircraft() const;
  /// The design parameters, in the archive's design column order.
  const std::vector<ParameterId>& design_parameters() const { return design_ids_; }
  /// The full parameter vector of a run whose design values are `design_values` (one per design
  /// parameter, in design_parameters() order).
  RunParameters Parameters(const std::vector<double>& design_values) const;
  /// The run's model. Reused while the model parameters do not change (the runner's cache).
  /// The reference stays valid until the next call.
  const LongitudinalModel& Model(const RunParameters& parameters);

 private:
  ArchiveRunModels();
  std::unique_ptr<SweepPlan> plan_;
  std::unique_ptr<RunWorkspace> workspace_;
  RunParameters base_;
  std::vector<ParameterId> design_ids_;
};

}  // namespace gesweep
