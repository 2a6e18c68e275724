#pragma once
/// Morris elementary effects of one scalar output (Morris 1991; μ* of Campolongo et al. 2007):
/// μ, μ* and σ per parameter from r trajectories of D+1 consecutive design rows (docs/sensitivity.md).

#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

#include "engine/estimators/sensitivity_common.h"

namespace gesweep {

/// How to analyse.
struct MorrisOptions {
  /// A trajectory that holds a failed row is dropped whole (kDropBlocks) or stops the analysis.
  FailedRunPolicy failed_runs = FailedRunPolicy::kDropBlocks;
  /// Bootstrap over trajectories for the interval of μ*.
  BootstrapOptions bootstrap;
  /// Two consecutive rows "change" a parameter when they differ by more than this fraction of its
  /// range: far below a grid step (Δ > 1/2 of the range for any even p), far above the rounding of
  /// the affine map from the unit interval to the range.
  double change_tolerance = 1e-9;
  /// Names the input in error messages.
  std::string source = "sensitivity";
};

/// Statistics of the elementary effects, in the order of the design's columns; NaN when status is
/// not kOk. An elementary effect is EE = (y(x + Δ e_i) − y(x)) / Δ with Δ the signed step of the unit
/// coordinate (ParameterRange::ToUnit: a fraction of the range, or of the log-range), so EE is in
/// output units per full range of the parameter.
struct MorrisIndices {
  SensitivityStatus status = SensitivityStatus::kOk;
  std::string message;

  int parameter_count = 0;  ///< D
  int trajectories = 0;     ///< r in the design
  int trajectories_used = 0;
  int trajectories_dropped = 0;  ///< held a failed row
  int failed_rows = 0;

  std::vector<double> mu;       ///< mean of EE_i
  std::vector<double> mu_star;  ///< mean of |EE_i|
  std::vector<double> sigma;    ///< sample standard deviation of EE_i (n−1; NaN with one effect)
  std::vector<int> effects;     ///< number of elementary effects of each parameter
  std::vector<ConfidenceInterval> mu_star_ci;  ///< percentile bootstrap over trajectories

  BootstrapOptions bootstrap;
};

/// Elementary-effect statistics from a design of r trajectories (rows t(D+1) … t(D+1)+D for
/// trajectory t) and its outputs. Which parameter changes between consecutive rows, and by how much,
/// is read from the design and scaled by each parameter's range, so any one-at-a-time trajectory
/// design works (the sweep's `morris` design, SALib's, a radial one). `succeeded` as for AnalyzeSobol.
/// Throws InputError naming options.source when: the design has a column count ≠ ranges.size() or a
/// row count not a multiple of D+1, outputs/succeeded have the wrong length, a step changes no
/// parameter or more than one, or the ranges or bootstrap options are invalid.
MorrisIndices AnalyzeMorris(const Eigen::MatrixXd& design, std::span<const double> outputs,
                            const std::vector<bool>& succeeded, const std::vector<ParameterRange>& ranges,
                            const MorrisOptions& options = {});

}  // namespace gesweep
