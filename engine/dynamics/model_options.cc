#include "engine/dynamics/model_options.h"

namespace gesweep {

std::string_view ToString(CdhMode mode) { return mode == CdhMode::kPolar ? "polar" : "zero"; }

std::string_view ToString(Interpolation interpolation) {
  return interpolation == Interpolation::kLinear ? "linear" : "pchip";
}

std::optional<CdhMode> ParseCdhMode(std::string_view text) {
  if (text == "polar") return CdhMode::kPolar;
  if (text == "zero") return CdhMode::kZero;
  return std::nullopt;
}

std::optional<Interpolation> ParseInterpolation(std::string_view text) {
  if (text == "linear") return Interpolation::kLinear;
  if (text == "pchip") return Interpolation::kPchip;
  return std::nullopt;
}

}  // namespace gesweep
