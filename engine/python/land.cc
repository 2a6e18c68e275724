// gesweep.land: the landing; its settings, summary, design and series.
#include "engine/python/series_dict.h"
#include "engine/python/support.h"

namespace gesweep::python {

// ---------------------------------------------------------------- land

/// gesweep.land's settings for its signature and docstring: LandingConfig's (Describe) and q_weights,
/// the one array, which each front end reads itself.
py::list LandingSettingsList() {
  const LandingConfig defaults;
  py::list out = SettingsList(defaults, {});
  py::dict q;
  q["key"] = "q_weights";
  q["unit"] = "SI";
  std::string names;
  for (auto name : LandingStateNames()) {
    if (!names.empty()) names += ", ";
    names += name;
  }
  q["doc"] = "9 LQR output weights >= 0 on " + names;
  q["default"] = py::cast(std::vector<double>(defaults.q_weights.begin(), defaults.q_weights.end()));
  out.append(q);
  return out;
}

/// q_weights: a sequence of 9 numbers.
void TakeQWeights(py::dict& options, LandingConfig& config) {
  if (!options.contains("q_weights")) return;
  py::object value = options["q_weights"];
  PyDict_DelItemString(options.ptr(), "q_weights");
  if (value.is_none()) return;
  const std::string expected = "expected a sequence of 9 weights >= 0";
  if (py::isinstance<py::str>(value) || !py::isinstance<py::sequence>(value) ||
      py::len(value) != kLandingStateCount)
    throw InputError(kArguments, "q_weights", Repr(value), expected);
  const auto weights = value.cast<py::sequence>();
  for (int i = 0; i < kLandingStateCount; ++i)
    config.q_weights[static_cast<std::size_t>(i)] =
        ToNumber(weights[static_cast<std::size_t>(i)], "q_weights." + std::string(LandingStateNames()[i]));
}

py::tuple Land(const PyAircraft& aircraft, const py::object& summary_only_arg, const py::kwargs& kwargs) {
  py::dict options = kwargs;
  const auto model = ModelOf(aircraft, options);
  const bool summary_only = ToBool(summary_only_arg, "summary_only");
  LandingConfig config;
  std::vector<std::string> keys;
  KwargsReader reader{&options, &keys};
  config.Describe(reader);
  TakeQWeights(options, config);
  keys.push_back("q_weights");
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
