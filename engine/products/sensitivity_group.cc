#include "engine/products/sensitivity_group.h"

#include <cstring>
#include <limits>

#include "engine/archive/analysis_product.h"
#include "engine/archive/archive_format.h"
#include "engine/archive/provenance.h"
#include "engine/common/errors.h"

namespace gesweep {
namespace {

// The group under which each output's result group lies (SensitivityProduct's path without "/<output>").
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

// The attributes of every result group, and those of each method (SensitivityProduct).
constexpr ProductField kMethod{"method", "string", "", "", "sobol or morris: what marks a result group"};
constexpr ProductField kOutput{"output", "string", "", "", "The output column's name below results/"};
constexpr ProductField kOutputPath{"output_path", "string", "", "", "Its dataset path"};
constexpr ProductField kOutputUnits{"output_units", "string", "", "", "Its units"};
constexpr ProductField kParameters{"parameters", "list of string", "", "parameter",
                                   "The swept parameters, in the order of every dataset's first axis"};
constexpr ProductField kParameterUnits{"parameter_units", "list of string", "", "parameter", "Their units"};
constexpr ProductField kParameterLower{"parameter_lower", "list of float64", "", "parameter",
                                       "Lower end of each parameter's range"};
constexpr ProductField kParameterUpper{"parameter_upper", "list of float64", "", "parameter",
                                       "Upper end of each parameter's range"};
constexpr ProductField kParameterDistributions{"parameter_distributions", "list of string", "", "parameter",
                                               "uniform or loguniform"};
constexpr ProductField kN{"n", "int64", "", "",
                          "Base samples (Sobol') or trajectories (Morris) of the design"};
constexpr ProductField kRunCount{"run_count", "int64", "", "", "Runs of the archive"};
constexpr ProductField kFailedRuns{"failed_runs", "string", "", "", "What was done with failed runs"};
constexpr ProductField kRunsFailed{"runs_failed", "int64", "", "", "Failed runs"};
constexpr ProductField kRunsWithoutValue{"runs_without_value", "int64", "", "",
                                         "Runs without a finite value"};
constexpr ProductField kBootstrapResamples{"bootstrap_resamples", "int64", "", "", "Bootstrap resamples"};
constexpr ProductField kBootstrapSeed{"bootstrap_seed", "int64", "", "", "Bootstrap seed"};
constexpr ProductField kConfidenceLevel{"confidence_level", "float64", "", "", "Level of the intervals"};
constexpr ProductField kDimension{"dimension", "int64", "", "", "D: the number of parameters"};
constexpr ProductField kBlocksUsed{"blocks_used", "int64", "", "",
                                   "Blocks (Saltelli blocks or trajectories) used"};
constexpr ProductField kBlocksDropped{"blocks_dropped", "int64", "", "",
                                      "Blocks dropped (a failed run or a missing value in them)"};
constexpr ProductField kBootstrapUnit{"bootstrap_unit", "string", "", "", "What the bootstrap resamples"};
constexpr ProductField kBaseSamples{"base_samples", "int64", "", "", "Sobol': N, the base samples"};
constexpr ProductField kSecondOrder{"second_order", "int64", "", "", "Sobol': 1 with second-order indices"};
constexpr ProductField kEstimatorFirst{"estimator_first_order", "string", "", "",
                                       "Sobol': the S_i estimator"};
constexpr ProductField kEstimatorTotal{"estimator_total", "string", "", "", "Sobol': the S_Ti estimator"};
constexpr ProductField kEstimatorSecond{"estimator_second_order", "string", "", "",
                                        "Sobol': the S_ij estimator (with second-order indices)"};
constexpr ProductField kOutputMean{"output_mean", "float64", "", "", "Sobol': mean of the output"};
constexpr ProductField kOutputVariance{"output_variance", "float64", "", "", "Sobol': its variance V"};
constexpr ProductField kTrajectories{"trajectories", "int64", "", "", "Morris: trajectories of the design"};
constexpr ProductField kMorrisLevels{"levels", "int64", "", "", "Morris: levels of the grid"};
constexpr ProductField kDelta{"delta", "float64", "", "", "Morris: the step, in units of the range"};
constexpr ProductField kEstimator{"estimator", "string", "", "", "Morris: the estimator"};
constexpr ProductField kTrajectoriesUsed{"trajectories_used", "int64", "", "", "Morris: trajectories used"};
constexpr ProductField kTrajectoriesDropped{"trajectories_dropped", "int64", "", "",
                                            "Morris: trajectories dropped"};

// The datasets of a Sobol' result (a <level> in a description is the interval's level, "95 %").
constexpr ProductField kFirstOrder{"first_order", "float64", "1", "parameter",
                                   "First-order Sobol' index S_i of each parameter"};
constexpr ProductField kFirstOrderCi{"first_order_ci", "float64", "1", "parameter, 2",
                                     "<level> bootstrap percentile interval of S_i: columns lower, upper"};
constexpr ProductField kTotal{"total", "float64", "1", "parameter",
                              "Total Sobol' index S_Ti of each parameter"};
constexpr ProductField kTotalCi{"total_ci", "float64", "1", "parameter, 2",
                                "<level> bootstrap percentile interval of S_Ti: columns lower, upper"};
constexpr ProductField kSecondOrderIndices{
    "second_order", "float64", "1", "parameter, parameter",
    "Second-order Sobol' index S_ij at (i, j) for i < j (parameters in the order of the attribute "
    "parameters); NaN on and below the diagonal"};
constexpr ProductField kSecondOrderCi{
    "second_order_ci", "float64", "1", "parameter, parameter, 2",
    "<level> bootstrap percentile interval of S_ij: [i, j, 0] lower, [i, j, 1] upper"};
// The datasets of a Morris result (<output units>: those of the output).
constexpr std::string_view kMorrisUnits = "<output units> per full range of the parameter";
constexpr ProductField kMu{"mu", "float64", kMorrisUnits, "parameter", "Mean elementary effect mu (signed)"};
constexpr ProductField kMuStar{"mu_star", "float64", kMorrisUnits, "parameter",
                               "Mean absolute elementary effect mu* (the ranking measure)"};
constexpr ProductField kMuStarCi{"mu_star_ci", "float64", kMorrisUnits, "parameter, 2",
                                 "<level> bootstrap percentile interval of mu*: columns lower, upper"};
constexpr ProductField kSigma{"sigma", "float64", kMorrisUnits, "parameter",
                              "Sample standard deviation of the elementary effects (n - 1)"};
constexpr ProductField kEffects{"effects", "int64", "1", "parameter",
                                "Number of elementary effects of each parameter that entered"};

// A float64 dataset of `field` with its <level> and <output units> filled in.
void WriteDoubles(ProductGroup& group, const ProductField& field, const std::vector<std::size_t>& dims,
                  const std::vector<double>& values, const std::string& level,
                  const std::string& output_units) {
  GESWEEP_DEMAND(field.type == "float64");
  group.Numbers(std::string(field.name), values, Filled(field.units, "<output units>", output_units),
                Filled(field.description, "<level>", level), dims);
}

void WriteCounts(ProductGroup& group, const ProductField& field, const std::vector<int>& counts) {
  const std::vector<std::int64_t> values(counts.begin(), counts.end());
  group.Numbers(field, values);
}

// D × 2 (lower, upper) intervals.
void WriteIntervals(ProductGroup& group, const ProductField& field,
                    const std::vector<ConfidenceInterval>& intervals, const std::string& level,
                    const std::string& output_units) {
  std::vector<double> values;
  for (const auto& ci : intervals) {
    values.push_back(ci.lower);
    values.push_back(ci.upper);
  }
  WriteDoubles(group, field, {intervals.size(), 2}, values, level, output_units);
}

void WriteSobol(ProductGroup& group, const ArchiveSensitivity& result, const std::string& level) {
  const SobolIndices& s = result.sobol;
  const auto D = static_cast<std::size_t>(s.layout.parameter_count);
  group.Attribute(kBaseSamples, static_cast<std::int64_t>(s.layout.base_samples));
  group.Attribute(kDimension, static_cast<std::int64_t>(s.layout.parameter_count));
  group.Attribute(kSecondOrder, static_cast<std::int64_t>(s.layout.second_order ? 1 : 0));
  group.Attribute(kEstimatorFirst, kFirstOrderEstimator);
  group.Attribute(kEstimatorTotal, kTotalEstimator);
  if (s.layout.second_order) group.Attribute(kEstimatorSecond, kSecondOrderEstimator);
  group.Attribute(kBlocksUsed, static_cast<std::int64_t>(s.blocks_used));
  group.Attribute(kBlocksDropped, static_cast<std::int64_t>(s.blocks_dropped));
  group.Attribute(kBootstrapUnit, "base samples (whole Saltelli blocks), with replacement");
  group.Attribute(kOutputMean, s.output_mean);
  group.Attribute(kOutputVariance, s.output_variance);

  WriteDoubles(group, kFirstOrder, {}, s.first_order, level, "");
  WriteIntervals(group, kFirstOrderCi, s.first_order_ci, level, "");
  WriteDoubles(group, kTotal, {}, s.total, level, "");
  WriteIntervals(group, kTotalCi, s.total_ci, level, "");
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
  WriteDoubles(group, kSecondOrderIndices, {D, D}, second, level, "");
  WriteDoubles(group, kSecondOrderCi, {D, D, 2}, interval, level, "");
}

void WriteMorris(ProductGroup& group, const ArchiveSensitivity& result, const std::string& level) {
  const MorrisIndices& m = result.morris;
  const std::string& units = result.output.units;
  group.Attribute(kTrajectories, static_cast<std::int64_t>(m.trajectories));
  group.Attribute(kDimension, static_cast<std::int64_t>(m.parameter_count));
  group.Attribute(kMorrisLevels, static_cast<std::int64_t>(result.morris_levels));
  group.Attribute(kDelta, result.morris_delta);
  group.Attribute(kEstimator, kMorrisEstimator);
  group.Attribute(kTrajectoriesUsed, static_cast<std::int64_t>(m.trajectories_used));
  group.Attribute(kTrajectoriesDropped, static_cast<std::int64_t>(m.trajectories_dropped));
  group.Attribute(kBlocksUsed, static_cast<std::int64_t>(m.trajectories_used));
  group.Attribute(kBlocksDropped, static_cast<std::int64_t>(m.trajectories_dropped));
  group.Attribute(kBootstrapUnit, "trajectories, with replacement");
  WriteDoubles(group, kMu, {}, m.mu, level, units);
  WriteDoubles(group, kMuStar, {}, m.mu_star, level, units);
  WriteIntervals(group, kMuStarCi, m.mu_star_ci, level, units);
  WriteDoubles(group, kSigma, {}, m.sigma, level, units);
  WriteCounts(group, kEffects, m.effects);
}

void WriteGroup(ProductGroup& g, const ArchiveSensitivity& result, const std::string& command_line) {
  const BootstrapOptions& bootstrap =
      result.method == SensitivityMethod::kSobol ? result.sobol.bootstrap : result.morris.bootstrap;
  const std::string level = ShortNumber(100.0 * bootstrap.confidence_level) + " %";
  g.Attribute(kProductDescription,
              std::string(result.method == SensitivityMethod::kSobol ? "Sobol' indices"
                                                                     : "Morris elementary effects") +
                  " of " + result.output.path + " over the swept parameters (docs/sensitivity.md)");
  g.Attribute(kMethod, std::string(ToString(result.method)));
  g.Attribute(kOutput, result.output.name);
  g.Attribute(kOutputPath, result.output.path);
  g.Attribute(kOutputUnits, result.output.units);
  g.Attribute(kParameters, result.parameters);
  g.Attribute(kParameterUnits, result.parameter_units);
  std::vector<double> lower, upper;
  std::vector<std::string> distributions;
  for (const auto& range : result.ranges) {
    lower.push_back(range.lower);
    upper.push_back(range.upper);
    distributions.push_back(range.log_uniform ? "loguniform" : "uniform");
  }
  g.Attribute(kParameterLower, lower);
  g.Attribute(kParameterUpper, upper);
  g.Attribute(kParameterDistributions, distributions);
  g.Attribute(kN, result.n());
  g.Attribute(kRunCount, result.run_count);
  g.Attribute(kFailedRuns, std::string(ToString(result.failed_runs)));
  g.Attribute(kRunsFailed, result.runs_failed);
  g.Attribute(kRunsWithoutValue, result.runs_without_value);
  g.Attribute(kBootstrapResamples, static_cast<std::int64_t>(bootstrap.resamples));
  g.Attribute(kBootstrapSeed, static_cast<std::int64_t>(bootstrap.seed));
  g.Attribute(kConfidenceLevel, bootstrap.confidence_level);
  g.Attribute(kEngineVersion, EngineVersion());
  g.Attribute(kGitCommit, EngineGitCommit());
  g.Attribute(kCreated, UtcTimestamp());
  g.Attribute(kCommandLine, command_line);
  if (result.method == SensitivityMethod::kSobol) {
    WriteSobol(g, result, level);
  } else {
    WriteMorris(g, result, level);
  }
}

}  // namespace

const ProductLayout& SensitivityProduct() {
  static const ProductLayout layout{
      "sensitivity",
      "analysis/sensitivity/<output>",
      "gesweep sensitivity",
      "Global sensitivity indices of one result column over the swept parameters, one group per output "
      "(a result group is one with the attribute method; the groups between have none)",
      {kProductDescription,
       kMethod,
       kOutput,
       kOutputPath,
       kOutputUnits,
       kParameters,
       kParameterUnits,
       kParameterLower,
       kParameterUpper,
       kParameterDistributions,
       kN,
       kRunCount,
       kFailedRuns,
       kRunsFailed,
       kRunsWithoutValue,
       kBootstrapResamples,
       kBootstrapSeed,
       kConfidenceLevel,
       kEngineVersion,
       kGitCommit,
       kCreated,
       kCommandLine,
       kDimension,
       kBlocksUsed,
       kBlocksDropped,
       kBootstrapUnit,
       kBaseSamples,
       kSecondOrder,
       kEstimatorFirst,
       kEstimatorTotal,
       kEstimatorSecond,
       kOutputMean,
       kOutputVariance,
       kTrajectories,
       kMorrisLevels,
       kDelta,
       kEstimator,
       kTrajectoriesUsed,
       kTrajectoriesDropped},
      {kFirstOrder, kFirstOrderCi, kTotal, kTotalCi, kSecondOrderIndices, kSecondOrderCi, kMu, kMuStar,
       kMuStarCi, kSigma, kEffects},
      {}};
  return layout;
}

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
