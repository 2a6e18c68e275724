#include "engine/estimators/sobol_indices.h"

#include <algorithm>
#include <boost/random/mersenne_twister.hpp>
#include <boost/random/uniform_int_distribution.hpp>
#include <cmath>
#include <limits>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The outputs of the used blocks, standardised: column 0 f_A, 1..D f_AB, D+1..2D f_BA, last f_B.
struct BlockOutputs {
  int parameter_count = 0;
  bool second_order = false;
  Eigen::ArrayXd a, b;
  Eigen::ArrayXXd ab, ba;  // blocks × D
};

struct Estimates {
  std::vector<double> first_order, total;
  Eigen::MatrixXd second_order;
};

/// The three estimators over the blocks `pick(0..n−1)` (all blocks, or one bootstrap resample).
template <typename Pick>
Estimates Estimate(const BlockOutputs& data, int n, Pick pick) {
  const int D = data.parameter_count;
  double sum = 0, sum_squares = 0;
  Eigen::ArrayXd first_sum = Eigen::ArrayXd::Zero(D), total_sum = Eigen::ArrayXd::Zero(D);
  Eigen::ArrayXXd second_sum = Eigen::ArrayXXd::Zero(D, D);
  double ab_product_sum = 0;
  for (int k = 0; k < n; ++k) {
    const int j = pick(k);
    const double fa = data.a[j], fb = data.b[j];
    sum += fa + fb;
    sum_squares += fa * fa + fb * fb;
    for (int i = 0; i < D; ++i) {
      const double fab = data.ab(j, i);
      first_sum[i] += fb * (fab - fa);
      total_sum[i] += (fa - fab) * (fa - fab);
    }
    if (data.second_order) {
      ab_product_sum += fa * fb;
      for (int i = 0; i < D; ++i) {
        for (int m = i + 1; m < D; ++m) second_sum(i, m) += data.ba(j, i) * data.ab(j, m);
      }
    }
  }
  const double mean = sum / (2.0 * n);
  const double variance = sum_squares / (2.0 * n) - mean * mean;
  Estimates e;
  e.first_order.resize(D);
  e.total.resize(D);
  for (int i = 0; i < D; ++i) {
    e.first_order[i] = first_sum[i] / n / variance;
    e.total[i] = 0.5 * total_sum[i] / n / variance;
  }
  e.second_order = Eigen::MatrixXd::Constant(D, D, kNaN);
  if (data.second_order) {
    for (int i = 0; i < D; ++i) {
      for (int m = i + 1; m < D; ++m) {
        const double closed = (second_sum(i, m) - ab_product_sum) / n / variance;
        e.second_order(i, m) = closed - e.first_order[i] - e.first_order[m];
      }
    }
  }
  return e;
}

void FillNaN(SobolIndices& result) {
  const int D = result.layout.parameter_count;
  result.first_order.assign(D, kNaN);
  result.total.assign(D, kNaN);
  result.first_order_ci.assign(D, {kNaN, kNaN});
  result.total_ci.assign(D, {kNaN, kNaN});
  result.second_order = Eigen::MatrixXd::Constant(D, D, kNaN);
  result.second_order_ci_lower = result.second_order;
  result.second_order_ci_upper = result.second_order;
}

// The layout is a Saltelli design's and the outputs and flags have one entry per its row. Throws
// InputError.
void CheckSobolShapes(std::span<const double> outputs, const std::vector<bool>& succeeded,
                      const SaltelliLayout& layout, const SobolOptions& options) {
  if (layout.parameter_count < 1 || layout.base_samples < 1) {
    throw InputError(
        options.source, "design",
        "D = " + std::to_string(layout.parameter_count) + ", N = " + std::to_string(layout.base_samples),
        "expected a Saltelli design with D >= 1 parameters and N >= 1 base samples");
  }
  if (outputs.size() != layout.RowCount()) {
    throw InputError(options.source, "outputs", std::to_string(outputs.size()) + " rows",
                     "expected N·(" + std::string(layout.second_order ? "2D+2" : "D+2") +
                         ") = " + std::to_string(layout.RowCount()) +
                         " rows for D = " + std::to_string(layout.parameter_count) +
                         ", N = " + std::to_string(layout.base_samples) +
                         (layout.second_order ? " with" : " without") + " second order");
  }
  if (!succeeded.empty() && succeeded.size() != outputs.size()) {
    throw InputError(options.source, "succeeded", std::to_string(succeeded.size()) + " flags",
                     "expected one flag per output row (" + std::to_string(outputs.size()) + ")");
  }
}

// The blocks without a failed run; counts the failed rows in result.failed_rows and sets
// `first_failed` to the first (outputs.size() when none).
std::vector<int> CompleteBlocks(const std::vector<bool>& failed, const SaltelliLayout& layout,
                                SobolIndices& result, std::size_t& first_failed) {
  std::vector<int> used_blocks;
  for (int j = 0; j < layout.base_samples; ++j) {
    bool block_ok = true;
    for (std::size_t r = layout.RowA(j); r <= layout.RowB(j); ++r) {
      if (!failed[r]) continue;
      ++result.failed_rows;
      block_ok = false;
      first_failed = std::min(first_failed, r);
    }
    if (block_ok) used_blocks.push_back(j);
  }
  return used_blocks;
}

// The outputs of the used blocks, as given (not yet standardised).
BlockOutputs GatherBlocks(std::span<const double> outputs, const SaltelliLayout& layout,
                          const std::vector<int>& used_blocks) {
  const int D = layout.parameter_count;
  const int n = static_cast<int>(used_blocks.size());
  BlockOutputs data;
  data.parameter_count = D;
  data.second_order = layout.second_order;
  data.a.resize(n);
  data.b.resize(n);
  data.ab.resize(n, D);
  if (layout.second_order) data.ba.resize(n, D);
  for (int k = 0; k < n; ++k) {
    const int j = used_blocks[k];
    data.a[k] = outputs[layout.RowA(j)];
    data.b[k] = outputs[layout.RowB(j)];
    for (int i = 0; i < D; ++i) {
      data.ab(k, i) = outputs[layout.RowAB(j, i)];
      if (layout.second_order) data.ba(k, i) = outputs[layout.RowBA(j, i)];
    }
  }
  return data;
}

// The bootstrap intervals of the indices: the n blocks resampled with replacement,
// options.bootstrap.resamples times.
void BootstrapIntervals(const BlockOutputs& data, int n, const SobolOptions& options, SobolIndices& result) {
  const int D = data.parameter_count;
  std::vector<std::vector<double>> first(D), total(D);
  std::vector<std::vector<std::vector<double>>> second(D, std::vector<std::vector<double>>(D));
  boost::random::mt19937_64 engine(options.bootstrap.seed);
  boost::random::uniform_int_distribution<int> draw(0, n - 1);
  std::vector<int> sample(n);
  for (int s = 0; s < options.bootstrap.resamples; ++s) {
    for (int& k : sample) k = draw(engine);
    const Estimates e = Estimate(data, n, [&sample](int k) { return sample[k]; });
    for (int i = 0; i < D; ++i) {
      first[i].push_back(e.first_order[i]);
      total[i].push_back(e.total[i]);
      for (int m = i + 1; m < D && data.second_order; ++m) second[i][m].push_back(e.second_order(i, m));
    }
  }
  const double level = options.bootstrap.confidence_level;
  for (int i = 0; i < D; ++i) {
    result.first_order_ci[i] = PercentileInterval(std::move(first[i]), level);
    result.total_ci[i] = PercentileInterval(std::move(total[i]), level);
    for (int m = i + 1; m < D && data.second_order; ++m) {
      const ConfidenceInterval ci = PercentileInterval(std::move(second[i][m]), level);
      result.second_order_ci_lower(i, m) = ci.lower;
      result.second_order_ci_upper(i, m) = ci.upper;
    }
  }
}

}  // namespace

SobolIndices AnalyzeSobol(std::span<const double> outputs, const std::vector<bool>& succeeded,
                          const SaltelliLayout& layout, const SobolOptions& options) {
  CheckSobolShapes(outputs, succeeded, layout, options);
  ValidateBootstrapOptions(options.bootstrap, options.source);

  SobolIndices result;
  result.layout = layout;
  result.bootstrap = options.bootstrap;
  FillNaN(result);
  const int N = layout.base_samples;

  const std::vector<bool> failed = FailedRows(outputs, succeeded);
  std::size_t first_failed = outputs.size();
  const std::vector<int> used_blocks = CompleteBlocks(failed, layout, result, first_failed);
  result.blocks_used = static_cast<int>(used_blocks.size());
  result.blocks_dropped = N - result.blocks_used;

  if (result.failed_rows > 0 && options.failed_runs == FailedRunPolicy::kError) {
    result.status = SensitivityStatus::kStoppedOnFailedRuns;
    result.blocks_used = 0;
    result.blocks_dropped = 0;
    result.message = std::to_string(result.failed_rows) + " of " + std::to_string(outputs.size()) +
                     " runs failed (first: row " + std::to_string(first_failed) + ", base sample " +
                     std::to_string(layout.BlockOfRow(first_failed)) +
                     "); rerun them, or choose failed_runs = drop_blocks to drop the " +
                     std::to_string(N - static_cast<int>(used_blocks.size())) +
                     " Saltelli blocks that hold them";
    return result;
  }
  if (result.blocks_used < 2) {
    result.status = SensitivityStatus::kTooFewBlocks;
    result.message = std::to_string(result.blocks_used) + " of " + std::to_string(N) +
                     " Saltelli blocks are free of failed runs; at least 2 are needed";
    return result;
  }

  const int n = result.blocks_used;
  BlockOutputs data = GatherBlocks(outputs, layout, used_blocks);
  // Standardise (as SALib does): the estimators are ratios, invariant to the scale, but the first-
  // and second-order numerators are not invariant to a shift in a finite sample, and centring keeps
  // their variance small.
  const double mean = 0.5 * (data.a.mean() + data.b.mean());
  const double variance = 0.5 * ((data.a - mean).square().mean() + (data.b - mean).square().mean());
  result.output_mean = mean;
  result.output_variance = variance;
  if (!(variance > 0.0)) {
    result.status = SensitivityStatus::kZeroVariance;
    result.message = "the output is the same in every used run (" + ShortNumber(mean) +
                     "); its sensitivity indices are undefined";
    return result;
  }
  const double scale = 1.0 / std::sqrt(variance);
  data.a = (data.a - mean) * scale;
  data.b = (data.b - mean) * scale;
  data.ab = (data.ab - mean) * scale;
  if (layout.second_order) data.ba = (data.ba - mean) * scale;

  const Estimates point = Estimate(data, n, [](int k) { return k; });
  result.first_order = point.first_order;
  result.total = point.total;
  result.second_order = point.second_order;

  if (options.bootstrap.resamples == 0) return result;
  BootstrapIntervals(data, n, options, result);
  return result;
}

}  // namespace gesweep
