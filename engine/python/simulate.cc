// gesweep.simulate: the open-loop response; its settings and summary from their descriptions.
#include "engine/python/series_dict.h"
#include "engine/python/support.h"

namespace gesweep::python {

// ---------------------------------------------------------------- simulate

py::tuple Simulate(const PyAircraft& aircraft, const py::object& height_m, const py::object& speed_mps,
                   const py::object& summary_only_arg, const py::object& output_dt_arg,
                   const py::kwargs& kwargs) {
  py::dict options = kwargs;
  const auto model = ModelOf(aircraft, options);
  const bool summary_only = ToBool(summary_only_arg, "summary_only");
  std::optional<double> output_dt_s;
  if (!output_dt_arg.is_none()) output_dt_s = ToNumber(output_dt_arg, "output_dt_s");
  OpenLoopConfig config;
  config.start_height_m = ToNumber(height_m, "height_m");
  config.reference_speed_mps = ToNumber(speed_mps, "speed_mps");
  std::vector<std::string> keys;
  KwargsReader reader{&options, &keys};
  config.Describe(reader);
  // The turbulence is RunNoise(seed, run_index), as `gesweep simulate --seed --run-index`.
  for (auto [key, target] : {std::pair{"seed", &config.seed}, std::pair{"run_index", &config.run_index}}) {
    if (!options.contains(key)) continue;
    *target = ToCount<std::uint64_t>(options[key], key, key);
    PyDict_DelItemString(options.ptr(), key);
  }
  keys.insert(keys.end(), ModelOptionKeys().begin(), ModelOptionKeys().end());
  RefuseLeftovers(options, keys);
  if (!summary_only) {
    const double output_dt = output_dt_s ? *output_dt_s : config.integrator.step_s;
    if (output_dt_s) CheckInputLimit("output_dt_s", output_dt, kArguments, "output_dt_s");
    if (config.duration_s / output_dt > 1e7)
      throw InputError(kArguments, "output_dt_s", ShortNumber(output_dt), "expected at most 1e7 samples");
    config.series_interval_s = output_dt;
  }
  try {
    ValidateOpenLoopConfig(*model, config, kArguments);
  } catch (const InputError& e) {
    if (e.key() == "series_interval_s") throw InputError(kArguments, "output_dt_s", e.value(), e.expected());
    throw;
  }
  OpenLoopResult result;
  RunInterruptible(
      [&](const std::atomic<bool>* cancel) { result = SimulateOpenLoop(*model, config, cancel); });
  const py::dict run = RecordDict([&](auto& sink) { OpenLoopRunRecord(config, *model, sink); });
  py::object series = py::none();
  if (!summary_only) series = SeriesDict(result.series, result.series.contents());
  return py::make_tuple(run, FieldsDict(result.summary), series);
}

}  // namespace gesweep::python
