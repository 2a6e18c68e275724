#include "engine/aircraft/coefficient.h"

namespace gesweep {

std::optional<Coefficient> CoefficientFromName(std::string_view name) {
  for (int i = 0; i < kCoefficientCount; ++i) {
    if (kCoefficientNames[i] == name) return static_cast<Coefficient>(i);
  }
  return std::nullopt;
}

}  // namespace gesweep
