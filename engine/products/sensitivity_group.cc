#include "engine/products/sensitivity_group.h"

#include <cstring>
#include <limits>

#include "engine/archive/analysis_product.h"
#include "engine/archive/archive_format.h"
#include "engine/archive/provenance.h"
#include "engine/common/errors.h"

namespace gesweep {
namespace {

constexpr const char* kSensitivityGroup = "analysis/sensitivity";

// Estimator names as recorded (docs/sensitivity.md, "Sobol' indices" and "Morris elementary effects").
constexpr const char* kFirstOrderEstimator =
    "Saltelli et al. (2010), Table 2 (b): S_i = mean(f_B (f_ABi - f_A)) / V";
constexpr const char* kTotalEstimator = "Jansen (1999): S_Ti = mean((f_A - f_ABi)^2) / (2V)";
constexpr const char* kSecondOrderEstimator =
    "Saltelli (2002), SALib's form: S_ij = mean(f_BAi f_ABj - f_A f_B) / V - S_i - S_j";
constexpr const char* kMorrisEstimator =
    "Morris (1991) elementary effects EE = dy / (signed unit step); mu = mean EE, mu_star = mean |EE| "
    "(Campolongo et al. 2007), sigma = sample standard deviation (n - 1)";

void WriteDoubles(ProductGroup& group, const std::string& name, const std::vector<std::size_t>& dims,
                  const std::vector<double>& values, const std::string& units,
                  const std::string& description) {
  group.Numbers(name, values, units, description, dims);
}

void WriteCounts(ProductGroup& group, const std::string& name, const std::vector<int>& counts,
                 const std::string& description) {
  const std::vector<std::int64_t> values(counts.begin(), counts.end());
  group.Numbers(name, values, "1", description);
}

void WriteVector(ProductGroup& group, const std::string& name, const std::vector<double>& values,
                 const std::string& units, const std::string& description) {
  group.Numbers(name, values, units, description);
}

// D × 2 (lower, upper) intervals.
void WriteIntervals(ProductGroup& group, const std::string& name,
                    const std::vector<ConfidenceInterval>& intervals, const std::string& units,
                    const std::string& description) {
  std::vector<double> values;
  for (const auto& ci : intervals) {
    values.push_back(ci.lower);
    values.push_back(ci.upper);
  }
  WriteDoubles(group, name, {intervals.size(), 2}, values, units, description);
}

void WriteSobol(ProductGroup& group, const ArchiveSensitivity& result, const std::string& level) {
  const SobolIndices& s = result.sobol;
  const auto D = static_cast<std::size_t>(s.layout.parameter_count);
  group.Attribute("base_samples", static_cast<std::int64_t>(s.layout.base_samples));
  group.Attribute("dimension", static_cast<std::int64_t>(s.layout.parameter_count));
  group.Attribute("second_order", static_cast<std::int64_t>(s.layout.second_order ? 1 : 0));
  group.Attribute("estimator_first_order", kFirstOrderEstimator);
  group.Attribute("estimator_total", kTotalEstimator);
  if (s.layout.second_order) group.Attribute("estimator_second_order", kSecondOrderEstimator);
  group.Attribute("blocks_used", static_cast<std::int64_t>(s.blocks_used));
  group.Attribute("blocks_dropped", static_cast<std::int64_t>(s.blocks_dropped));
  group.Attribute("bootstrap_unit", "base samples (whole Saltelli blocks), with replacement");
  group.Attribute("output_mean", s.output_mean);
  group.Attribute("output_variance", s.output_variance);

  WriteVector(group, "first_order", s.first_order, "1", "First-order Sobol' index S_i of each parameter");
  WriteIntervals(group, "first_order_ci", s.first_order_ci, "1",
                 level + " bootstrap percentile interval of S_i: columns lower, upper");
  WriteVector(group, "total", s.total, "1", "Total Sobol' index S_Ti of each parameter");
  WriteIntervals(group, "total_ci", s.total_ci, "1",
                 level + " bootstrap percentile interval of S_Ti: columns lower, upper");
  if (!s.layout.second_order) return;
  // Row-major D × D (Eigen is column-major): element (i, j), i < j, is S_ij; NaN elsewhere.
  std::vector<double> second, interval;
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(D); ++i) {
    for (Eigen::Index j = 0; j < static_cast<Eigen::Index>(D); ++j) {
      second.push_back(s.second_order(i, j));
      interval.push_back(s.second_order_ci_lower(i, j));
      interval.push_back(s.second_order_ci_upper(i, j));
    }
  }
  WriteDoubles(group, "second_order", {D, D}, second, "1",
               "Second-order Sobol' index S_ij at (i, j) for i < j (parameters in the order of the attribute "
               "parameters); NaN on and below the diagonal");
  WriteDoubles(group, "second_order_ci", {D, D, 2}, interval, "1",
               level + " bootstrap percentile interval of S_ij: [i, j, 0] lower, [i, j, 1] upper");
}

void WriteMorris(ProductGroup& group, const ArchiveSensitivity& result, const std::string& level) {
  const MorrisIndices& m = result.morris;
  const std::string units = result.output.units + " per full range of the parameter";
  group.Attribute("trajectories", static_cast<std::int64_t>(m.trajectories));
  group.Attribute("dimension", static_cast<std::int64_t>(m.parameter_count));
  group.Attribute("levels", static_cast<std::int64_t>(result.morris_levels));
  group.Attribute("delta", result.morris_delta);
  group.Attribute("estimator", kMorrisEstimator);
  group.Attribute("trajectories_used", static_cast<std::int64_t>(m.trajectories_used));
  group.Attribute("trajectories_dropped", static_cast<std::int64_t>(m.trajectories_dropped));
  group.Attribute("blocks_used", static_cast<std::int64_t>(m.trajectories_used));
  group.Attribute("blocks_dropped", static_cast<std::int64_t>(m.trajectories_dropped));
  group.Attribute("bootstrap_unit", "trajectories, with replacement");
  WriteVector(group, "mu", m.mu, units, "Mean elementary effect mu (signed)");
  WriteVector(group, "mu_star", m.mu_star, units,
              "Mean absolute elementary effect mu* (the ranking measure)");
  WriteIntervals(group, "mu_star_ci", m.mu_star_ci, units,
                 level + " bootstrap percentile interval of mu*: columns lower, upper");
  WriteVector(group, "sigma", m.sigma, units, "Sample standard deviation of the elementary effects (n - 1)");
  WriteCounts(group, "effects", m.effects, "Number of elementary effects of each parameter that entered");
}

void WriteGroup(ProductGroup& g, const ArchiveSensitivity& result, const std::string& command_line) {
  const BootstrapOptions& bootstrap =
      result.method == SensitivityMethod::kSobol ? result.sobol.bootstrap : result.morris.bootstrap;
  const std::string level = ShortNumber(100.0 * bootstrap.confidence_level) + " %";
  g.Attribute("description",
              std::string(result.method == SensitivityMethod::kSobol ? "Sobol' indices"
                                                                     : "Morris elementary effects") +
                  " of " + result.output.path + " over the swept parameters (docs/sensitivity.md)");
  g.Attribute("method", std::string(ToString(result.method)));
  g.Attribute("output", result.output.name);
  g.Attribute("output_path", result.output.path);
  g.Attribute("output_units", result.output.units);
  g.Attribute("parameters", result.parameters);
  g.Attribute("parameter_units", result.parameter_units);
  std::vector<double> lower, upper;
  std::vector<std::string> distributions;
  for (const auto& range : result.ranges) {
    lower.push_back(range.lower);
    upper.push_back(range.upper);
    distributions.push_back(range.log_uniform ? "loguniform" : "uniform");
  }
  g.Attribute("parameter_lower", lower);
  g.Attribute("parameter_upper", upper);
  g.Attribute("parameter_distributions", distributions);
  g.Attribute("n", result.n());
  g.Attribute("run_count", result.run_count);
  g.Attribute("failed_runs", std::string(ToString(result.failed_runs)));
  g.Attribute("runs_failed", result.runs_failed);
  g.Attribute("runs_without_value", result.runs_without_value);
  g.Attribute("bootstrap_resamples", static_cast<std::int64_t>(bootstrap.resamples));
  g.Attribute("bootstrap_seed", static_cast<std::int64_t>(bootstrap.seed));
  g.Attribute("confidence_level", bootstrap.confidence_level);
  g.Attribute("engine_version", EngineVersion());
  g.Attribute("git_commit", EngineGitCommit());
  g.Attribute("created", UtcTimestamp());
  g.Attribute("command_line", command_line);
  if (result.method == SensitivityMethod::kSobol) {
    WriteSobol(g, result, level);
  } else {
    WriteMorris(g, result, level);
  }
}

}  // namespace

std::string SensitivityGroupPath(const ArchiveOutput& output) {
  return std::string(kSensitivityGroup) + "/" + output.name;
}

void WriteSensitivityGroup(const std::filesystem::path& archive, const ArchiveSensitivity& result,
                           const std::string& command_line) {
  GESWEEP_DEMAND(result.status == SensitivityStatus::kOk);
  WriteAnalysisProduct(archive, SensitivityGroupPath(result.output), "the result",
                       [&](ProductGroup& group) { WriteGroup(group, result, command_line); });
}

}  // namespace gesweep
