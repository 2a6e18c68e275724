#include "engine/estimators/sensitivity_common.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "engine/common/errors.h"

namespace gesweep {

double ValueAtUnit(double lower, double upper, bool log_uniform, double u) {
  if (log_uniform) {
    const double log_lower = std::log(lower);
    return std::exp(log_lower + u * (std::log(upper) - log_lower));
  }
  return lower + u * (upper - lower);
}

double UnitOfValue(double lower, double upper, bool log_uniform, double value) {
  if (log_uniform) {
    const double log_lower = std::log(lower);
    return (std::log(value) - log_lower) / (std::log(upper) - log_lower);
  }
  return (value - lower) / (upper - lower);
}

void ValidateRanges(const std::vector<ParameterRange>& ranges, const std::string& source) {
  if (ranges.empty()) throw InputError(source, "parameters", "", "expected at least one sampled parameter");
  std::set<std::string> names;
  for (const auto& range : ranges) {
    if (range.name.empty())
      throw InputError(source, "parameters", "''", "expected a non-empty parameter name");
    if (!names.insert(range.name).second) {
      throw InputError(source, range.name, "", "parameter listed twice; expected distinct names");
    }
    if (!std::isfinite(range.lower) || !std::isfinite(range.upper) || !(range.lower < range.upper)) {
      throw InputError(source, range.name,
                       "[" + ShortNumber(range.lower) + ", " + ShortNumber(range.upper) + "]",
                       "expected finite bounds with lower < upper");
    }
    if (range.log_uniform && !(range.lower > 0.0)) {
      throw InputError(source, range.name,
                       "[" + ShortNumber(range.lower) + ", " + ShortNumber(range.upper) + "]",
                       "expected 0 < lower for a log-uniform parameter");
    }
  }
}

ConfidenceInterval PercentileInterval(std::vector<double> statistics, double confidence_level) {
  GESWEEP_DEMAND(confidence_level > 0.0 && confidence_level < 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::erase_if(statistics, [](double v) { return !std::isfinite(v); });
  if (statistics.size() < 2) return {nan, nan};
  std::sort(statistics.begin(), statistics.end());
  auto quantile = [&statistics](double q) {
    // Type 7: position q·(n−1) in the sorted sample, linear between neighbours.
    const double position = q * static_cast<double>(statistics.size() - 1);
    const auto below = static_cast<std::size_t>(std::floor(position));
    const std::size_t above = std::min(below + 1, statistics.size() - 1);
    const double fraction = position - static_cast<double>(below);
    return statistics[below] + fraction * (statistics[above] - statistics[below]);
  };
  const double tail = 0.5 * (1.0 - confidence_level);
  return {quantile(tail), quantile(1.0 - tail)};
}

void ValidateBootstrapOptions(const BootstrapOptions& options, const std::string& source) {
  if (options.resamples < 0) {
    throw InputError(source, "bootstrap", std::to_string(options.resamples),
                     "expected a number of resamples >= 0 (0: no confidence intervals)");
  }
  if (!(options.confidence_level > 0.0 && options.confidence_level < 1.0)) {
    throw InputError(source, "confidence_level", ShortNumber(options.confidence_level),
                     "expected a level strictly between 0 and 1, e.g. 0.95");
  }
}

std::vector<bool> FailedRows(std::span<const double> outputs, const std::vector<bool>& succeeded) {
  GESWEEP_DEMAND(succeeded.empty() || succeeded.size() == outputs.size());
  std::vector<bool> failed(outputs.size());
  for (std::size_t r = 0; r < outputs.size(); ++r) {
    failed[r] = !std::isfinite(outputs[r]) || (!succeeded.empty() && !succeeded[r]);
  }
  return failed;
}

}  // namespace gesweep
