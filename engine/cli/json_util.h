#pragma once
/// JSON helpers for the CLI: non-finite numbers become null (JSON has no NaN), +∞ heights "inf".

#include <cmath>
#include <nlohmann/json.hpp>

namespace gesweep::cli {

/// A number, or null when it is not finite.
inline nlohmann::json JsonNumber(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

/// Declares `to_json` for a struct whose JSON object is its members under their own names (in the
/// struct's namespace, so that nlohmann::json finds it): GESWEEP_JSON_MEMBERS(InputLimit, name, units).
/// Non-finite numbers are written as null, as JsonNumber's. The output-only half of nlohmann's
/// NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE (whose from_json cannot read a std::string_view member).
#define GESWEEP_JSON_MEMBERS(Type, ...)                                               \
  inline void to_json(nlohmann::json& nlohmann_json_j, const Type& nlohmann_json_t) { \
    NLOHMANN_JSON_EXPAND(NLOHMANN_JSON_PASTE(NLOHMANN_JSON_TO, __VA_ARGS__))          \
  }

/// A height: a number, or the string "inf" for free flight.
inline nlohmann::json JsonHeight(double height_m) {
  return std::isinf(height_m) ? nlohmann::json("inf") : nlohmann::json(height_m);
}

}  // namespace gesweep::cli
