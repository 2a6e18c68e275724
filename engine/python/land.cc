// gesweep.land: the landing; its settings, summary, design and series.
#include "engine/python/series_dict.h"
#include "engine/python/support.h"

namespace gesweep::python {

// ---------------------------------------------------------------- land

py::tuple Land(const PyAircraft& aircraft, const py::object& summary_only_arg, const py::kwargs& kwargs) {
  py::dict options = kwargs;
  const auto model = ModelOf(aircraft, options);
  const bool summary_only = ToBool(summary_only_arg, "summary_only");
  LandingConfig config;
  std::vector<std::string> keys;
  KwargsReader reader{&options, &keys};
  config.Describe(reader);
  keys.insert(keys.end(), ModelOptionKeys().begin(), ModelOptionKeys().end());
  RefuseLeftovers(options, keys);
  if (summary_only) config.output_interval_s = 0.0;
  ValidateLandingConfig(config, model->aircraft(), kArguments);
  const double time_limit_s = LandingTimeLimit(config, model->aircraft().wheel_contact_height_m);
  if (config.output_interval_s > 0.0 && time_limit_s / config.output_interval_s > 1e7) {
    throw InputError(kArguments, "output_interval_s", ShortNumber(config.output_interval_s),
                     "expected at most 1e7 samples");
  }
  LandingResult r;
  RunInterruptible([&](const std::atomic<bool>* cancel) { r = SimulateLanding(*model, config, cancel); });
  py::dict summary = FieldsDict(r);
  summary["design"] = RecordDict([&](auto& sink) { DesignRecord(r.design, sink); });
  py::object series = py::none();
  if (!summary_only) series = SeriesDict(r.series, LandingSeriesContents(config));
  return py::make_tuple(RecordDict([&](auto& sink) { LandingRunRecord(config, r, *model, sink); }), summary,
                        series);
}

}  // namespace gesweep::python
