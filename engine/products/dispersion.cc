#include "engine/products/dispersion.h"

#include <algorithm>
#include <array>
#include <boost/math/distributions/beta.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <limits>
#include <map>

#include "engine/archive/analysis_product.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/product_fields.h"
#include "engine/common/errors.h"
#include "engine/common/request_error.h"
#include "engine/query/run_columns.h"

namespace gesweep {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::int8_t kStatusPending = 0;
constexpr std::int8_t kStatusOk = 1;
constexpr std::int8_t kStatusFailed = 2;
// Runs read at a time: bounded buffers for any archive.
constexpr std::int64_t kPieceRows = 1 << 16;
// Stephens' tables for the Anderson–Darling test with estimated parameters, as scipy.stats.anderson
// holds them: normal (case 3, Stephens 1974) and Gumbel (Stephens 1977), and their small-sample
// corrections; the critical values are rounded to the tables' three decimals.
constexpr double kNormalCritical[] = {0.576, 0.656, 0.787, 0.918, 1.092};
constexpr double kNormalSignificance[] = {15, 10, 5, 2.5, 1};
constexpr double kGumbelCritical[] = {0.474, 0.637, 0.757, 0.877, 1.038};
constexpr double kGumbelSignificance[] = {25, 10, 5, 2.5, 1};

const boost::math::normal kStandardNormal;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// The GEV fit: |ξ| below this is the Gumbel law (the GEV formulas lose digits as 1/ξ grows: at
// 1e-7 the two laws differ by about ξ·z² ≈ 1e-5 relative at z = 10, below any sample's resolution);
// ξ above −1, where the likelihood is bounded; Nelder–Mead's start step (standardised units),
// tolerances (relative on the log-likelihood, absolute on the standardised parameters), iteration
// cap per run and restarts.
constexpr double kGumbelShape = 1e-7;
constexpr double kLowestShape = -1.0;
constexpr double kNelderMeadStep = 0.1;
constexpr double kNelderMeadValueTolerance = 1e-14;
constexpr double kNelderMeadPointTolerance = 1e-9;
constexpr int kNelderMeadIterations = 20000;
constexpr int kNelderMeadRestarts = 8;

double Round3(double x) { return std::nearbyint(x * 1000.0) / 1000.0; }

double Mean(const std::vector<double>& values) {
  double sum = 0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

// Σ (x − mean)² by two passes.
double SumOfSquares(const std::vector<double>& values, double mean) {
  double sum = 0;
  for (double v : values) sum += (v - mean) * (v - mean);
  return sum;
}

// A² from the log CDF and log survival of each sorted value.
double AndersonDarlingStatistic(const std::vector<double>& logcdf, const std::vector<double>& logsf) {
  const auto n = static_cast<double>(logcdf.size());
  const std::size_t size = logcdf.size();
  double sum = 0;
  for (std::size_t i = 0; i < size; ++i) {
    sum += (2.0 * static_cast<double>(i + 1) - 1.0) / n * (logcdf[i] + logsf[size - 1 - i]);
  }
  return -n - sum;
}

double NormalLogCdf(double z) {
  return z < 0 ? std::log(boost::math::cdf(kStandardNormal, z))
               : std::log1p(-boost::math::cdf(boost::math::complement(kStandardNormal, z)));
}

}  // namespace

double Percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return kNaN;
  const double h = static_cast<double>(sorted.size() - 1) * p / 100.0;
  const double lower = std::floor(h);
  const auto i = static_cast<std::size_t>(lower);
  if (i + 1 >= sorted.size()) return sorted.back();
  return sorted[i] + (h - lower) * (sorted[i + 1] - sorted[i]);
}

ProportionInterval WilsonInterval(std::int64_t k, std::int64_t n, double confidence_level) {
  if (n <= 0) return {kNaN, kNaN};
  const double z = boost::math::quantile(kStandardNormal, 0.5 + 0.5 * confidence_level);
  const auto nn = static_cast<double>(n);
  const double p = static_cast<double>(k) / nn;
  const double denominator = 2.0 * (nn + z * z);
  const double center = (2.0 * nn * p + z * z) / denominator;
  const double half = z * std::sqrt(z * z + 4.0 * nn * p * (1.0 - p)) / denominator;
  return {std::max(0.0, center - half), std::min(1.0, center + half)};
}

ProportionInterval ClopperPearsonInterval(std::int64_t k, std::int64_t n, double confidence_level) {
  if (n <= 0) return {kNaN, kNaN};
  const double alpha = 1.0 - confidence_level;
  const auto kk = static_cast<double>(k), nn = static_cast<double>(n);
  const double lower = k == 0 ? 0.0 : boost::math::ibeta_inv(kk, nn - kk + 1.0, alpha / 2);
  const double upper = k == n ? 1.0 : boost::math::ibetac_inv(kk + 1.0, nn - kk, alpha / 2);
  return {lower, upper};
}

LocationScale FitNormal(const std::vector<double>& values) {
  if (values.size() < 2) return {kNaN, kNaN};
  // One value repeated has no spread, whatever the rounding of its mean makes of Σ (x − x̄)².
  const auto [lowest, highest] = std::minmax_element(values.begin(), values.end());
  if (*lowest == *highest) return {kNaN, kNaN};
  const double mean = Mean(values);
  const double sigma = std::sqrt(SumOfSquares(values, mean) / static_cast<double>(values.size()));
  if (!(sigma > 0)) return {kNaN, kNaN};
  return {mean, sigma};
}

LocationScale FitGumbelMax(const std::vector<double>& values) {
  // Standardised values y = (x − x̄)/s, with the normal fit's x̄ and s, keep the exponentials in
  // range; the fit is equivariant. The normal fit is NaN for fewer than two values or all equal.
  const LocationScale normal = FitNormal(values);
  if (!(normal.scale > 0)) return {kNaN, kNaN};
  const double mean = normal.location;
  const double s = normal.scale;
  std::vector<double> y(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) y[i] = (values[i] - mean) / s;
  const double y_min = *std::min_element(y.begin(), y.end());
  // log Σ e^{−y/b}, shifted by its largest term (−y_min/b).
  auto log_sum = [&](double b) {
    double sum = 0;
    for (double v : y) sum += std::exp(-(v - y_min) / b);
    return std::log(sum) - y_min / b;
  };
  // g(b) = b − ȳ + Σ y e^{−y/b} / Σ e^{−y/b}, with ȳ = 0: g → y_min < 0 as b → 0, g → b as b → ∞.
  auto g = [&](double b) {
    double weights = 0, weighted = 0;
    for (double v : y) {
      const double w = std::exp(-(v - y_min) / b);
      weights += w;
      weighted += v * w;
    }
    return b + weighted / weights;
  };
  double low = 1e-6, high = 1.0;
  // g(low) < 0 < g(high) for any sample with a spread; a sample without one (its values equal but
  // for the rounding of their mean) has none to fit: not fitted, never an exception out of Boost.
  if (!(g(low) < 0)) return {kNaN, kNaN};
  while (g(high) < 0 && high < 1e6) high *= 2;
  if (!(g(high) > 0)) return {kNaN, kNaN};
  std::uintmax_t iterations = 200;
  std::pair<double, double> bracket;
  try {
    bracket = boost::math::tools::toms748_solve(g, low, high, boost::math::tools::eps_tolerance<double>(52),
                                                iterations);
  } catch (const std::exception&) {  // Boost's evaluation_error: no root to the precision asked
    return {kNaN, kNaN};
  }
  const double b = 0.5 * (bracket.first + bracket.second);
  const double location_y = -b * (log_sum(b) - std::log(static_cast<double>(y.size())));
  return {mean + s * location_y, s * b};
}

double NormalQuantile(const LocationScale& fit, double p) {
  if (!(fit.scale > 0)) return kNaN;
  return fit.location + fit.scale * boost::math::quantile(kStandardNormal, p);
}

double NormalProbabilityAbove(const LocationScale& fit, double x) {
  if (!(fit.scale > 0)) return kNaN;
  return boost::math::cdf(boost::math::complement(kStandardNormal, (x - fit.location) / fit.scale));
}

double GumbelMaxQuantile(const LocationScale& fit, double p) {
  if (!(fit.scale > 0)) return kNaN;
  return fit.location - fit.scale * std::log(-std::log1p(p - 1.0));  // p − 1 is exact near 1
}

double GumbelMaxProbabilityAbove(const LocationScale& fit, double x) {
  if (!(fit.scale > 0)) return kNaN;
  return -std::expm1(-std::exp(-(x - fit.location) / fit.scale));
}

double GevNegativeLogLikelihood(const std::vector<double>& values, double location, double scale,
                                double shape) {
  if (!(scale > 0) || !std::isfinite(location) || !std::isfinite(shape)) return kInfinity;
  const auto n = static_cast<double>(values.size());
  double sum_log = 0, sum_power = 0;
  if (std::abs(shape) < kGumbelShape) {
    for (double x : values) {
      const double z = (x - location) / scale;
      sum_log += z;
      sum_power += std::exp(-z);
    }
    return n * std::log(scale) + sum_log + sum_power;
  }
  for (double x : values) {
    const double t = 1.0 + shape * (x - location) / scale;
    if (!(t > 0)) return kInfinity;
    const double log_t = std::log(t);
    sum_log += log_t;
    sum_power += std::exp(-log_t / shape);
  }
  return n * std::log(scale) + (1.0 + 1.0 / shape) * sum_log + sum_power;
}

namespace {

using GevPoint = std::array<double, 3>;  // (μ, log σ, ξ) of the standardised values

// One Nelder–Mead run (the standard coefficients 1, 2, 1/2, 1/2) of `f` from a fresh simplex about
// `start`, until the tolerances or the iteration cap: the final simplex and its values.
template <typename F>
void RunNelderMead(const F& f, const GevPoint& start, std::array<GevPoint, 4>& simplex,
                   std::array<double, 4>& value) {
  simplex[0] = start;
  for (std::size_t d = 0; d < 3; ++d) {
    simplex[d + 1] = start;
    simplex[d + 1][d] += kNelderMeadStep;
  }
  for (std::size_t k = 0; k < 4; ++k) value[k] = f(simplex[k]);
  for (int iteration = 0; iteration < kNelderMeadIterations; ++iteration) {
    std::array<std::size_t, 4> order = {0, 1, 2, 3};
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return value[a] < value[b]; });
    const std::size_t lo = order[0], hi = order[3], second = order[2];
    double spread = 0;
    for (std::size_t k = 1; k < 4; ++k)
      for (std::size_t d = 0; d < 3; ++d)
        spread = std::max(spread, std::abs(simplex[order[k]][d] - simplex[lo][d]));
    if (value[hi] - value[lo] <= kNelderMeadValueTolerance * (1.0 + std::abs(value[lo])) &&
        spread <= kNelderMeadPointTolerance)
      break;
    GevPoint centroid = {0, 0, 0};
    for (std::size_t k = 0; k < 3; ++k)
      for (std::size_t d = 0; d < 3; ++d) centroid[d] += simplex[order[k]][d] / 3.0;
    auto along = [&](double t) {
      GevPoint p;
      for (std::size_t d = 0; d < 3; ++d) p[d] = centroid[d] + t * (simplex[hi][d] - centroid[d]);
      return p;
    };
    const GevPoint reflected = along(-1.0);
    const double fr = f(reflected);
    if (fr < value[lo]) {
      const GevPoint expanded = along(-2.0);
      const double fe = f(expanded);
      simplex[hi] = fe < fr ? expanded : reflected;
      value[hi] = std::min(fe, fr);
    } else if (fr < value[second]) {
      simplex[hi] = reflected;
      value[hi] = fr;
    } else {
      const bool outside = fr < value[hi];
      const GevPoint contracted = along(outside ? -0.5 : 0.5);
      const double fc = f(contracted);
      if (fc < (outside ? fr : value[hi])) {
        simplex[hi] = contracted;
        value[hi] = fc;
      } else {
        for (std::size_t k = 0; k < 4; ++k) {
          if (k == lo) continue;
          for (std::size_t d = 0; d < 3; ++d)
            simplex[k][d] = simplex[lo][d] + 0.5 * (simplex[k][d] - simplex[lo][d]);
          value[k] = f(simplex[k]);
        }
      }
    }
  }
}

}  // namespace

GevFit FitGevMax(const std::vector<double>& values) {
  GevFit fit{kNaN, kNaN, kNaN, kNaN};
  if (values.size() < 3) return fit;
  // Standardised as FitGumbelMax's.
  const LocationScale normal = FitNormal(values);
  if (!(normal.scale > 0)) return fit;
  const double mean = normal.location;
  const double sd = normal.scale;
  std::vector<double> y(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) y[i] = (values[i] - mean) / sd;
  auto f = [&](const GevPoint& p) {
    if (!(p[2] > kLowestShape)) return kInfinity;
    return GevNegativeLogLikelihood(y, p[0], std::exp(p[1]), p[2]);
  };
  const LocationScale gumbel = FitGumbelMax(y);
  GevPoint best = {gumbel.location, std::log(gumbel.scale), 0.0};
  double best_value = f(best);
  // Nelder–Mead, restarted from its optimum with a fresh simplex until a restart no longer lowers the
  // minimum.
  for (int restart = 0; restart < kNelderMeadRestarts; ++restart) {
    std::array<GevPoint, 4> simplex;
    std::array<double, 4> value;
    RunNelderMead(f, best, simplex, value);
    const auto lo = static_cast<std::size_t>(std::min_element(value.begin(), value.end()) - value.begin());
    const bool improved = value[lo] < best_value - kNelderMeadValueTolerance * (1.0 + std::abs(best_value));
    if (value[lo] < best_value) {
      best = simplex[lo];
      best_value = value[lo];
    }
    if (!improved && restart > 0) break;
  }
  if (!std::isfinite(best_value)) return fit;
  fit.location = mean + sd * best[0];
  fit.scale = sd * std::exp(best[1]);
  fit.shape = best[2];
  fit.negative_log_likelihood = GevNegativeLogLikelihood(values, fit.location, fit.scale, fit.shape);
  return fit;
}

double GevMaxQuantile(const GevFit& fit, double p) {
  if (!(fit.scale > 0)) return kNaN;
  const double minus_log_p = -std::log1p(p - 1.0);  // p − 1 is exact near 1
  if (std::abs(fit.shape) < kGumbelShape) return fit.location - fit.scale * std::log(minus_log_p);
  return fit.location + fit.scale / fit.shape * std::expm1(-fit.shape * std::log(minus_log_p));
}

double GevMaxProbabilityAbove(const GevFit& fit, double x) {
  if (!(fit.scale > 0)) return kNaN;
  if (std::abs(fit.shape) < kGumbelShape) return GumbelMaxProbabilityAbove({fit.location, fit.scale}, x);
  const double t = 1.0 + fit.shape * (x - fit.location) / fit.scale;
  if (!(t > 0)) return fit.shape < 0 ? 0.0 : 1.0;  // beyond the upper end point, or below the lower
  return -std::expm1(-std::exp(-std::log(t) / fit.shape));
}

double AndersonDarling::rejected_at_percent() const {
  if (!std::isfinite(statistic) || critical.empty()) return kNaN;
  double level = 0;
  for (std::size_t i = 0; i < critical.size(); ++i) {
    if (statistic > critical[i] && (level == 0 || significance_percent[i] < level))
      level = significance_percent[i];
  }
  return level;
}

AndersonDarling AndersonDarlingNormal(const std::vector<double>& sorted) {
  AndersonDarling result;
  const auto n = static_cast<double>(sorted.size());
  for (std::size_t i = 0; i < std::size(kNormalCritical); ++i) {
    result.critical.push_back(Round3(kNormalCritical[i] / (1.0 + 4.0 / n - 25.0 / n / n)));
    result.significance_percent.push_back(kNormalSignificance[i]);
  }
  result.statistic = kNaN;
  if (sorted.size() < 3) return result;
  const double mean = Mean(sorted);
  const double s = std::sqrt(SumOfSquares(sorted, mean) / (n - 1));
  if (!(s > 0)) return result;
  std::vector<double> logcdf, logsf;
  for (double x : sorted) {
    const double z = (x - mean) / s;
    logcdf.push_back(NormalLogCdf(z));
    logsf.push_back(NormalLogCdf(-z));
  }
  result.statistic = AndersonDarlingStatistic(logcdf, logsf);
  return result;
}

AndersonDarling AndersonDarlingGumbelMax(const std::vector<double>& sorted, const LocationScale& fit) {
  AndersonDarling result;
  const auto n = static_cast<double>(sorted.size());
  for (std::size_t i = 0; i < std::size(kGumbelCritical); ++i) {
    result.critical.push_back(Round3(kGumbelCritical[i] / (1.0 + 0.2 / std::sqrt(n))));
    result.significance_percent.push_back(kGumbelSignificance[i]);
  }
  result.statistic = kNaN;
  if (sorted.size() < 3 || !(fit.scale > 0)) return result;
  std::vector<double> logcdf, logsf;
  for (double x : sorted) {
    const double e = std::exp(-(x - fit.location) / fit.scale);
    logcdf.push_back(-e);
    logsf.push_back(std::log(-std::expm1(-e)));
  }
  result.statistic = AndersonDarlingStatistic(logcdf, logsf);
  return result;
}

const std::vector<std::string>& DefaultDispersionColumns() {
  static const std::vector<std::string> columns = {
      "results/landing/touchdown_distance_past_transmitter_m", "results/landing/touchdown_sink_rate_mps",
      "results/landing/touchdown_speed_mps", "results/landing/touchdown_pitch_deg"};
  return columns;
}

namespace {

// The statistics of one sample (its values sorted in place).
ColumnDispersion Describe(std::vector<double>& sample, const DispersionOptions& options) {
  ColumnDispersion c;
  std::sort(sample.begin(), sample.end());
  c.values = static_cast<std::int64_t>(sample.size());
  if (sample.empty()) {
    c.mean = c.standard_deviation = c.minimum = c.maximum = kNaN;
  } else {
    c.mean = Mean(sample);
    c.standard_deviation =
        sample.size() < 2 ? kNaN
                          : std::sqrt(SumOfSquares(sample, c.mean) / static_cast<double>(sample.size() - 1));
    c.minimum = sample.front();
    c.maximum = sample.back();
  }
  for (double p : options.percentiles) c.percentiles.push_back(Percentile(sample, p));
  c.normal.law = "normal";
  c.gumbel_max.law = "gumbel_max";
  c.gumbel_min.law = "gumbel_min";
  c.gev_max.law = "gev_max";
  if (sample.size() >= 2 && sample.front() == sample.back()) {
    // No spread: a stated result, not a fit. The mean is the value itself (the sum's rounding left
    // out), the spread 0, and the laws' parameters and quantiles NaN (nothing to fit).
    c.no_spread = true;
    c.mean = sample.front();
    c.standard_deviation = 0.0;
    for (TailFit* fit : {&c.normal, &c.gumbel_max, &c.gumbel_min, &c.gev_max}) {
      fit->fit = {kNaN, kNaN};
      fit->goodness.statistic = kNaN;
    }
    c.gev_max.shape = kNaN;
    const std::vector<double> none(options.tail_probabilities.size(), kNaN);
    c.normal.upper_quantiles = c.normal.lower_quantiles = c.gumbel_max.upper_quantiles = none;
    c.gumbel_min.lower_quantiles = c.gev_max.upper_quantiles = none;
    return c;
  }
  c.normal.fit = FitNormal(sample);
  c.normal.goodness = AndersonDarlingNormal(sample);
  c.gumbel_max.law = "gumbel_max";
  c.gumbel_max.fit = FitGumbelMax(sample);
  c.gumbel_max.goodness = AndersonDarlingGumbelMax(sample, c.gumbel_max.fit);
  // The minimum's law: the negated values' Gumbel-max fit.
  std::vector<double> negated(sample.rbegin(), sample.rend());
  for (double& v : negated) v = -v;
  c.gumbel_min.law = "gumbel_min";
  const LocationScale negated_fit = FitGumbelMax(negated);
  c.gumbel_min.goodness = AndersonDarlingGumbelMax(negated, negated_fit);
  // Stored as the smallest-value Gumbel law itself (scipy's gumbel_l): location −μ of the negated fit.
  c.gumbel_min.fit = {-negated_fit.location, negated_fit.scale};
  c.gev_max.law = "gev_max";
  const GevFit gev = FitGevMax(sample);
  c.gev_max.fit = {gev.location, gev.scale};
  c.gev_max.shape = gev.shape;
  c.gev_max.goodness.statistic = kNaN;
  if (std::isfinite(gev.scale)) {
    std::vector<double> logcdf, logsf;
    for (double x : sample) {
      const double above = GevMaxProbabilityAbove(gev, x);
      logcdf.push_back(std::log1p(-above));
      logsf.push_back(std::log(above));
    }
    c.gev_max.goodness.statistic = AndersonDarlingStatistic(logcdf, logsf);
  }
  for (double p : options.tail_probabilities) {
    c.gev_max.upper_quantiles.push_back(GevMaxQuantile(gev, 1.0 - p));
    c.normal.upper_quantiles.push_back(NormalQuantile(c.normal.fit, 1.0 - p));
    c.normal.lower_quantiles.push_back(NormalQuantile(c.normal.fit, p));
    c.gumbel_max.upper_quantiles.push_back(GumbelMaxQuantile(c.gumbel_max.fit, 1.0 - p));
    c.gumbel_min.lower_quantiles.push_back(-GumbelMaxQuantile(negated_fit, 1.0 - p));
  }
  return c;
}

DispersionLimit ParseLimit(const std::string& text, const ColumnCatalog& catalog, const std::string& source) {
  const auto at = text.find_first_of("<>");
  if (at == std::string::npos || at == 0 || text.find_first_of("<>", at + 1) != std::string::npos) {
    throw InputError(source, "limits", text,
                     "expected COLUMN>VALUE or COLUMN<VALUE, e.g. touchdown_sink_rate_mps>3");
  }
  DispersionLimit limit;
  limit.text = text;
  limit.above = text[at] == '>';
  std::string name = text.substr(0, at), number = text.substr(at + 1);
  auto trim = [](const std::string& s) {
    const auto b = s.find_first_not_of(' '), e = s.find_last_not_of(' ');
    return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
  };
  name = trim(name);
  number = trim(number);
  char* end = nullptr;
  limit.value = std::strtod(number.c_str(), &end);
  if (number.empty() || end != number.c_str() + number.size() || !std::isfinite(limit.value)) {
    throw InputError(source, "limits", text, "expected a finite number after " + std::string(1, text[at]));
  }
  const int index = catalog.Require(name, source, "limits");
  limit.column = catalog.column(index).name;
  return limit;
}

// Refuses options out of their ranges (the percentiles, the tail probabilities, the confidence level).
void CheckDispersionOptions(const DispersionOptions& options) {
  for (double p : options.percentiles) {
    if (!(p >= 0 && p <= 100))
      throw InputError("command line", "percentiles", ShortNumber(p), "expected 0 to 100");
  }
  for (double p : options.tail_probabilities) {
    if (!(p >= kLowestTailProbability && p < 0.5))
      throw InputError("command line", "tail_probabilities", ShortNumber(p),
                       "expected a probability in [" + ShortNumber(kLowestTailProbability) +
                           ", 0.5) (the upper quantiles are taken at 1 - p in double precision: below " +
                           ShortNumber(kLowestTailProbability) + " p keeps fewer than 4 digits)");
  }
  if (!(options.confidence_level > 0 && options.confidence_level <= kHighestConfidenceLevel)) {
    throw InputError("command line", "confidence_level", ShortNumber(options.confidence_level),
                     "expected a level in (0, 1 - 1e-12], e.g. 0.95");
  }
}

void AddColumn(Dispersion& d, const RunColumn& column) {
  d.columns.push_back(column.name);
  d.column_paths.push_back(column.path);
  d.column_units.push_back(column.units);
}

// The catalogue indices of the columns described (the options' columns, or the landing's touchdown
// and flare-elevator columns; then each column a limit names), added to d.columns with their
// paths and units; the limits parsed into d.limits.
std::vector<int> ChooseColumns(const ColumnCatalog& catalog, const DispersionOptions& options,
                               const std::string& source, Dispersion& d) {
  std::vector<int> indices;
  if (options.columns.empty()) {
    for (const auto& path : DefaultDispersionColumns()) {
      if (const auto index = catalog.FindPath(path)) indices.push_back(*index);
    }
    for (std::size_t i = 0; i < catalog.columns().size(); ++i) {
      const RunColumn& column = catalog.columns()[i];
      const std::string leaf = column.path.substr(column.path.rfind('/') + 1);
      if (column.path.rfind("results/landing/", 0) == 0 && leaf.find("flare") != std::string::npos &&
          leaf.find("elevator") != std::string::npos && column.kind == ColumnKind::kNumber) {
        indices.push_back(static_cast<int>(i));
      }
    }
    if (indices.empty()) {
      throw RequestError(source, "columns", "",
                         "expected the landing's touchdown columns (results/landing/touchdown_*) or columns "
                         "chosen by name",
                         "describe_columns");
    }
  } else {
    for (const auto& name : options.columns) {
      for (int index : catalog.Expand(name, source, "columns")) {
        if (std::find(indices.begin(), indices.end(), index) == indices.end()) indices.push_back(index);
      }
    }
  }
  for (int index : indices) {
    const RunColumn& column = catalog.column(index);
    if (column.kind != ColumnKind::kNumber || column.path.rfind("results/", 0) != 0) {
      throw InputError(source, "columns", column.name, "expected a numeric result column (results/...)");
    }
    AddColumn(d, column);
  }
  for (const auto& text : options.limits) {
    DispersionLimit limit = ParseLimit(text, catalog, source);
    const RunColumn& column = catalog.column(catalog.Require(limit.column, source, "limits"));
    if (std::find(d.column_paths.begin(), d.column_paths.end(), column.path) == d.column_paths.end()) {
      // A limit on a column not chosen adds it.
      if (column.kind != ColumnKind::kNumber || column.path.rfind("results/", 0) != 0) {
        throw InputError(source, "limits", text, "expected a limit on a numeric result column (results/...)");
      }
      AddColumn(d, column);
      indices.push_back(catalog.Require(limit.column, source, "limits"));
    }
    d.limits.push_back(limit);
  }
  return indices;
}

// Each run's group: the index in d.groups (made here: the distinct values of the group_by column,
// NaN last; one group "all" without group_by).
std::vector<int> GroupRuns(const ArchiveReader& archive, const ColumnCatalog& catalog,
                           const DispersionOptions& options, const std::string& source, Dispersion& d) {
  const std::int64_t n = archive.run_count();
  std::vector<double> group_values(static_cast<std::size_t>(n), kNaN);
  const RunColumn* group_column = nullptr;
  if (!options.group_by.empty()) {
    group_column = &catalog.column(catalog.Require(options.group_by, source, "group_by"));
    if (group_column->kind != ColumnKind::kNumber) {
      throw InputError(source, "group_by", options.group_by, "expected a numeric column to group by");
    }
    d.group_by = group_column->name;
    d.group_path = group_column->path;
    d.group_units = group_column->units;
    ColumnValues values;
    for (std::int64_t first = 0; first < n; first += kPieceRows) {
      const std::int64_t count = std::min(kPieceRows, n - first);
      ReadColumn(archive, *group_column, first, count, values);
      std::copy(values.numbers.begin(), values.numbers.end(), group_values.begin() + first);
    }
  }
  // Distinct grouping values, NaN last; each run's group.
  std::vector<double> keys;
  std::vector<int> group_of(static_cast<std::size_t>(n), 0);
  if (group_column != nullptr) {
    std::map<double, int> finite;
    bool has_nan = false;
    for (double v : group_values) {
      if (std::isnan(v)) {
        has_nan = true;
      } else {
        finite.emplace(v, 0);
      }
      if (static_cast<int>(finite.size()) + (has_nan ? 1 : 0) > options.max_groups) {
        throw RequestError(source, "group_by", options.group_by,
                           "more than " + std::to_string(options.max_groups) + " groups", "fewer_groups");
      }
    }
    int g = 0;
    for (auto& [value, index] : finite) {
      index = g++;
      keys.push_back(value);
    }
    if (has_nan) keys.push_back(kNaN);
    for (std::size_t r = 0; r < group_values.size(); ++r) {
      group_of[r] = std::isnan(group_values[r]) ? g : finite.at(group_values[r]);
    }
  } else {
    keys.push_back(kNaN);
  }
  d.groups.resize(keys.size());
  for (std::size_t g = 0; g < keys.size(); ++g) {
    d.groups[g].value = keys[g];
    d.groups[g].label = group_column == nullptr ? "all" : FormatCell(*group_column, keys[g]);
  }
  return group_of;
}

// Every run's status, read piece by piece.
std::vector<std::int8_t> ReadStatuses(const ArchiveReader& archive) {
  const std::int64_t n = archive.run_count();
  std::vector<std::int8_t> status;
  status.reserve(static_cast<std::size_t>(n));
  for (std::int64_t first = 0; first < n; first += kPieceRows) {
    const auto piece = archive.ReadStatus(first, std::min(kPieceRows, n - first));
    status.insert(status.end(), piece.begin(), piece.end());
  }
  return status;
}

// One column's samples per group (the complete runs' finite values), and each group's counts of
// runs, pending, failed and without a value in `counts`.
std::vector<std::vector<double>> SampleColumn(const ArchiveReader& archive, const RunColumn& column,
                                              const std::vector<std::int8_t>& status,
                                              const std::vector<int>& group_of,
                                              std::vector<ColumnDispersion>& counts) {
  const std::int64_t n = archive.run_count();
  std::vector<std::vector<double>> samples(counts.size());
  ColumnValues values;
  for (std::int64_t first = 0; first < n; first += kPieceRows) {
    const std::int64_t count = std::min(kPieceRows, n - first);
    ReadColumn(archive, column, first, count, values);
    for (std::int64_t k = 0; k < count; ++k) {
      const auto r = static_cast<std::size_t>(first + k);
      const auto g = static_cast<std::size_t>(group_of[r]);
      ColumnDispersion& tally = counts[g];
      ++tally.runs;
      if (status[r] == kStatusPending) {
        ++tally.pending;
      } else if (status[r] == kStatusFailed) {
        ++tally.failed;
      } else if (status[r] == kStatusOk && std::isfinite(values.numbers[static_cast<std::size_t>(k)])) {
        samples[g].push_back(values.numbers[static_cast<std::size_t>(k)]);
      } else {
        ++tally.without_value;
      }
    }
  }
  return samples;
}

// The empirical counts of group g's limits on `column`, on the unsorted sample (order does not matter).
void CountExceedances(Dispersion& d, const std::string& column, std::size_t g,
                      const std::vector<double>& sample, const ColumnDispersion& counts) {
  for (std::size_t l = 0; l < d.limits.size(); ++l) {
    if (d.limits[l].column != column) continue;
    const DispersionLimit& limit = d.limits[l];
    LimitExceedance& e = d.groups[g].limits[l];
    e.values = static_cast<std::int64_t>(sample.size());
    e.failed = counts.failed + counts.without_value;
    for (double v : sample) e.exceed += limit.above ? v > limit.value : v < limit.value;
  }
}

// The probabilities of group g's limits on `column`: empirical with its intervals, and of the fits.
void EstimateExceedances(Dispersion& d, const std::string& column, std::size_t g,
                         const ColumnDispersion& described, const DispersionOptions& options) {
  for (std::size_t l = 0; l < d.limits.size(); ++l) {
    if (d.limits[l].column != column) continue;
    const DispersionLimit& limit = d.limits[l];
    LimitExceedance& e = d.groups[g].limits[l];
    e.probability = e.values > 0 ? static_cast<double>(e.exceed) / static_cast<double>(e.values) : kNaN;
    e.wilson = WilsonInterval(e.exceed, e.values, options.confidence_level);
    e.clopper_pearson = ClopperPearsonInterval(e.exceed, e.values, options.confidence_level);
    if (limit.above) {
      e.normal_probability = NormalProbabilityAbove(described.normal.fit, limit.value);
      e.gumbel_probability = GumbelMaxProbabilityAbove(described.gumbel_max.fit, limit.value);
      e.gev_probability = GevMaxProbabilityAbove(
          {described.gev_max.fit.location, described.gev_max.fit.scale, described.gev_max.shape, 0},
          limit.value);
    } else {
      const LocationScale negated{-described.normal.fit.location, described.normal.fit.scale};
      e.normal_probability = NormalProbabilityAbove(negated, -limit.value);
      const LocationScale negated_fit{-described.gumbel_min.fit.location, described.gumbel_min.fit.scale};
      e.gumbel_probability = GumbelMaxProbabilityAbove(negated_fit, -limit.value);
      e.gev_probability = kNaN;
    }
  }
}

}  // namespace

Dispersion ComputeDispersion(const ArchiveReader& archive, const ColumnCatalog& catalog,
                             const DispersionOptions& options) {
  const std::string source = archive.path().string();
  CheckDispersionOptions(options);
  Dispersion d;
  d.archive = source;
  d.options = options;
  d.run_count = archive.run_count();
  d.study_name = archive.StringAttributeOf("/", "study_name").value_or("");
  d.design_kind = archive.StringAttributeOf("design", "kind").value_or("");
  const std::vector<int> indices = ChooseColumns(catalog, options, source, d);
  const std::vector<int> group_of = GroupRuns(archive, catalog, options, source, d);
  const std::size_t group_count = d.groups.size();

  // Statuses, then each column: its samples per group.
  const std::vector<std::int8_t> status = ReadStatuses(archive);
  for (auto& group : d.groups) group.limits.resize(d.limits.size());
  for (std::size_t c = 0; c < indices.size(); ++c) {
    const RunColumn& column = catalog.column(indices[c]);
    std::vector<ColumnDispersion> counts(group_count);
    std::vector<std::vector<double>> samples = SampleColumn(archive, column, status, group_of, counts);
    for (std::size_t g = 0; g < group_count; ++g) {
      // The limits on this column first, on the unsorted sample.
      CountExceedances(d, column.name, g, samples[g], counts[g]);
      ColumnDispersion described = Describe(samples[g], options);
      described.runs = counts[g].runs;
      described.failed = counts[g].failed;
      described.without_value = counts[g].without_value;
      described.pending = counts[g].pending;
      EstimateExceedances(d, column.name, g, described, options);
      d.groups[g].columns.push_back(std::move(described));
    }
  }
  return d;
}

std::string DispersionGroupPath() { return product::dispersion::kPath; }

namespace {

// The fields of /analysis/dispersion and of its subgroup limits (schemas/products.json).
namespace attribute = product::dispersion::attribute;
namespace dataset = product::dispersion::dataset;
namespace limits_attribute = product::dispersion::limits::attribute;
namespace limits_dataset = product::dispersion::limits::dataset;

// The product's attributes: what it is, where it comes from and the options it was computed with.
void WriteDispersionAttributes(ProductGroup& group, const Dispersion& d, const std::string& command_line) {
  group.Attribute(attribute::kDescription,
                  "Dispersion of per-run result columns over the runs of a sweep, per group of a grouping "
                  "column (docs/dispersion.md): counts, moments, percentiles, normal and Gumbel tail fits "
                  "with Anderson-Darling statistics, and limit exceedance probabilities with Wilson and "
                  "Clopper-Pearson intervals");
  WriteProvenance(group, product::dispersion::Layout(), command_line);
  group.Attribute(attribute::kStudyName, d.study_name);
  group.Attribute(attribute::kColumns, d.columns);
  group.Attribute(attribute::kColumnPaths, d.column_paths);
  group.Attribute(attribute::kColumnUnits, d.column_units);
  group.Attribute(attribute::kGroupBy, d.group_by);
  group.Attribute(attribute::kGroupPath, d.group_path);
  group.Attribute(attribute::kGroupUnits, d.group_units);
  group.Attribute(attribute::kPercentiles, d.options.percentiles);
  group.Attribute(attribute::kTailProbabilities, d.options.tail_probabilities);
  group.Attribute(attribute::kConfidenceLevel, d.options.confidence_level);
  group.Attribute(attribute::kRunCount, d.run_count);
}

// The groups' labels and grouping values, one per group.
void WriteGroupKeys(ProductGroup& group, const Dispersion& d) {
  std::vector<std::string> labels;
  std::vector<double> keys;
  for (const auto& g : d.groups) {
    labels.push_back(g.label);
    keys.push_back(g.value);
  }
  group.Strings(dataset::kGroupLabel, labels);
  group.Numbers(std::string(dataset::kGroupValue.name), keys, d.group_units.empty() ? "1" : d.group_units,
                std::string(dataset::kGroupValue.description));
}

// A per (group, column) table of `field`'s type, shape [G, C]; a <fit> and <law> in the field are
// `fit` and `law`.
template <typename T, typename ValueOf>
void WritePerColumn(ProductGroup& group, const Dispersion& d, const ProductField& field, ValueOf value_of,
                    const std::string& fit = "", const std::string& law = "") {
  std::vector<T> values;
  for (const auto& g : d.groups)
    for (const auto& c : g.columns) values.push_back(value_of(c));
  group.Numbers(Filled(field.name, "<fit>", fit), values, std::string(field.units),
                Filled(field.description, "<law>", law), {d.groups.size(), d.columns.size()});
}

// Each column's sample: its counts, moments, extremes and percentiles.
void WriteSampleTables(ProductGroup& group, const Dispersion& d) {
  const std::size_t G = d.groups.size(), C = d.columns.size(), P = d.options.percentiles.size();
  using E = const ColumnDispersion&;
  WritePerColumn<std::int64_t>(group, d, dataset::kRuns, [](E c) { return c.runs; });
  WritePerColumn<std::int64_t>(group, d, dataset::kValues, [](E c) { return c.values; });
  WritePerColumn<std::int64_t>(group, d, dataset::kFailed, [](E c) { return c.failed; });
  WritePerColumn<std::int64_t>(group, d, dataset::kWithoutValue, [](E c) { return c.without_value; });
  WritePerColumn<std::int64_t>(group, d, dataset::kPending, [](E c) { return c.pending; });
  WritePerColumn<double>(group, d, dataset::kMean, [](E c) { return c.mean; });
  WritePerColumn<double>(group, d, dataset::kStandardDeviation, [](E c) { return c.standard_deviation; });
  WritePerColumn<std::int64_t>(group, d, dataset::kNoSpread,
                               [](E c) { return static_cast<std::int64_t>(c.no_spread ? 1 : 0); });
  WritePerColumn<double>(group, d, dataset::kMinimum, [](E c) { return c.minimum; });
  WritePerColumn<double>(group, d, dataset::kMaximum, [](E c) { return c.maximum; });
  std::vector<double> percentiles;
  for (const auto& g : d.groups)
    for (const auto& c : g.columns)
      percentiles.insert(percentiles.end(), c.percentiles.begin(), c.percentiles.end());
  group.Numbers(dataset::kPercentileValues, percentiles, {G, C, P});
}

// One tail law's fits: location, scale, A2 and its rejection level, and the quantiles of the tails
// asked for (`upper`, `lower`).
template <typename TailOf>
void WriteTailFit(ProductGroup& group, const Dispersion& d, const std::string& fit, const std::string& law,
                  TailOf tail_of, bool upper, bool lower) {
  const std::size_t G = d.groups.size(), C = d.columns.size(), T = d.options.tail_probabilities.size();
  using E = const ColumnDispersion&;
  WritePerColumn<double>(
      group, d, dataset::kFitLocation, [&](E c) { return tail_of(c).fit.location; }, fit, law);
  WritePerColumn<double>(
      group, d, dataset::kFitScale, [&](E c) { return tail_of(c).fit.scale; }, fit, law);
  WritePerColumn<double>(
      group, d, dataset::kFitAndersonDarling, [&](E c) { return tail_of(c).goodness.statistic; }, fit, law);
  WritePerColumn<double>(
      group, d, dataset::kFitRejectedAtPercent,
      [&](E c) { return tail_of(c).goodness.rejected_at_percent(); }, fit, law);
  for (int side = 0; side < 2; ++side) {
    if ((side == 0 && !upper) || (side == 1 && !lower)) continue;
    std::vector<double> values;
    for (const auto& g : d.groups)
      for (const auto& c : g.columns) {
        const auto& q = side == 0 ? tail_of(c).upper_quantiles : tail_of(c).lower_quantiles;
        values.insert(values.end(), q.begin(), q.end());
      }
    const ProductField& field = side == 0 ? dataset::kFitUpperQuantiles : dataset::kFitLowerQuantiles;
    group.Numbers(Filled(field.name, "<fit>", fit), values, std::string(field.units),
                  Filled(field.description, "<law>", law), {G, C, T});
  }
}

// The tail fits: normal, Gumbel and GEV of the largest values, Gumbel of the smallest.
void WriteTailFits(ProductGroup& group, const Dispersion& d) {
  WriteTailFit(
      group, d, "normal", "Normal", [](const ColumnDispersion& c) -> const TailFit& { return c.normal; },
      true, true);
  WriteTailFit(
      group, d, "gumbel_max", "Gumbel (largest values)",
      [](const ColumnDispersion& c) -> const TailFit& { return c.gumbel_max; }, true, false);
  WriteTailFit(
      group, d, "gev_max", "Generalised extreme value (largest values; A2 without a table)",
      [](const ColumnDispersion& c) -> const TailFit& { return c.gev_max; }, true, false);
  WritePerColumn<double>(group, d, dataset::kGevMaxShape,
                         [](const ColumnDispersion& c) { return c.gev_max.shape; });
  WriteTailFit(
      group, d, "gumbel_min",
      "Gumbel of the smallest values (CDF 1 - exp(-exp((x - location)/scale)), scipy's gumbel_l)",
      [](const ColumnDispersion& c) -> const TailFit& { return c.gumbel_min; }, false, true);
}

// A per (group, limit) table of `field`'s type, shape [G, L].
template <typename T, typename ValueOf>
void WritePerLimit(ProductGroup& limits, const Dispersion& d, const ProductField& field, ValueOf value_of) {
  std::vector<T> values;
  for (const auto& g : d.groups)
    for (const auto& e : g.limits) values.push_back(value_of(e));
  limits.Numbers(field, values, {d.groups.size(), d.limits.size()});
}

// The subgroup limits: each limit as given, and per group its exceedance counts and probabilities.
void WriteLimitTables(ProductGroup& group, const Dispersion& d) {
  std::vector<std::string> texts, limit_columns;
  std::vector<double> limit_values;
  std::vector<std::int64_t> above;
  for (const auto& l : d.limits) {
    texts.push_back(l.text);
    limit_columns.push_back(l.column);
    limit_values.push_back(l.value);
    above.push_back(l.above ? 1 : 0);
  }
  ProductGroup limits = group.Group(product::dispersion::limits::kPath);
  limits.Attribute(limits_attribute::kDescription, std::string(limits_attribute::kDescription.description));
  limits.Strings(limits_dataset::kLimit, texts);
  limits.Strings(limits_dataset::kColumn, limit_columns);
  limits.Numbers(limits_dataset::kValue, limit_values);
  limits.Numbers(limits_dataset::kAbove, above);
  using E = const LimitExceedance&;
  WritePerLimit<std::int64_t>(limits, d, limits_dataset::kExceed, [](E e) { return e.exceed; });
  WritePerLimit<std::int64_t>(limits, d, limits_dataset::kValues, [](E e) { return e.values; });
  WritePerLimit<std::int64_t>(limits, d, limits_dataset::kFailed, [](E e) { return e.failed; });
  WritePerLimit<double>(limits, d, limits_dataset::kProbability, [](E e) { return e.probability; });
  WritePerLimit<double>(limits, d, limits_dataset::kWilsonLower, [](E e) { return e.wilson.lower; });
  WritePerLimit<double>(limits, d, limits_dataset::kWilsonUpper, [](E e) { return e.wilson.upper; });
  WritePerLimit<double>(limits, d, limits_dataset::kClopperPearsonLower,
                        [](E e) { return e.clopper_pearson.lower; });
  WritePerLimit<double>(limits, d, limits_dataset::kClopperPearsonUpper,
                        [](E e) { return e.clopper_pearson.upper; });
  WritePerLimit<double>(limits, d, limits_dataset::kNormalProbability,
                        [](E e) { return e.normal_probability; });
  WritePerLimit<double>(limits, d, limits_dataset::kGumbelProbability,
                        [](E e) { return e.gumbel_probability; });
  WritePerLimit<double>(limits, d, limits_dataset::kGevProbability, [](E e) { return e.gev_probability; });
}

}  // namespace

void WriteDispersionGroup(const std::filesystem::path& archive, const Dispersion& d,
                          const std::string& command_line) {
  WriteAnalysisProduct(archive, DispersionGroupPath(), "the dispersion", [&](ProductGroup& group) {
    WriteDispersionAttributes(group, d, command_line);
    WriteGroupKeys(group, d);
    // Per (group, column) tables, shape [G, C] (and [G, C, P] / [G, C, T]).
    WriteSampleTables(group, d);
    WriteTailFits(group, d);
    // The limits: [group, limit].
    WriteLimitTables(group, d);
  });
}

}  // namespace gesweep
