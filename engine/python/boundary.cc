// gesweep.boundary: the boundary H* at one speed, the record of engine/analyses/records.h as a dict.
#include "engine/python/support.h"

namespace gesweep::python {

// ---------------------------------------------------------------- boundary

py::dict Boundary(const PyAircraft& aircraft, const py::object& speed_arg, const py::object& method_arg,
                  const py::object& sensitivities_arg, const py::kwargs& kwargs) {
  const double speed_mps = ToNumber(speed_arg, "speed_mps");
  const std::string method = ToText(method_arg, "method");
  const bool sensitivities = ToBool(sensitivities_arg, "sensitivities");
  py::dict options_in = kwargs;
  const auto model = ModelOf(aircraft, options_in);
  RefuseLeftovers(options_in, ModelOptionKeys());
  CheckInputLimit("speed_mps", speed_mps, kArguments, "speed_mps");
  BoundaryOptions options;
  if (method == "sampled") {
    options.method = BoundaryMethod::kSampled;
  } else if (method != "hurwitz") {
    throw InputError(kArguments, "method", "'" + method + "'", "expected hurwitz or sampled");
  }
  BoundaryResult result;
  std::optional<BoundarySensitivities> s;
  {
    py::gil_scoped_release release;
    result = FindBoundary(*model, speed_mps, options);
    if (sensitivities) s = ComputeBoundarySensitivities(*model, result);
  }
  return RecordDict(
      [&](auto& sink) { BoundaryRecord(speed_mps, result, model->aircraft().wingspan_m, s, sink); });
}

}  // namespace gesweep::python
