#pragma once
/// Sobol' sensitivity indices of one scalar output from the outputs of a Saltelli design
/// (docs/sensitivity.md): first order by the Saltelli et al. (2010) estimator, total by Jansen's
/// (1999), second order by Saltelli's (2002), percentile bootstrap intervals over the base samples.

#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

#include "engine/estimators/saltelli_layout.h"
#include "engine/estimators/sensitivity_common.h"

namespace gesweep {

/// How to analyse.
struct SobolOptions {
  FailedRunPolicy failed_runs = FailedRunPolicy::kDropBlocks;
  BootstrapOptions bootstrap;
  /// Names the input in error messages (an archive path, a study file).
  std::string source = "sensitivity";
};

/// Indices of every parameter, in the order of the design's columns. NaN when status is not kOk.
struct SobolIndices {
  SensitivityStatus status = SensitivityStatus::kOk;
  std::string message;  ///< empty when kOk

  SaltelliLayout layout;       ///< D, N and second order as analysed
  int blocks_used = 0;         ///< base samples that entered the estimates
  int blocks_dropped = 0;      ///< blocks left out because they held a failed row
  int failed_rows = 0;         ///< rows that failed (not succeeded, or a non-finite output)
  double output_mean = 0;      ///< mean of the output over the A and B rows of the used blocks
  double output_variance = 0;  ///< population variance over the same rows (the estimators' V)

  std::vector<double> first_order;  ///< S_i
  std::vector<double> total;        ///< S_Ti
  std::vector<ConfidenceInterval> first_order_ci, total_ci;
  /// S_ij in (i, j) for i < j; NaN elsewhere and when the design has no second order.
  Eigen::MatrixXd second_order;
  Eigen::MatrixXd second_order_ci_lower, second_order_ci_upper;

  BootstrapOptions bootstrap;  ///< as used (resamples, level, seed)
};

/// Estimates the indices from the outputs of a Saltelli design in SaltelliLayout's row order.
/// `succeeded` (empty: every run succeeded) marks the rows whose run succeeded; a row whose run
/// failed or whose output is not finite is a failed row, and is never used. With failed rows,
/// FailedRunPolicy::kDropBlocks analyses the blocks without a failed row and reports how many were
/// dropped; kError returns status kStoppedOnFailedRuns and a message naming the first failed row.
///
/// Estimators on the used blocks (f_A = output of A_j, f_B of B_j, f_ABi of AB_j^(i), f_BAi of BA_j^(i);
/// the output centred on its mean; V the population variance of the f_A and f_B together):
///   S_i  = mean(f_B·(f_ABi − f_A)) / V                   (Saltelli et al. 2010)
///   S_Ti = mean((f_A − f_ABi)²) / (2V)                   (Jansen 1999)
///   S_ij = mean(f_BAi·f_ABj − f_A·f_B) / V − S_i − S_j   (Saltelli 2002; SALib's form)
/// Throws InputError naming options.source when outputs.size() ≠ layout.RowCount(), the layout has
/// D < 1 or N < 1, `succeeded` has the wrong length, or the bootstrap options are invalid.
SobolIndices AnalyzeSobol(std::span<const double> outputs, const std::vector<bool>& succeeded,
                          const SaltelliLayout& layout, const SobolOptions& options = {});

}  // namespace gesweep
