#include "engine/dynamics/model_options.h"

namespace gesweep {

std::optional<CdhMode> ParseCdhMode(std::string_view text) { return ParseEnum<CdhMode>(text); }

std::optional<Interpolation> ParseInterpolation(std::string_view text) {
  return ParseEnum<Interpolation>(text);
}

}  // namespace gesweep
