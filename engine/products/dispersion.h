#pragma once
/// Dispersion of a Monte Carlo sweep's results (docs/dispersion.md, "gesweep dispersion"): for chosen
/// per-run columns (by default the landing's touchdown distance past the transmitter, sink rate,
/// speed and pitch, and the flare's peak elevator when the archive has such a column), per group of
/// a grouping column: the counts (runs, values, failed, without a value, pending), mean, standard
/// deviation, percentiles, a normal fit and two Gumbel (extreme-value type I) fits with their
/// Anderson–Darling statistics and the tail quantiles they extrapolate to, and for each limit the
/// empirical probability of exceeding it with Wilson and Clopper–Pearson intervals beside the
/// fitted tails' probabilities. Written to /analysis/dispersion (schemas/archive.md).
///
/// Memory: one double per run per column (the sorted values of a group are kept to compute its
/// percentiles and fits) plus the grouping column.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "engine/archive/analysis_product.h"

namespace gesweep {

class ArchiveReader;
class ColumnCatalog;

// --- The statistics, over plain arrays (unit-tested alone) -------------------------------------

/// The percentile p (0..100) of sorted values by linear interpolation between order statistics
/// (Hyndman & Fan's definition 7, NumPy's default): h = (n − 1)·p/100, x[⌊h⌋] + (h − ⌊h⌋)·(x[⌊h⌋+1] −
/// x[⌊h⌋]). NaN for an empty array.
double Percentile(const std::vector<double>& sorted, double p);

/// A two-sided interval of a binomial proportion.
struct ProportionInterval {
  double lower = 0;
  double upper = 0;
};
/// Wilson's score interval (1927) of k successes in n trials, without continuity correction.
ProportionInterval WilsonInterval(std::int64_t k, std::int64_t n, double confidence_level);
/// The Clopper–Pearson ("exact") interval: the α/2 quantile of Beta(k, n − k + 1) and the 1 − α/2
/// quantile of Beta(k + 1, n − k) (0 when k = 0, 1 when k = n).
ProportionInterval ClopperPearsonInterval(std::int64_t k, std::int64_t n, double confidence_level);

/// A two-parameter location–scale fit.
struct LocationScale {
  double location = 0;
  double scale = 0;
};
/// The normal distribution's maximum-likelihood fit: the mean and the standard deviation with
/// divisor n. NaN when fewer than two values or all equal.
LocationScale FitNormal(const std::vector<double>& values);
/// The Gumbel (largest extreme value, CDF exp(−exp(−(x − μ)/β))) maximum-likelihood fit: β solves
/// β = x̄ − Σ xᵢ e^{−xᵢ/β} / Σ e^{−xᵢ/β} (TOMS 748), μ = −β log(mean e^{−xᵢ/β}). NaN when fewer than two
/// values or all equal.
LocationScale FitGumbelMax(const std::vector<double>& values);

/// Quantile and upper-tail probability of the fitted laws. The "Gumbel min" law (of the smallest
/// values, scipy's gumbel_l) is that of −Y for Y Gumbel-max fitted to the negated values; it is
/// stored with location −μ and scale β of that fit.
double NormalQuantile(const LocationScale& fit, double p);
double NormalProbabilityAbove(const LocationScale& fit, double x);
double GumbelMaxQuantile(const LocationScale& fit, double p);
double GumbelMaxProbabilityAbove(const LocationScale& fit, double x);

/// The generalised extreme value law of the largest values, P(X ≤ x) = exp(−(1 + ξ(x − μ)/σ)^(−1/ξ))
/// (Coles 2001, §3.1.3; ξ > 0 a heavy tail, ξ < 0 a bounded one with end point μ − σ/ξ, ξ → 0 the
/// Gumbel law; SciPy's genextreme has c = −ξ).
struct GevFit {
  double location = 0, scale = 0, shape = 0;  ///< μ, σ, ξ
  double negative_log_likelihood = 0;         ///< at the fit, in the values' units
};
/// The negative log-likelihood of values under a GEV law (+∞ outside its support or for σ ≤ 0).
double GevNegativeLogLikelihood(const std::vector<double>& values, double location, double scale,
                                double shape);
/// The GEV maximum-likelihood fit: Nelder–Mead on (μ, log σ, ξ) of the standardised values, started
/// from the Gumbel fit (ξ = 0) and restarted from its own optimum until it no longer improves; ξ is
/// kept above −1, where the likelihood is bounded (Smith 1985: regular above −0.5). NaN when fewer
/// than three values or all equal.
GevFit FitGevMax(const std::vector<double>& values);
/// The value not exceeded with probability p, and the probability of exceeding x.
double GevMaxQuantile(const GevFit& fit, double p);
double GevMaxProbabilityAbove(const GevFit& fit, double x);

/// The Anderson–Darling statistic A² of sorted values against a fitted law, and Stephens'
/// critical values for a law whose parameters were estimated from the same values (as
/// scipy.stats.anderson tabulates them). `critical` and `significance_percent` have equal sizes.
struct AndersonDarling {
  double statistic = 0;
  std::vector<double> critical;
  std::vector<double> significance_percent;
  /// The smallest significance level (percent) at which the fit is rejected (statistic > critical):
  /// the p-value is below it. 0 when it is rejected at none (p above the table's largest level), NaN
  /// when there is no statistic or no table (the GEV fit: Stephens gives none for three estimated
  /// parameters).
  double rejected_at_percent() const;
};
/// Against the normal of mean x̄ and standard deviation with divisor n − 1 (Stephens' case 3).
AndersonDarling AndersonDarlingNormal(const std::vector<double>& sorted);
/// Against the Gumbel-max maximum-likelihood fit (Stephens 1977).
AndersonDarling AndersonDarlingGumbelMax(const std::vector<double>& sorted, const LocationScale& fit);

// --- The product -------------------------------------------------------------------------------

/// A limit: the probability that `column` is above (or below) `value`.
struct DispersionLimit {
  std::string text;    ///< as given, e.g. "touchdown_sink_rate_mps>3"
  std::string column;  ///< the column's display name
  bool above = true;   ///< ">" (true) or "<"
  double value = 0;
};

/// What to compute.
/// The smallest tail probability p whose quantiles are computed: the upper ones are taken at 1 − p
/// in double precision, which holds p to 4 significant digits (5.5e-17 / p) down to 1e-12; below
/// 1.1e-16, 1 − p is 1 and the quantile infinite.
inline constexpr double kLowestTailProbability = 1e-12;
/// The highest confidence level of the intervals: z is taken at 0.5 + 0.5 level, as the tails above.
inline constexpr double kHighestConfidenceLevel = 1.0 - 1e-12;

struct DispersionOptions {
  std::vector<std::string> columns;  ///< empty: the landing defaults the archive has
  std::vector<std::string> limits;   ///< "column>value" or "column<value"
  std::string group_by;              ///< a column to group the runs by; empty: one group
  std::vector<double> percentiles = {0.1, 1, 5, 50, 95, 99, 99.9};
  std::vector<double> tail_probabilities = {1e-3, 1e-4, 1e-5,
                                            1e-6};  ///< each in [kLowestTailProbability, 0.5)
  double confidence_level = 0.95;
  int max_groups = 1000;
};

/// Landing columns used when none are chosen (each when the archive has it), and a pattern for the
/// flare's peak elevator column.
const std::vector<std::string>& DefaultDispersionColumns();

/// A fitted tail: the law's fit, its goodness, and the quantiles at the tail probabilities.
struct TailFit {
  std::string law;  ///< "normal", "gumbel_max", "gumbel_min" or "gev_max"
  LocationScale fit;
  double shape = 0;  ///< gev_max: ξ
  AndersonDarling goodness;
  std::vector<double> upper_quantiles;  ///< exceeded with probability p (normal, gumbel_max)
  std::vector<double> lower_quantiles;  ///< not reached with probability p (normal, gumbel_min)
};

/// The statistics of one column in one group.
struct ColumnDispersion {
  std::int64_t runs = 0;           ///< runs of the group
  std::int64_t values = 0;         ///< complete runs with a finite value: the sample
  std::int64_t failed = 0;         ///< status failed
  std::int64_t without_value = 0;  ///< status ok with a non-finite value (or an integer fill)
  std::int64_t pending = 0;        ///< not run yet
  double mean = 0, standard_deviation = 0, minimum = 0, maximum = 0;  ///< standard deviation: n − 1
  std::vector<double> percentiles;                                    ///< one per option
  /// Every value of the sample is the same (two or more values): its standard deviation is 0, every
  /// percentile is that value, and no tail law is fitted (the fits and their quantiles are NaN).
  bool no_spread = false;
  TailFit normal, gumbel_max, gumbel_min, gev_max;
};

/// A limit's exceedance in one group.
struct LimitExceedance {
  std::int64_t exceed = 0;  ///< values beyond the limit
  std::int64_t values = 0;  ///< the sample (finite values)
  std::int64_t failed = 0;  ///< failed or without a value: not in the sample
  double probability = 0;   ///< exceed / values (NaN when values = 0)
  ProportionInterval wilson, clopper_pearson;
  double normal_probability = 0;  ///< of the normal fit
  double gumbel_probability = 0;  ///< of the Gumbel fit of the same tail (max for >, min for <)
  double gev_probability = 0;     ///< of the GEV fit of the largest values (NaN for <)
};

/// One group of runs.
struct DispersionGroup {
  std::string label;                      ///< the grouping value as shown ("all" without grouping)
  double value = 0;                       ///< the grouping value (NaN without grouping)
  std::vector<ColumnDispersion> columns;  ///< one per Dispersion::columns
  std::vector<LimitExceedance> limits;    ///< one per Dispersion::limits
};

/// The dispersion of an archive.
struct Dispersion {
  std::string archive;
  std::string study_name;
  std::string design_kind;
  std::int64_t run_count = 0;
  std::vector<std::string> columns;  ///< display names
  std::vector<std::string> column_paths;
  std::vector<std::string> column_units;
  std::vector<DispersionLimit> limits;
  std::string group_by;    ///< display name; empty: no grouping
  std::string group_path;  ///< its dataset path
  std::string group_units;
  DispersionOptions options;
  std::vector<DispersionGroup> groups;  ///< by increasing grouping value
};

/// Computes the dispersion. Throws InputError (source the archive) when a column, limit or grouping
/// column does not resolve (key columns, limits, group_by), when no default column exists and none
/// is chosen, or when an option is out of range (source "command line"); ArchiveError on I/O failure.
Dispersion ComputeDispersion(const ArchiveReader& archive, const ColumnCatalog& catalog,
                             const DispersionOptions& options);

/// Writes `dispersion` into the archive's group analysis/dispersion, replacing a previous one
/// (WriteAnalysisProduct). Precondition: the caller holds ArchiveLock and has no handle open.
void WriteDispersionGroup(const std::filesystem::path& archive, const Dispersion& dispersion,
                          const std::string& command_line);

/// "analysis/dispersion". What the group holds (its attributes, datasets and the subgroup `limits`)
/// is product::dispersion of engine/archive/product_fields.h, generated from schemas/products.json.
std::string DispersionGroupPath();

}  // namespace gesweep
