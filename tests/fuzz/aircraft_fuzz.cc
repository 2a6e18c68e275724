// Fuzz target: the aircraft loader, then the model and one eigen-analysis and boundary search on
// whatever loads. Anything but InputError escaping is a defect.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "engine/aircraft/aircraft.h"
#include "engine/common/errors.h"
#include "engine/modal/boundary.h"
#include "engine/modal/modal_analysis.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    gesweep::Aircraft aircraft = gesweep::ParseAircraft(text, "fuzz.toml");
    const gesweep::LongitudinalModel model(std::move(aircraft), gesweep::ModelOptions{});
    const double speed = model.aircraft().stall_speed_mps * 1.3;
    gesweep::AnalyzeModes(model.StateMatrix(model.aircraft().wheel_contact_height_m, speed));
    gesweep::BoundaryOptions options;
    options.samples_per_segment = 2;
    gesweep::FindBoundary(model, speed, options);
  } catch (const gesweep::InputError&) {
  }
  return 0;
}
