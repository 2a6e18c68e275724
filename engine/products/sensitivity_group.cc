#include "engine/products/sensitivity_group.h"

#include <cstring>
#include <limits>

#include "engine/archive/archive_format.h"
#include "engine/archive/product_fields.h"
#include "engine/common/errors.h"

namespace gesweep {
namespace {

// The group under which each output's result group lies (product::sensitivity::kPath without "/<output>").
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

// The fields of a result group (schemas/products.json): a Sobol' group has the Sobol' attributes and
// datasets, a Morris group the Morris ones.
namespace attribute = product::sensitivity::attribute;
namespace dataset = product::sensitivity::dataset;

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
  group.Attribute(attribute::kBaseSamples, static_cast<std::int64_t>(s.layout.base_samples));
  group.Attribute(attribute::kDimension, static_cast<std::int64_t>(s.layout.parameter_count));
  group.Attribute(attribute::kSecondOrder, static_cast<std::int64_t>(s.layout.second_order ? 1 : 0));
  group.Attribute(attribute::kEstimatorFirstOrder, kFirstOrderEstimator);
  group.Attribute(attribute::kEstimatorTotal, kTotalEstimator);
  if (s.layout.second_order) group.Attribute(attribute::kEstimatorSecondOrder, kSecondOrderEstimator);
  group.Attribute(attribute::kBlocksUsed, static_cast<std::int64_t>(s.blocks_used));
  group.Attribute(attribute::kBlocksDropped, static_cast<std::int64_t>(s.blocks_dropped));
  group.Attribute(attribute::kBootstrapUnit, "base samples (whole Saltelli blocks), with replacement");
  group.Attribute(attribute::kOutputMean, s.output_mean);
  group.Attribute(attribute::kOutputVariance, s.output_variance);

  WriteDoubles(group, dataset::kFirstOrder, {}, s.first_order, level, "");
  WriteIntervals(group, dataset::kFirstOrderCi, s.first_order_ci, level, "");
  WriteDoubles(group, dataset::kTotal, {}, s.total, level, "");
  WriteIntervals(group, dataset::kTotalCi, s.total_ci, level, "");
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
  WriteDoubles(group, dataset::kSecondOrder, {D, D}, second, level, "");
  WriteDoubles(group, dataset::kSecondOrderCi, {D, D, 2}, interval, level, "");
}

void WriteMorris(ProductGroup& group, const ArchiveSensitivity& result, const std::string& level) {
  const MorrisIndices& m = result.morris;
  const std::string& units = result.output.units;
  group.Attribute(attribute::kTrajectories, static_cast<std::int64_t>(m.trajectories));
  group.Attribute(attribute::kDimension, static_cast<std::int64_t>(m.parameter_count));
  group.Attribute(attribute::kLevels, static_cast<std::int64_t>(result.morris_levels));
  group.Attribute(attribute::kDelta, result.morris_delta);
  group.Attribute(attribute::kEstimator, kMorrisEstimator);
  group.Attribute(attribute::kTrajectoriesUsed, static_cast<std::int64_t>(m.trajectories_used));
  group.Attribute(attribute::kTrajectoriesDropped, static_cast<std::int64_t>(m.trajectories_dropped));
  group.Attribute(attribute::kBlocksUsed, static_cast<std::int64_t>(m.trajectories_used));
  group.Attribute(attribute::kBlocksDropped, static_cast<std::int64_t>(m.trajectories_dropped));
  group.Attribute(attribute::kBootstrapUnit, "trajectories, with replacement");
  WriteDoubles(group, dataset::kMu, {}, m.mu, level, units);
  WriteDoubles(group, dataset::kMuStar, {}, m.mu_star, level, units);
  WriteIntervals(group, dataset::kMuStarCi, m.mu_star_ci, level, units);
  WriteDoubles(group, dataset::kSigma, {}, m.sigma, level, units);
  WriteCounts(group, dataset::kEffects, m.effects);
}

void WriteGroup(ProductGroup& g, const ArchiveSensitivity& result, const std::string& command_line) {
  const BootstrapOptions& bootstrap =
      result.method == SensitivityMethod::kSobol ? result.sobol.bootstrap : result.morris.bootstrap;
  const std::string level = ShortNumber(100.0 * bootstrap.confidence_level) + " %";
  g.Attribute(attribute::kDescription,
              std::string(result.method == SensitivityMethod::kSobol ? "Sobol' indices"
                                                                     : "Morris elementary effects") +
                  " of " + result.output.path + " over the swept parameters (docs/sensitivity.md)");
  g.Attribute(attribute::kMethod, std::string(ToString(result.method)));
  g.Attribute(attribute::kOutput, result.output.name);
  g.Attribute(attribute::kOutputPath, result.output.path);
  g.Attribute(attribute::kOutputUnits, result.output.units);
  g.Attribute(attribute::kParameters, result.parameters);
  g.Attribute(attribute::kParameterUnits, result.parameter_units);
  std::vector<double> lower, upper;
  std::vector<std::string> distributions;
  for (const auto& range : result.ranges) {
    lower.push_back(range.lower);
    upper.push_back(range.upper);
    distributions.push_back(range.log_uniform ? "loguniform" : "uniform");
  }
  g.Attribute(attribute::kParameterLower, lower);
  g.Attribute(attribute::kParameterUpper, upper);
  g.Attribute(attribute::kParameterDistributions, distributions);
  g.Attribute(attribute::kN, result.n());
  g.Attribute(attribute::kRunCount, result.run_count);
  g.Attribute(attribute::kFailedRuns, std::string(ToString(result.failed_runs)));
  g.Attribute(attribute::kRunsFailed, result.runs_failed);
  g.Attribute(attribute::kRunsWithoutValue, result.runs_without_value);
  g.Attribute(attribute::kBootstrapResamples, static_cast<std::int64_t>(bootstrap.resamples));
  g.Attribute(attribute::kBootstrapSeed, static_cast<std::int64_t>(bootstrap.seed));
  g.Attribute(attribute::kConfidenceLevel, bootstrap.confidence_level);
  WriteProvenance(g, product::sensitivity::Layout(), command_line);
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
