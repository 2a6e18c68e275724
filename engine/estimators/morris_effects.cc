#include "engine/estimators/morris_effects.h"

#include <algorithm>
#include <boost/random/mersenne_twister.hpp>
#include <boost/random/uniform_int_distribution.hpp>
#include <cmath>
#include <limits>

#include "engine/common/errors.h"

namespace gesweep {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// One elementary effect: the parameter that moved and the effect.
struct Effect {
  int parameter = 0;
  double value = 0;
};

// The design, outputs and flags agree with D parameters: D columns, whole trajectories of D + 1 rows,
// one output (and one flag, if any) per row. Throws InputError.
void CheckMorrisShapes(const Eigen::MatrixXd& design, std::span<const double> outputs,
                       const std::vector<bool>& succeeded, int D, const MorrisOptions& options) {
  if (design.cols() != D) {
    throw InputError(options.source, "design", std::to_string(design.cols()) + " columns",
                     "expected one column per parameter (" + std::to_string(D) + ")");
  }
  if (design.rows() == 0 || design.rows() % (D + 1) != 0) {
    throw InputError(
        options.source, "design", std::to_string(design.rows()) + " rows",
        "expected r·(D+1) rows: whole Morris trajectories of " + std::to_string(D + 1) + " rows");
  }
  if (outputs.size() != static_cast<std::size_t>(design.rows())) {
    throw InputError(options.source, "outputs", std::to_string(outputs.size()) + " rows",
                     "expected one output per design row (" + std::to_string(design.rows()) + ")");
  }
  if (!succeeded.empty() && succeeded.size() != outputs.size()) {
    throw InputError(options.source, "succeeded", std::to_string(succeeded.size()) + " flags",
                     "expected one flag per output row (" + std::to_string(outputs.size()) + ")");
  }
}

// Each trajectory's steps: the parameter that moves between consecutive rows and its step in unit
// coordinates. Throws InputError when a step moves other than exactly one parameter.
std::vector<std::vector<Effect>> MorrisSteps(const Eigen::MatrixXd& design,
                                             const std::vector<ParameterRange>& ranges, int trajectories,
                                             const MorrisOptions& options) {
  const int D = static_cast<int>(ranges.size());
  std::vector<std::vector<Effect>> steps(trajectories);
  for (int t = 0; t < trajectories; ++t) {
    for (int k = 0; k < D; ++k) {
      const Eigen::Index row = static_cast<Eigen::Index>(t) * (D + 1) + k;
      int changed = -1, changed_count = 0;
      double unit_step = 0;
      for (int i = 0; i < D; ++i) {
        const double step = ranges[i].ToUnit(design(row + 1, i)) - ranges[i].ToUnit(design(row, i));
        if (std::abs(step) > options.change_tolerance) {
          changed = i;
          unit_step = step;
          ++changed_count;
        }
      }
      if (changed_count != 1) {
        throw InputError(
            options.source, "design rows " + std::to_string(row) + " to " + std::to_string(row + 1),
            std::to_string(changed_count) + " parameters change",
            "expected exactly one parameter to change between consecutive rows of a Morris trajectory");
      }
      steps[t].push_back({changed, unit_step});
    }
  }
  return steps;
}

// The trajectories without a failed run; counts the failed rows in result.failed_rows and sets
// `first_failed` to the first (outputs.size() when none).
std::vector<int> CompleteTrajectories(const std::vector<bool>& failed, int D, MorrisIndices& result,
                                      std::size_t& first_failed) {
  std::vector<int> used;
  for (int t = 0; t < result.trajectories; ++t) {
    bool ok = true;
    for (int k = 0; k <= D; ++k) {
      const std::size_t row = static_cast<std::size_t>(t) * (D + 1) + k;
      if (!failed[row]) continue;
      ok = false;
      ++result.failed_rows;
      first_failed = std::min(first_failed, row);
    }
    if (ok) used.push_back(t);
  }
  return used;
}

// The mean, mean absolute value, standard deviation and count of each parameter's elementary effects.
struct Moments {
  std::vector<double> mu, mu_star, sigma;
  std::vector<int> count;
};

// The moments of the effects of `trajectories` (a trajectory may repeat).
Moments MorrisMoments(const std::vector<std::vector<Effect>>& effects, const std::vector<int>& trajectories,
                      int D) {
  Moments m{std::vector<double>(D, 0.0), std::vector<double>(D, 0.0), std::vector<double>(D, kNaN),
            std::vector<int>(D, 0)};
  for (int t : trajectories) {
    for (const Effect& e : effects[t]) {
      m.mu[e.parameter] += e.value;
      m.mu_star[e.parameter] += std::abs(e.value);
      ++m.count[e.parameter];
    }
  }
  for (int i = 0; i < D; ++i) {
    if (m.count[i] == 0) {
      m.mu[i] = m.mu_star[i] = kNaN;
      continue;
    }
    m.mu[i] /= m.count[i];
    m.mu_star[i] /= m.count[i];
  }
  std::vector<double> squares(D, 0.0);
  for (int t : trajectories) {
    for (const Effect& e : effects[t])
      squares[e.parameter] += (e.value - m.mu[e.parameter]) * (e.value - m.mu[e.parameter]);
  }
  for (int i = 0; i < D; ++i) {
    if (m.count[i] >= 2) m.sigma[i] = std::sqrt(squares[i] / (m.count[i] - 1));
  }
  return m;
}

// The bootstrap interval of each μ*: `used` resampled with replacement, options.bootstrap.resamples times.
void BootstrapMuStar(const std::vector<std::vector<Effect>>& effects, const std::vector<int>& used, int D,
                     const MorrisOptions& options, MorrisIndices& result) {
  boost::random::mt19937_64 engine(options.bootstrap.seed);
  boost::random::uniform_int_distribution<std::size_t> draw(0, used.size() - 1);
  std::vector<std::vector<double>> mu_star(D);
  std::vector<int> sample(used.size());
  for (int s = 0; s < options.bootstrap.resamples; ++s) {
    for (int& t : sample) t = used[draw(engine)];
    const Moments m = MorrisMoments(effects, sample, D);
    for (int i = 0; i < D; ++i) mu_star[i].push_back(m.mu_star[i]);
  }
  for (int i = 0; i < D; ++i) {
    result.mu_star_ci[i] = PercentileInterval(std::move(mu_star[i]), options.bootstrap.confidence_level);
  }
}

}  // namespace

MorrisIndices AnalyzeMorris(const Eigen::MatrixXd& design, std::span<const double> outputs,
                            const std::vector<bool>& succeeded, const std::vector<ParameterRange>& ranges,
                            const MorrisOptions& options) {
  ValidateRanges(ranges, options.source);
  ValidateBootstrapOptions(options.bootstrap, options.source);
  const int D = static_cast<int>(ranges.size());
  CheckMorrisShapes(design, outputs, succeeded, D, options);

  MorrisIndices result;
  result.parameter_count = D;
  result.trajectories = static_cast<int>(design.rows() / (D + 1));
  result.bootstrap = options.bootstrap;
  result.mu.assign(D, kNaN);
  result.mu_star.assign(D, kNaN);
  result.sigma.assign(D, kNaN);
  result.effects.assign(D, 0);
  result.mu_star_ci.assign(D, {kNaN, kNaN});

  // The steps come from the design whatever the outputs, so a malformed design is reported even
  // when every run failed.
  const std::vector<std::vector<Effect>> steps = MorrisSteps(design, ranges, result.trajectories, options);

  const std::vector<bool> failed = FailedRows(outputs, succeeded);
  std::size_t first_failed = outputs.size();
  const std::vector<int> used = CompleteTrajectories(failed, D, result, first_failed);
  if (result.failed_rows > 0 && options.failed_runs == FailedRunPolicy::kError) {
    result.status = SensitivityStatus::kStoppedOnFailedRuns;
    result.message = std::to_string(result.failed_rows) + " of " + std::to_string(outputs.size()) +
                     " runs failed (first: row " + std::to_string(first_failed) + ", trajectory " +
                     std::to_string(first_failed / (D + 1)) +
                     "); rerun them, or choose failed_runs = drop_blocks to drop the " +
                     std::to_string(result.trajectories - static_cast<int>(used.size())) +
                     " trajectories that hold them";
    return result;
  }
  result.trajectories_used = static_cast<int>(used.size());
  result.trajectories_dropped = result.trajectories - result.trajectories_used;
  if (result.trajectories_used < 1) {
    result.status = SensitivityStatus::kTooFewBlocks;
    result.message = "every Morris trajectory holds a failed run";
    return result;
  }

  // effects[t] holds the elementary effects of trajectory t (those of used trajectories only).
  std::vector<std::vector<Effect>> effects(result.trajectories);
  for (int t : used) {
    for (int k = 0; k < D; ++k) {
      const std::size_t row = static_cast<std::size_t>(t) * (D + 1) + k;
      const Effect& step = steps[t][k];
      effects[t].push_back({step.parameter, (outputs[row + 1] - outputs[row]) / step.value});
    }
  }

  const Moments point = MorrisMoments(effects, used, D);
  result.mu = point.mu;
  result.mu_star = point.mu_star;
  result.sigma = point.sigma;
  result.effects = point.count;

  if (options.bootstrap.resamples == 0) return result;
  BootstrapMuStar(effects, used, D, options, result);
  return result;
}

}  // namespace gesweep
