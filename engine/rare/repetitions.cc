#include "engine/rare/repetitions.h"

#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <limits>

#include "engine/common/errors.h"

namespace gesweep::rare {

double StudentT975(int degrees_of_freedom) {
  GESWEEP_DEMAND(degrees_of_freedom >= 1);
  const boost::math::students_t t(static_cast<double>(degrees_of_freedom));
  return boost::math::quantile(t, 0.975);
}

PooledEstimate PoolRepetitions(std::span<const SubsetResult> runs) {
  GESWEEP_DEMAND(!runs.empty());
  PooledEstimate pooled;
  pooled.repetitions = static_cast<int>(runs.size());
  double sum = 0, stated = 0;
  for (const SubsetResult& run : runs) {
    if (static_cast<int>(run.status) > static_cast<int>(pooled.status)) pooled.status = run.status;
    if (run.status == SubsetResult::Status::kLevelCap)
      pooled.upper_bound = std::max(pooled.upper_bound, run.upper_bound);
    sum += run.probability;
    stated += run.coefficient_of_variation;
    pooled.evaluations += run.evaluations;
    pooled.failed_evaluations += run.failed_evaluations;
  }
  const double k = static_cast<double>(runs.size());
  pooled.mean_stated_coefficient_of_variation = stated / k;
  if (runs.size() == 1) {
    const SubsetResult& run = runs.front();
    pooled.probability = run.probability;
    pooled.coefficient_of_variation = run.coefficient_of_variation;
    pooled.measured_coefficient_of_variation_one_run = std::numeric_limits<double>::quiet_NaN();
    pooled.interval_95_low = run.interval_95_low;
    pooled.interval_95_high = run.interval_95_high;
    return pooled;
  }
  const double mean = sum / k;
  double squares = 0;
  for (const SubsetResult& run : runs) squares += (run.probability - mean) * (run.probability - mean);
  const double sd = std::sqrt(squares / (k - 1));
  pooled.probability = mean;
  pooled.measured_coefficient_of_variation_one_run =
      mean > 0 ? sd / mean : std::numeric_limits<double>::quiet_NaN();
  pooled.coefficient_of_variation = pooled.measured_coefficient_of_variation_one_run / std::sqrt(k);
  if (!(mean > 0) || !std::isfinite(pooled.coefficient_of_variation)) {
    pooled.interval_95_low = 0;
    pooled.interval_95_high = mean > 0 ? std::numeric_limits<double>::infinity() : 0;
    return pooled;
  }
  const double c = pooled.coefficient_of_variation;
  const double s2 = std::log1p(c * c);
  const double s = std::sqrt(s2);
  const double t = StudentT975(pooled.repetitions - 1);
  const double mean_log = std::log(mean) - s2 / 2;
  pooled.interval_95_low = std::exp(mean_log - t * s);
  pooled.interval_95_high = std::exp(mean_log + t * s);
  return pooled;
}

}  // namespace gesweep::rare
