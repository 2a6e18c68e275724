#include "engine/simulation/integrator.h"

#include <cmath>

#include "engine/common/errors.h"

namespace gesweep {

namespace {

std::string Text(double value) { return ShortNumber(value); }

}  // namespace

void ValidateIntegratorOptions(const IntegratorOptions& options, const std::string& source) {
  auto require = [&source](bool ok, const char* key, double value, const char* expected) {
    if (!ok) throw InputError(source, key, Text(value), expected);
  };
  require(options.step_s > 0.0 && std::isfinite(options.step_s), "step_s", options.step_s,
          "expected a finite step > 0 s");
  require(options.relative_tolerance > 0.0 && options.relative_tolerance < 1.0, "relative_tolerance",
          options.relative_tolerance, "expected a relative tolerance in (0, 1)");
  require(options.absolute_tolerance > 0.0 && std::isfinite(options.absolute_tolerance), "absolute_tolerance",
          options.absolute_tolerance, "expected a finite absolute tolerance > 0");
  require(options.max_step_s >= 0.0 && std::isfinite(options.max_step_s), "max_step_s", options.max_step_s,
          "expected a finite largest step >= 0 s (0: no limit)");
  require(options.output_interval_s >= 0.0 && std::isfinite(options.output_interval_s), "output_interval_s",
          options.output_interval_s, "expected a finite output interval >= 0 s (0: no output)");
  require(options.event_time_tolerance_s > 0.0 && options.event_time_tolerance_s <= 1e-6,
          "event_time_tolerance_s", options.event_time_tolerance_s, "expected a tolerance in (0, 1e-6] s");
}

}  // namespace gesweep
