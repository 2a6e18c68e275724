#pragma once
/// Independent repetitions of a subset simulation, pooled (docs/dispersion.md, "Independent
/// repetitions"). A subset simulation's stated coefficient of variation sees the correlation within
/// a level's chains but not between levels, nor the collapse of the chains onto a few families of
/// the first level's samples; on the landing it can understate the error by far. K runs with
/// independent seeds measure it instead: their mean is the estimate, the spread of the K estimates
/// its error.
///
///   P̄ = (1/K) Σ_r P_r,     s² = Σ_r (P_r − P̄)² / (K − 1),
///   measured CoV of one run  c₁ = s / P̄,    CoV of the mean  c = c₁ / √K,
///   95 % interval: lognormal with CoV c and Student's t quantile of K − 1 degrees of freedom in
///   place of 1.96: exp(ln P̄ − σ²/2 ∓ t σ), σ² = ln(1 + c²).
/// With K = 1 the pooled estimate is the run's own (its stated CoV and interval).

#include <cstdint>
#include <span>

#include "engine/rare/subset_simulation.h"

namespace gesweep::rare {

struct PooledEstimate {
  int repetitions = 0;  ///< K
  /// The worst of the runs' statuses (too many failed evaluations, then the level cap, then
  /// converged): a pooled figure is only as good as its worst run.
  SubsetResult::Status status = SubsetResult::Status::kConverged;
  double probability = 0;  ///< P̄ (NaN when a run has none)
  /// c: the measured CoV of P̄ for K >= 2; the run's stated CoV for K = 1.
  double coefficient_of_variation = 0;
  /// c₁ = s / P̄, the spread of one run measured across the K (NaN for K = 1).
  double measured_coefficient_of_variation_one_run = 0;
  /// The mean over the runs of their stated CoVs (√Σδ_j²): what one run says of itself; its ratio to
  /// c₁ is the check of the stated figure.
  double mean_stated_coefficient_of_variation = 0;
  double interval_95_low = 0, interval_95_high = 0;
  double upper_bound = 0;  ///< under kLevelCap: the largest of the capped runs' bounds
  std::int64_t evaluations = 0, failed_evaluations = 0;
};

/// Pools K >= 1 results (of the same event, with independent seeds). GESWEEP_DEMANDs K >= 1.
PooledEstimate PoolRepetitions(std::span<const SubsetResult> runs);

/// The two-sided 95 % quantile of Student's t with `degrees_of_freedom` >= 1 (12.706 for 1, 1.960
/// in the limit).
double StudentT975(int degrees_of_freedom);

}  // namespace gesweep::rare
