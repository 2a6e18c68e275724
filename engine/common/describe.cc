#include "engine/common/describe.h"

#include "engine/common/input_limits.h"

namespace gesweep {

std::string FieldNumberText(double value) { return ShortNumber(value); }

std::string ComponentKey(const FieldAttributes& attributes, std::size_t c) {
  GESWEEP_DEMAND(c < attributes.components.size());
  return std::string(attributes.key) + "." + std::string(attributes.components[c].name);
}

void CheckFieldLimit(const FieldAttributes& attributes, double struct_value, const std::string& source) {
  CheckInputLimit(attributes.limit, struct_value / attributes.scale, source, std::string(attributes.key));
}

}  // namespace gesweep
