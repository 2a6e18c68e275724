#pragma once
/// Pieces shared by the global sensitivity estimators (docs/sensitivity.md): the range of a sampled
/// parameter, the failed-run policy, the status of an analysis and bootstrap percentile intervals.

#include <span>
#include <string>
#include <vector>

#include "engine/common/enum_names.h"

namespace gesweep {

/// The value at unit coordinate u ∈ [0, 1] of the interval [lower, upper]: lower + u·(upper − lower),
/// or, when `log_uniform`, exp(log lower + u·(log upper − log lower)). This is the one map from the unit
/// cube to the parameters' units: every sampled design of the sweep applies it (engine/sweep/design.h,
/// MapUnit), and the estimators invert it with UnitOfValue.
double ValueAtUnit(double lower, double upper, bool log_uniform, double u);
/// The unit coordinate of a value: the inverse of ValueAtUnit.
double UnitOfValue(double lower, double upper, bool log_uniform, double value);

/// One sampled parameter as the estimators see it: its name and the interval it is sampled on, in its
/// own unit; uniform in the value, or in its logarithm (the sweep's `distribution = "loguniform"`).
struct ParameterRange {
  std::string name;
  double lower = 0;
  double upper = 1;
  bool log_uniform = false;  ///< uniform in log(value); needs 0 < lower

  /// The unit coordinate of a value (UnitOfValue).
  double ToUnit(double value) const { return UnitOfValue(lower, upper, log_uniform, value); }
};

/// Throws InputError naming `source` unless there is at least one range, every bound is finite,
/// lower < upper (and 0 < lower when log-uniform), and the names are non-empty and distinct.
void ValidateRanges(const std::vector<ParameterRange>& ranges, const std::string& source);

/// What an estimator does when the output of a run is missing (docs/sensitivity.md, "Failed runs").
enum class FailedRunPolicy {
  kDropBlocks,  ///< drop every Saltelli block (Morris trajectory) that holds a failed row; report how many
  kError,       ///< stop: no indices, status kStoppedOnFailedRuns and a message naming the first failure
};
GESWEEP_ENUM_NAMES(FailedRunPolicy, {kDropBlocks, "drop_blocks"}, {kError, "error"});

/// Outcome of an analysis. Anything but kOk leaves the indices NaN and says why in `message`; the
/// CLI prints the message and exits with code 3 (runs failed) or 1 (degenerate output).
enum class SensitivityStatus {
  kOk,
  kStoppedOnFailedRuns,  ///< failed rows and FailedRunPolicy::kError
  kTooFewBlocks,         ///< fewer than two usable blocks (trajectories) remain
  kZeroVariance,         ///< the output does not vary over the usable rows
};
GESWEEP_ENUM_NAMES(SensitivityStatus, {kOk, "ok"}, {kStoppedOnFailedRuns, "stopped_on_failed_runs"},
                   {kTooFewBlocks, "too_few_blocks"}, {kZeroVariance, "zero_variance"});

/// A two-sided interval [lower, upper]; NaN when not computed.
struct ConfidenceInterval {
  double lower = 0;
  double upper = 0;
  bool Contains(double value) const { return lower <= value && value <= upper; }
};

/// Settings common to the bootstrap of every estimator.
struct BootstrapOptions {
  /// Number of resamples (with replacement, of whole blocks or trajectories); 0: no intervals.
  int resamples = 1000;
  /// Two-sided level of the percentile interval, in (0, 1).
  double confidence_level = 0.95;
  /// Seed of the Boost.Random mt19937_64 that draws the resamples: same seed, same intervals.
  unsigned long long seed = 20240607;
};

/// The percentile bootstrap interval of level `confidence_level` from the resampled statistics: the
/// (1−c)/2 and (1+c)/2 sample quantiles with linear interpolation between order statistics
/// (Hyndman–Fan type 7, numpy's default). Non-finite values are left out; NaN interval when fewer
/// than two finite values remain. Precondition: 0 < confidence_level < 1.
ConfidenceInterval PercentileInterval(std::vector<double> statistics, double confidence_level);

/// Throws InputError (source `source`, keys `bootstrap` / `confidence_level`) unless resamples ≥ 0
/// and 0 < confidence_level < 1.
void ValidateBootstrapOptions(const BootstrapOptions& options, const std::string& source);

/// Row r failed when `succeeded` is non-empty and says false, or when the output is not finite.
/// Precondition: `succeeded` is empty or as long as `outputs`.
std::vector<bool> FailedRows(std::span<const double> outputs, const std::vector<bool>& succeeded);

}  // namespace gesweep
