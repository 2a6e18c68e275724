#include "engine/common/describe.h"

#include "engine/common/input_limits.h"

namespace gesweep {

std::string FieldNumberText(double value) { return ShortNumber(value); }

void CheckFieldLimit(const FieldAttributes& attributes, double struct_value, const std::string& source) {
  CheckInputLimit(attributes.limit, struct_value / attributes.scale, source, std::string(attributes.key));
}

}  // namespace gesweep
