// gesweep.simulate: the open-loop response; its settings and summary from their descriptions.
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
  py::dict run = FieldsDict(config);
  run["aircraft"] = model->aircraft().name;
  run["h_derivatives"] = model->options().h_derivatives;
  run["cdh"] = std::string(ToString(model->options().cdh));
  run["interpolation"] = std::string(ToString(model->options().interpolation));
  run["seed"] = config.seed;
  run["run_index"] = config.run_index;
  py::object series = py::none();
  if (!summary_only) {
    const OpenLoopSeries& s = result.series;
    py::dict columns;
    columns["time_s"] = Array(s.time_s);
    columns["delta_speed_mps"] = Array(s.delta_speed_mps);
    columns["delta_normal_velocity_mps"] = Array(s.delta_normal_velocity_mps);
    columns["pitch_rate_radps"] = Array(s.pitch_rate_radps);
    columns["delta_pitch_rad"] = Array(s.delta_pitch_rad);
    columns["delta_height_m"] = Array(s.delta_height_m);
    columns["height_m"] = Array(s.height_m);
    columns["speed_mps"] = Array(s.speed_mps);
    columns["elevator_rad"] = Array(s.elevator_rad);
    if (!s.u_g_mps.empty()) {  // the air motion met, as the CSV has it: only with a disturbance
      columns["u_g_mps"] = Array(s.u_g_mps);
      columns["w_g_mps"] = Array(s.w_g_mps);
    }
    if (!s.q_g_radps.empty()) columns["q_g_radps"] = Array(s.q_g_radps);
    series = columns;
  }
  return py::make_tuple(run, FieldsDict(result.summary), series);
}

}  // namespace gesweep::python
