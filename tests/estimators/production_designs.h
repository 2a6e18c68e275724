#pragma once
// The designs the estimators' tests run on are the sweep's own (engine/sweep/design.h), built and
// enumerated as `gesweep run` does: a DesignSpec, MakeDesign, then Row(i) for every run. The
// estimators see them as `gesweep sensitivity` reads them back from an archive: the Saltelli layout
// from the design's D, N and second order; each column's range from its bounds and distribution.
// engine/sweep is a dependency of these tests only: engine/estimators itself does not know it.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "engine/analyses/parameter_catalog.h"
#include "engine/estimators/saltelli_layout.h"
#include "engine/estimators/sensitivity_common.h"
#include "engine/sweep/design.h"

namespace gesweep::production_designs {

/// A sampled column of a design: catalogue parameter `name` on [lower, upper].
inline DesignParameter Sampled(const std::string& name, double lower, double upper,
                               Distribution distribution = Distribution::kUniform) {
  DesignParameter parameter;
  parameter.id = RequireParameter(name);
  parameter.lower = lower;
  parameter.upper = upper;
  parameter.distribution = distribution;
  return parameter;
}

/// The spec of a `kind = "sobol"` design.
inline DesignSpec SobolSpec(std::vector<DesignParameter> parameters, std::int64_t base_samples,
                            bool second_order) {
  DesignSpec spec;
  spec.kind = DesignKind::kSobol;
  spec.parameters = std::move(parameters);
  spec.base_samples = base_samples;
  spec.second_order = second_order;
  return spec;
}

/// The spec of a `kind = "morris"` design.
inline DesignSpec MorrisSpec(std::vector<DesignParameter> parameters, std::int64_t trajectories, int levels,
                             std::uint64_t seed) {
  DesignSpec spec;
  spec.kind = DesignKind::kMorris;
  spec.parameters = std::move(parameters);
  spec.trajectories = trajectories;
  spec.levels = levels;
  spec.seed = seed;
  return spec;
}

/// Every row of the design, as the runner computes them: one matrix row per run, one column per
/// parameter, in the parameters' own units.
inline Eigen::MatrixXd DesignRows(const DesignSpec& spec) {
  const auto design = MakeDesign(spec);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows(design->run_count(),
                                                                              design->column_count());
  for (std::int64_t i = 0; i < design->run_count(); ++i) design->Row(i, rows.row(i).data());
  return rows;
}

/// The Saltelli layout of a sobol spec (what the archive's design attributes record).
inline SaltelliLayout LayoutOf(const DesignSpec& spec) {
  return {static_cast<int>(spec.parameters.size()), static_cast<int>(spec.base_samples), spec.second_order};
}

/// The sampled range of each column (what the archive's design datasets record).
inline std::vector<ParameterRange> RangesOf(const DesignSpec& spec) {
  std::vector<ParameterRange> ranges;
  for (const auto& p : spec.parameters) {
    ranges.push_back({ParameterCatalog()[static_cast<std::size_t>(p.id)].name, p.lower, p.upper,
                      p.distribution == Distribution::kLogUniform});
  }
  return ranges;
}

}  // namespace gesweep::production_designs
